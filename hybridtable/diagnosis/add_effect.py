"""The rig model with effects added, compared with recorded runs (``compare --add``,
``compare --model``).

:func:`model_with_effects` builds a :class:`~hybridtable.effects.model_file.RigModel`
from effects given on the command line (``EFFECT[:param=value,...]``, several
at once), on top of a model file's effects if one is given: the values given
are held, the others fitted jointly to the runs, with their standard errors.
:func:`compare_with_model` compares the runs with a model like the nominal one.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from hybridtable.diagnosis.fit import fit_given
from hybridtable.effects.effect import Effect
from hybridtable.effects.model_file import FittedEffect, RigModel
from hybridtable.effects.spec import RigScale
from hybridtable.errors import ParameterError
from hybridtable.measurement.comparison import RunComparison, compare_run, pool_noise_floors
from hybridtable.measurement.run_format import Run

__all__ = ["model_with_effects", "compare_with_model", "added_json"]


def model_with_effects(
    runs: Sequence[Run],
    added: Sequence[tuple[Effect, dict[str, float]]],
    base: RigModel | None = None,
    notify: Callable[[str], None] | None = None,
    source: str = "compare --add",
) -> RigModel:
    """The model of ``runs``' rig: ``base``'s effects (held at their values)
    plus ``added`` (values given held, the others fitted to ``runs``).

    Parameters
    ----------
    runs : sequence of Run
        Recorded runs of one rig.
    added : sequence of (Effect, dict)
        Effects and the values given (SI units), e.g. from
        :func:`~hybridtable.effects.registry.parse_effect_specs`.
    base : RigModel, optional
        A model whose effects and rig computer are kept.
    notify : callable, optional
        Told, in words, what is being fitted before a fit starts.

    Raises
    ------
    ParameterError
        For a value out of bounds, or an added effect that changes what one
        of ``base``'s effects changes.
    """
    kept = list(base.effects) if base is not None else []
    for e, _ in added:
        for k in kept:
            if e.name == k.name or e.conflicts_with(k.effect):
                raise ParameterError(
                    f"--add {e.name}: the model already has {k.name}, which changes "
                    f"{', '.join(k.effect.touches)}"
                )
    scale = RigScale.from_runs(runs)
    free = {e.name: [p for p in e.parameter_names if p not in v] for e, v in added}
    given = [(k.effect, dict(k.values)) for k in kept] + [(e, dict(v)) for e, v in added]
    if any(free.values()):
        if notify is not None:
            names = ", ".join(f"{p} of {n}" for n, ps in free.items() for p in ps)
            notify(f"fitting {names} to the runs...")
        values, std = fit_given(runs, given)
    else:
        values = {e.name: e.check_values(v, scale) for e, v in given}
        std = {e.name: dict.fromkeys(values[e.name]) for e, _ in given}
    effects = kept + [
        FittedEffect(e.name, values[e.name], std[e.name], tuple(free[e.name])) for e, _ in added
    ]
    computer = {r.run_id: base.computer_for(r.run_id) for r in runs} if base is not None else {}
    return RigModel.from_runs(runs, effects, computer, source=source)


def compare_with_model(
    runs: Sequence[Run], model: RigModel, max_lag_s: float | None
) -> list[RunComparison]:
    """Compare ``runs`` with ``model`` (replay and closed loop, errors in noise
    units), like :func:`~hybridtable.measurement.comparison.compare_run` the
    nominal model."""
    comparisons = [
        compare_run(
            model.closed_loop_run(r),
            model.physics(r.run_id, name="+".join(model.effect_names) or "nominal"),
            max_lag_s=max_lag_s,
        )
        for r in runs
    ]
    pool_noise_floors(comparisons)
    return comparisons


def added_json(model: RigModel, names: Sequence[str]) -> list[dict[str, Any]]:
    """The effects ``names`` of ``model`` for a command's JSON: ``effect``,
    ``parameters`` (SI units), ``std``, ``units`` and ``fitted``."""
    out = []
    for e in model.effects:
        if e.name in names:
            out.append(
                {
                    "effect": e.name,
                    "parameters": dict(e.values),
                    "std": dict(e.std),
                    "units": {p.name: p.unit for p in e.effect.parameters},
                    "fitted": list(e.fitted),
                }
            )
    return out
