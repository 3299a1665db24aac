"""The rig model with one effect added, compared with recorded runs (``compare --add``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from hybridtable.diagnosis.effects import RigScale
from hybridtable.diagnosis.fit import fit_effect
from hybridtable.diagnosis.registry import build_spec, parse_effect_spec
from hybridtable.measurement.comparison import RunComparison, compare_run
from hybridtable.measurement.run_format import Run

__all__ = ["compare_with_effect"]


def compare_with_effect(
    runs: Sequence[Run],
    text: str,
    max_lag_s: float | None,
    notify: Callable[[str], None] | None = None,
) -> tuple[list[RunComparison], dict[str, Any]]:
    """Compare ``runs`` with the model plus the effect of ``text``
    (``EFFECT[:param=value,...]``; parameters not given are fitted to the runs).

    Parameters
    ----------
    runs : sequence of Run
        Recorded runs of one rig.
    text : str
        The effect and the values given, e.g. ``"contact_damping:damping_n_s_per_m=400"``.
    max_lag_s : float or None
        Longest lag of the whiteness tests, s (None: 50 ticks).
    notify : callable, optional
        Told, in words, what is being fitted before a fit starts.

    Returns
    -------
    comparisons : list of RunComparison
        One per run, with the effect.
    added : dict
        ``effect`` (name), ``parameters`` (values in SI units), ``units``, and
        ``fitted`` (the names fitted rather than given).
    """
    effect, given = parse_effect_spec(text)
    scale = RigScale.from_runs(runs)
    values = effect.check_values(given, scale)
    fitted = [p for p in effect.parameter_names if p not in given]
    if fitted:
        if notify is not None:
            notify(f"fitting {', '.join(fitted)} of {effect.name} to the runs...")
        values = fit_effect(runs, effect.name, given)
    spec = build_spec([(effect, values)], scale)
    physics = spec.physics(name=effect.name)
    comparisons = [compare_run(spec.closed_loop_run(r), physics, max_lag_s=max_lag_s) for r in runs]
    return comparisons, {
        "effect": effect.name,
        "parameters": dict(values),
        "units": {p.name: p.unit for p in effect.parameters},
        "fitted": fitted,
    }
