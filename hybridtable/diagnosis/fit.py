"""Least-squares fits of effects to the prewhitened residuals, BIC and the
leave-one-run-out check.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from hybridtable.diagnosis.evaluate import Evaluation, Evaluator, RunData, prepare_runs
from hybridtable.diagnosis.settings import CHANNELS, FIT_ACCURACY
from hybridtable.effects import selection
from hybridtable.effects.effect import Effect
from hybridtable.effects.fitting import (
    REPLAY_LEAST_SQUARES,
    Coordinates,
    fit_values,
    standard_errors,
)
from hybridtable.effects.registry import build_spec, get_effect
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError
from hybridtable.measurement.run_format import Run

__all__ = [
    "Fit",
    "fit_effects",
    "fit_effect",
    "fit_given",
    "parameter_std",
    "delta_bic",
    "pooled_error",
    "HeldOut",
    "heldout",
    "model_spec",
    "residual_probe",
]


# -- fitting -------------------------------------------------------------------
@dataclass
class Fit:
    """A model (effects with values) fitted to runs ``indices``."""

    effects: list[str]
    values: dict[str, dict[str, float]]
    stage: str
    indices: list[int]
    evaluations: dict[int, Evaluation]
    n_parameters: int
    nfev: int = 0
    success: bool = True

    def rss_blocks(self) -> dict[tuple[int, str], float]:
        return {(i, c): v for i, ev in self.evaluations.items() for c, v in ev.rss().items()}

    @property
    def failed(self) -> bool:
        return any(ev.failed for ev in self.evaluations.values())

    def spec(self, scale: RigScale) -> ModelSpec:
        return build_spec([(get_effect(n), self.values[n]) for n in self.effects], scale)


def model_spec(
    names: Sequence[str], values: Mapping[str, Mapping[str, float]], scale: RigScale
) -> ModelSpec:
    """The model with the effects ``names`` at ``values`` (effect -> parameter -> value, SI units)."""
    return build_spec([(get_effect(n), values[n]) for n in names], scale)


def _key(values: Mapping[str, Mapping[str, float]]) -> tuple:
    return tuple((n, tuple(v.items())) for n, v in values.items())


def _space(
    ev: Evaluator,
    names: Sequence[str],
    origin: Mapping[str, Mapping[str, float]],
    fixed: Mapping[str, Mapping[str, float]],
) -> Coordinates:
    free = tuple(
        (n, p) for n in names for p in get_effect(n).parameters if p.name not in fixed.get(n, {})
    )
    return Coordinates(free, ev.scale, origin)


def _residual(ev: Evaluator, names, indices, stage, memo: dict):
    """Values -> the runs' whitened residuals, the evaluations kept in ``memo``."""

    def residual(values) -> np.ndarray:
        key = _key(values)
        if key not in memo:
            spec = model_spec(names, values, ev.scale)
            memo[key] = {i: ev.evaluate(spec, i, stage) for i in indices}
        return np.concatenate([w for i in indices for w in memo[key][i].whitened.values()])

    return residual


def fit_effects(
    ev: Evaluator,
    names: Sequence[str],
    start: Mapping[str, Mapping[str, float]] | None = None,
    indices: Sequence[int] | None = None,
    fixed: Mapping[str, Mapping[str, float]] | None = None,
    starts: Sequence[Mapping[str, Mapping[str, float]]] = (),
    stage: str = "replay",
    max_nfev: int = 20,
) -> Fit:
    """Fit the effects ``names`` jointly to the runs ``indices``
    (:func:`~hybridtable.effects.fitting.fit_values` from the best start).

    Parameters
    ----------
    start : mapping effect -> {param: value}, optional
        Start values (default: each effect's start).
    fixed : mapping effect -> {param: value}, optional
        Parameters held at these values.
    starts : sequence of mappings
        Further starting points (partial: missing values from ``start``);
        the fit starts from the one with the least whitened squared error.
    """
    indices = list(range(len(ev.data))) if indices is None else list(indices)
    fixed = {k: dict(v) for k, v in (fixed or {}).items()}
    origin = {n: get_effect(n).start(ev.scale) for n in names}
    for n, vals in (start or {}).items():
        if n in origin:
            origin[n].update(vals)
    for n, vals in fixed.items():
        origin[n].update(vals)
    space = _space(ev, names, origin, fixed)
    memo: dict = {}
    sol = fit_values(
        _residual(ev, names, indices, stage, memo),
        space,
        starts,
        replace(REPLAY_LEAST_SQUARES, max_nfev=max_nfev),
        held=fixed,
    )
    evs = memo[_key(sol.values)]
    return Fit(list(names), sol.values, stage, indices, evs, len(space.free), sol.nfev, sol.success)


