"""Least-squares fits of effects to the prewhitened residuals, BIC and the
leave-one-run-out check.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from hybridtable.diagnosis.evaluate import Evaluation, Evaluator, RunData, prepare_runs
from hybridtable.diagnosis.settings import CHANNELS, FIT_ACCURACY
from hybridtable.effects.effect import Effect
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
    "starts_for",
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
    """Fit the effects ``names`` jointly to the runs ``indices``.

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
    scale = ev.scale
    indices = list(range(len(ev.data))) if indices is None else list(indices)
    effects = [get_effect(n) for n in names]
    fixed = {k: dict(v) for k, v in (fixed or {}).items()}
    base = {e.name: e.start(scale) for e in effects}
    for n, vals in (start or {}).items():
        if n in base:
            base[n].update(vals)
    for n, vals in fixed.items():
        base[n].update(vals)
    free = [
        (e.name, p) for e in effects for p in e.parameters if p.name not in fixed.get(e.name, {})
    ]

    def values_of(u: np.ndarray, origin: Mapping[str, Mapping[str, float]]):
        vals = {n: dict(v) for n, v in origin.items()}
        for (n, p), x in zip(free, u, strict=True):
            lo, hi = p.bounds(scale)
            vals[n][p.name] = float(np.clip(p.value_at(x, scale, origin[n][p.name]), lo, hi))
        return vals

    def evaluate(vals) -> dict[int, Evaluation]:
        spec = model_spec(names, vals, scale)
        return {i: ev.evaluate(spec, i, stage) for i in indices}

    def stack(evs: dict[int, Evaluation]) -> np.ndarray:
        return np.concatenate([w for i in indices for w in evs[i].whitened.values()])

    # Pick the best starting point.
    origin = {n: dict(v) for n, v in base.items()}
    candidates = [origin]
    for s in starts:
        cand = {n: dict(v) for n, v in origin.items()}
        for n, vals in s.items():
            if n in cand:
                cand[n].update({k: v for k, v in vals.items() if k not in fixed.get(n, {})})
        candidates.append(cand)
    best = None
    for cand in candidates:
        evs = evaluate(cand)
        r = stack(evs)
        cost = float(r @ r)
        if best is None or cost < best[0]:
            best = (cost, cand, evs)
    _, origin, evs0 = best
    nfev = len(candidates)
    if not free:
        return Fit(list(names), origin, stage, indices, evs0, 0, nfev)

    # in each parameter's coordinate: steps of its typical change from the origin
    # (of the logarithm's, for a log parameter)
    lo = np.array([p.coordinate(p.bounds(scale)[0], scale, origin[n][p.name]) for n, p in free])
    hi = np.array([p.coordinate(p.bounds(scale)[1], scale, origin[n][p.name]) for n, p in free])
    cache: dict[bytes, dict[int, Evaluation]] = {np.zeros(len(free)).tobytes(): evs0}

    def fun(u: np.ndarray) -> np.ndarray:
        key = u.tobytes()
        if key not in cache:
            cache[key] = evaluate(values_of(u, origin))
        return stack(cache[key])

    x0 = np.clip(np.zeros(len(free)), lo, hi)
    try:
        sol = least_squares(
            fun,
            x0,
            bounds=(lo, hi),
            method="dogbox",
            diff_step=1e-2,
            x_scale=1.0,
            ftol=1e-5,
            xtol=1e-4,
            gtol=1e-8,
            max_nfev=max_nfev,
        )
        u, success, nfev = sol.x, bool(sol.status > 0), nfev + sol.nfev
    except ValueError:  # e.g. non-finite residuals
        u, success = np.zeros(len(free)), False
    vals = values_of(u, origin)
    evs = cache.get(u.tobytes()) or evaluate(vals)
    # Never worse than the best start.
    if float(stack(evs) @ stack(evs)) > float(stack(evs0) @ stack(evs0)):
        vals, evs = origin, evs0
    return Fit(list(names), vals, stage, indices, evs, len(free), nfev, success)