# -- criteria ------------------------------------------------------------------
def delta_bic(before: Fit, after: Fit) -> float:
    """:func:`~hybridtable.effects.selection.delta_bic` of the whitened replay
    blocks (run x channel), each block's variance estimated, not below its
    numerical floor (:attr:`~hybridtable.diagnosis.evaluate.Evaluation.floor`)."""

    def blocks(fit: Fit, keys) -> list[selection.Block]:
        rss = fit.rss_blocks()
        return [
            selection.Block(
                rss[i, c], len(fit.evaluations[i].whitened[c]), fit.evaluations[i].floor.get(c, 0.0)
            )
            for i, c in keys
        ]

    keys = list(before.rss_blocks())
    dp = after.n_parameters - before.n_parameters
    return selection.delta_bic(blocks(before, keys), blocks(after, keys), dp, stated=False)


def pooled_error(
    data: Sequence[RunData], evaluations: Mapping[int, Evaluation]
) -> tuple[float, dict[str, float]]:
    """RMS residual in noise units over the runs and replay channels, and the
    RMS error per channel in the channel's unit."""
    sq = 0.0
    n = 0
    per: dict[str, list[float]] = {c: [] for c in CHANNELS}
    for i, ev in evaluations.items():
        for c in CHANNELS:
            e = ev.residual[c]
            sq += float(np.sum((e / data[i].noise[c].sigma) ** 2))
            n += len(e)
            per[c].append(float(np.mean(e * e)))
    return math.sqrt(sq / n), {c: math.sqrt(float(np.mean(v))) for c, v in per.items()}


@dataclass
class HeldOut:
    """Leave-one-run-out result of a model against a base model."""

    z: float
    error: float
    folds: list[dict[str, float]]


def heldout(
    ev: Evaluator,
    base: Mapping[int, Evaluation],
    names: Sequence[str],
    start: Mapping[str, Mapping[str, float]],
    stage: str,
    fixed: Mapping[str, Mapping[str, float]] | None = None,
) -> HeldOut:
    n = len(ev.data)
    if n < 2:
        return HeldOut(math.nan, math.nan, [])
    num = den = 0.0
    sq, count = 0.0, 0
    folds = []
    for k in range(n):
        train = [i for i in range(n) if i != k]
        fit = fit_effects(
            ev, names, start=start, indices=train, fixed=fixed, stage=stage, max_nfev=8
        )
        spec = model_spec(names, fit.values, ev.scale)
        held = ev.evaluate(spec, k, stage)
        b = base[k]
        d_sse = dy2 = 0.0
        for c, w0 in b.whitened.items():
            s2 = max(float(w0 @ w0) / len(w0), 1.0)
            w1 = held.whitened[c]
            d_sse += (float(w0 @ w0) - float(w1 @ w1)) / s2
            dw = w1 - w0
            dy2 += float(dw @ dw) / s2
        num += d_sse
        den += dy2
        if stage == "replay":
            for c in CHANNELS:
                e = held.residual[c] / ev.data[k].noise[c].sigma
                sq += float(e @ e)
                count += len(e)
        folds.append(
            {
                "run_id": ev.data[k].run_id,
                "delta_sse": d_sse,
                "prediction_change": math.sqrt(dy2),
                "values": fit.values,
            }
        )
    z = num / (2.0 * math.sqrt(den)) if den > 0.0 else 0.0
    error = math.sqrt(sq / count) if count else math.nan
    return HeldOut(z, error, folds)


def fit_effect(
    runs: Sequence[Run],
    name: str,
    given: Mapping[str, float] | None = None,
    accuracy: float = FIT_ACCURACY,
) -> dict[str, float]:
    """Values of effect ``name`` fitted to ``runs`` (the ``given`` ones held):
    :func:`fit_given` for one effect, without standard errors."""
    values, _ = fit_given(runs, [(get_effect(name), dict(given or {}))], accuracy, False)
    return values[name]


def fit_given(
    runs: Sequence[Run],
    given: Sequence[tuple[Effect, Mapping[str, float]]],
    accuracy: float = FIT_ACCURACY,
    uncertainty: bool = True,
) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, float | None]]]:
    """Fit the effects of ``given`` jointly to ``runs``, their given values held.

    Returns the values (effect -> parameter -> value, SI units) and their
    standard errors (:func:`parameter_std`; ``None`` for a value given, or
    for every value when ``uncertainty`` is false). A closed-loop effect
    (``mass_error``) is fitted on the closed loop's ``v_des``; it cannot be
    fitted together with another effect's free parameters.

    Raises
    ------
    ParameterError
        For a value out of bounds, or a closed-loop effect with free
        parameters combined with other effects.
    """
    data = prepare_runs(runs)
    scale = RigScale.from_runs(runs)
    names = [e.name for e, _ in given]
    fixed = {}
    for e, v in given:
        checked = e.check_values(v, scale)
        fixed[e.name] = {k: checked[k] for k in v}
    free = {
        e.name for e in (e for e, _ in given) for p in e.parameters if p.name not in fixed[e.name]
    }
    closed = [e.name for e, _ in given if e.stage == "closed_loop"]
    ev = Evaluator(data, scale, accuracy)
    if closed and len(given) > 1 and free:
        raise ParameterError(
            f"{closed[0]} is seen in the closed loop only: fit it alone, or give every "
            "parameter of the other effects"
        )
    stage = "closed_loop" if closed else "replay"
    if stage == "closed_loop":
        ev.inject_noise(fit_effects(ev, []).evaluations)
        ev.calibrate_closed_loop(fit_effects(ev, [], stage="closed_loop").evaluations)
        fit = fit_effects(ev, names, fixed=fixed, stage=stage)
    else:
        starts: list = []
        if free:
            residuals = residual_probe(data, fit_effects(ev, []).evaluations)
            for e, _ in given:
                if e.name in free:
                    starts += e.fit_starts(scale, residuals)
        fit = fit_effects(ev, names, fixed=fixed, starts=starts)
    std = (
        parameter_std(ev, fit, fixed)
        if uncertainty
        else {n: dict.fromkeys(fit.values[n]) for n in names}
    )
    return {n: dict(fit.values[n]) for n in names}, std


def parameter_std(
    ev: Evaluator, fit: Fit, fixed: Mapping[str, Mapping[str, float]] | None = None
) -> dict[str, dict[str, float | None]]:
    """Standard errors of a fit's free parameters, SI units
    (:func:`~hybridtable.effects.fitting.standard_errors` of the whitened
    residuals, ``J`` by central differences of a hundredth of each parameter's
    typical change, one-sided at a bound). ``None`` for a parameter held
    fixed, and for all when the parameters are not identifiable."""
    space = _space(ev, fit.effects, fit.values, fixed or {})
    residual = _residual(ev, fit.effects, fit.indices, fit.stage, {})
    r0 = np.concatenate([w for i in fit.indices for w in fit.evaluations[i].whitened.values()])
    return standard_errors(residual, space, r0, step=1e-2)


def residual_probe(data: Sequence[RunData], evaluations: Mapping[int, Evaluation]):
    """Per run: the time (s) and the replay residuals (f_mea N, p_act m) an effect's ``starts`` reads."""
    return [
        {
            "time_s": data[i].run.time_s,
            "f_mea_n": evaluations[i].residual["f_mea_n"],
            "p_act_m": evaluations[i].residual["p_act_m"],
        }
        for i in sorted(evaluations)
    ]