# -- criteria ------------------------------------------------------------------
def delta_bic(before: Fit, after: Fit) -> float:
    """``sum_b N_b ln(s2_b,before / s2_b,after) - dp ln N`` over shared blocks,
    ``s2_b = max(RSS_b / N_b, floor_b)``: no model is credited with
    residuals below a numerical floor (:attr:`~hybridtable.diagnosis.evaluate.Evaluation.floor`)."""
    rb, ra = before.rss_blocks(), after.rss_blocks()
    total = 0.0
    n_total = 0
    for key, r0 in rb.items():
        i, c = key
        n_b = len(before.evaluations[i].whitened[c])
        n_total += n_b
        s0 = max(r0 / n_b, before.evaluations[i].floor.get(c, 0.0))
        s1 = max(ra[key] / n_b, after.evaluations[i].floor.get(c, 0.0))
        if s0 > 0.0 and s1 > 0.0:
            total += n_b * math.log(s0 / s1)
    dp = after.n_parameters - before.n_parameters
    return total - dp * math.log(max(n_total, 2))


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
                    starts += starts_for(e, scale, residuals)
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
    """Standard errors of a fit's free parameters, SI units.

    The linearized least-squares covariance ``s^2 (J^T J)^-1`` of the whitened
    residuals (``J`` by central differences of a hundredth of each
    parameter's typical change, one-sided at a bound), with
    ``s^2 = max(1, RSS / (N - p))``: the residuals are in noise units, and a
    misfit larger than the noise widens the errors rather than narrowing
    them. ``None`` for a parameter held fixed, and for all when the
    parameters are not identifiable (a singular ``J^T J``).
    """
    fixed = fixed or {}
    scale = ev.scale
    names = list(fit.effects)
    free = [
        (n, p) for n in names for p in get_effect(n).parameters if p.name not in fixed.get(n, {})
    ]
    out: dict[str, dict[str, float | None]] = {n: dict.fromkeys(fit.values[n]) for n in names}
    if not free:
        return out

    def stack(vals) -> np.ndarray:
        spec = model_spec(names, vals, scale)
        evs = [ev.evaluate(spec, i, fit.stage) for i in fit.indices]
        return np.concatenate([w for e in evs for w in e.whitened.values()])

    r0 = np.concatenate([w for i in fit.indices for w in fit.evaluations[i].whitened.values()])
    jac = np.empty((r0.size, len(free)))
    for j, (n, p) in enumerate(free):
        lo, hi = p.bounds(scale)
        x = fit.values[n][p.name]
        step = 1e-2 * p.typical(scale) * (abs(x) if p.log else 1.0)  # log: a relative step
        up, down = min(x + step, hi), max(x - step, lo)
        if up <= down:
            return out
        vals_up = {k: dict(v) for k, v in fit.values.items()}
        vals_dn = {k: dict(v) for k, v in fit.values.items()}
        vals_up[n][p.name], vals_dn[n][p.name] = up, down
        jac[:, j] = (stack(vals_up) - stack(vals_dn)) / (up - down)
    dof = max(r0.size - len(free), 1)
    s2 = max(1.0, float(r0 @ r0) / dof)
    jtj = jac.T @ jac
    if not np.all(np.isfinite(jtj)) or np.linalg.cond(jtj) > 1e14:
        return out
    cov = s2 * np.linalg.inv(jtj)
    for j, (n, p) in enumerate(free):
        out[n][p.name] = math.sqrt(max(float(cov[j, j]), 0.0))
    return out


def starts_for(effect: Effect, scale: RigScale, residuals) -> list[dict[str, dict[str, float]]]:
    """Extra starting points of ``effect``'s fit (its ``starts``, from the residuals), as fit starts."""
    if effect.starts is None:
        return []
    return [{effect.name: s} for s in effect.starts(scale, residuals)]


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
