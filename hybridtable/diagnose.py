"""Which physical effect is the rig model missing? Fit, rank, select.

:func:`diagnose` fits every candidate of :mod:`hybridtable.effects` to a set
of recorded runs and ranks them:

1. **Residuals.** The replay (:mod:`hybridtable.replay`: the recorded command
   through table, contact and force sensor) predicts ``f_mea`` and ``p_act``;
   the residuals of each run and channel are *prewhitened* with an AR(1) noise
   model estimated without any model from the no-contact ticks
   (:func:`estimate_noise`) and divided by the innovations' standard
   deviation, so that under a right model they are white with unit variance.
2. **Fit.** ``scipy.optimize.least_squares`` (bounded, in units of each
   parameter's typical change) on the stacked whitened residuals of all runs,
   from the effect's start values and its data-driven starts.
3. **Criterion.** ``delta_bic = sum_b N_b ln(RSS_b,before / RSS_b,after) -
   dp ln N`` over the blocks ``b`` (run x channel), each with its own noise
   level (profiled out), ``N`` the whitened samples: > 0 favours the effect,
   and :data:`BIC_THRESHOLD` (10) is very strong evidence.
4. **Held-out check.** Leave-one-run-out: the effect fitted on the other runs
   predicts the held-out run; ``z = sum dSSE / (2 sqrt(sum |dy|^2))`` with
   ``dSSE`` the fall of the held-out run's whitened squared error and ``dy``
   the change of its prediction. Without the effect in the data ``z`` is
   normal with mean ``-|dy|/2 <= 0`` and unit variance; significant needs
   ``z >`` :data:`Z_THRESHOLD` (3) as well as the BIC test (one run: BIC only).
5. **Verdict and forward selection.** The significant effect with the largest
   ``delta_bic`` is the verdict (``none`` without one); it joins the model and
   the remaining effects (those not touching the same part) are fitted again
   jointly with it, until nothing significant is left: the *staircase*.
   Effects seen only in the closed loop (``mass_error``) are tested last, on
   the closed loop's spacecraft velocity with the physics selected so far.
6. **Look-alikes.** Two significant effects whose ``delta_bic`` differ by less
   than :data:`INDISTINGUISHABLE_BIC` (6) are indistinguishable on the data;
   :func:`separating_run` simulates candidate runs (other approach velocity,
   other spacecraft mass) with both fitted models and names the one whose
   predictions differ most.

"Error" in the results is the RMS residual in units of the noise (pooled over
runs and both channels, each divided by its model-free noise RMS): 1.0 is the
noise floor.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from hybridtable.comparison import (
    _dilate,
    _runs,
    contact_mask,
    delayed_labels,
    phase_labels,
)
from hybridtable.effect_systems import RecordedOffset, chain_output
from hybridtable.effects import (
    EFFECTS,
    Effect,
    ModelSpec,
    RigScale,
    build_spec,
    get_effect,
)
from hybridtable.measurement import MeasurementError, Run
from hybridtable.replay import replay, replay_command
from hybridtable.rig import rig_params, simulate_rig
from hybridtable.sensor import delay_samples
from hybridtable.simulation import SimulationError

__all__ = [
    "BIC_THRESHOLD",
    "Z_THRESHOLD",
    "INDISTINGUISHABLE_BIC",
    "CHANNELS",
    "NoiseModel",
    "estimate_noise",
    "ar1_from_segments",
    "whiten",
    "RunData",
    "prepare_runs",
    "Evaluation",
    "Evaluator",
    "Fit",
    "fit_effects",
    "fit_effect",
    "Candidate",
    "Diagnosis",
    "diagnose",
    "separating_run",
]

#: Smallest ``delta_bic`` of a significant effect (Kass & Raftery: > 10 is
#: very strong evidence).
BIC_THRESHOLD = 10.0
#: Smallest leave-one-run-out ``z`` of a significant effect.
Z_THRESHOLD = 3.0
#: Two significant effects whose ``delta_bic`` differ by less are
#: indistinguishable on the data (< 6: no strong evidence for either).
INDISTINGUISHABLE_BIC = 6.0
#: Replay channels and their units.
CHANNELS: dict[str, str] = {"f_mea_n": "N", "p_act_m": "m"}
#: Integrator accuracy of the fits (RK3; 1e-3 N and 2e-8 m of error on the
#: examples, far under the noise).
FIT_ACCURACY = 1e-5
#: Noise floor of a noise-free record, relative to the largest reading (force)
#: or the range (position): the fits' numerical resolution.
NUMERICAL_FLOOR = 1e-5
#: Smallest force error (in units of the force noise) the closed loop's
#: velocity residual is credited with: below it, errors are numerical.
CLOSED_LOOP_FLOOR = 1e-3
#: Residual value standing in for a model run that failed during a fit.
FAILED_RESIDUAL = 1e3


# -- noise ---------------------------------------------------------------------
@dataclass(frozen=True)
class NoiseModel:
    """AR(1) noise of a channel: ``e[k] = phi e[k-1] + sigma sqrt(1 - phi^2) xi[k]``.

    ``sigma`` is the marginal standard deviation (the noise RMS), ``samples``
    the ticks the estimate used.
    """

    sigma: float
    phi: float
    samples: int

    @property
    def innovation_sigma(self) -> float:
        return self.sigma * math.sqrt(1.0 - self.phi * self.phi)


def _ar1_apply(x: np.ndarray, phi: float) -> np.ndarray:
    """``R x`` for the AR(1) correlation matrix ``R_ij = phi^|i-j|`` (O(n))."""
    fwd = np.empty_like(x)
    bwd = np.empty_like(x)
    acc = np.zeros(x.shape[1:])
    for i in range(len(x)):
        acc = x[i] + phi * acc
        fwd[i] = acc
    acc = np.zeros(x.shape[1:])
    for i in range(len(x) - 1, -1, -1):
        acc = x[i] + phi * acc
        bwd[i] = acc
    return fwd + bwd - x


def ar1_from_segments(segments: Sequence[np.ndarray], degree: int) -> NoiseModel | None:
    """AR(1) noise of segments that hold noise plus a polynomial of ``degree``.

    Each segment's polynomial trend is removed; the pooled lag-1
    autocorrelation is corrected for the bias of short detrended segments
    (``E[phi_hat] ~ phi - (q + (q + 2) phi) / n``, ``q = degree + 1``), and
    the variance for the noise the trend removes:
    ``E[sum x^2] = sigma^2 sum_s (n_s - trace(Q_s' R(phi) Q_s))`` with ``Q_s``
    an orthonormal basis of the trend and ``R`` the AR(1) correlation.
    Returns None with fewer than 20 degrees of freedom.
    """
    q = degree + 1
    s0 = s1 = 0.0
    kept = []
    for seg in segments:
        seg = np.asarray(seg, dtype=float)
        if len(seg) < q + 4:
            continue
        t = np.linspace(-1.0, 1.0, len(seg))
        basis, _ = np.linalg.qr(np.vander(t, q, increasing=True))
        x = seg - basis @ (basis.T @ seg)
        s0 += float(x @ x)
        s1 += float(x[1:] @ x[:-1])
        kept.append(basis)
    total = sum(len(b) for b in kept)
    if total - q * len(kept) < 20:
        return None
    if not s0 > 0.0:  # a noise-free record
        return NoiseModel(0.0, 0.0, total)
    k = len(kept)
    phi_hat = s1 / s0
    phi = (phi_hat + k * q / total) / (1.0 - k * (q + 2) / total)
    phi = float(np.clip(phi, -0.95, 0.98))
    dof = sum(len(b) - float(np.trace(b.T @ _ar1_apply(b, phi))) for b in kept)
    dof = max(dof, 0.25 * total)
    return NoiseModel(math.sqrt(s0 / dof), phi, total)


def estimate_noise(run: Run, delay_ticks: int, settle_ticks: int) -> dict[str, NoiseModel]:
    """Model-free AR(1) noise of ``f_mea`` and ``p_act`` from the no-contact ticks.

    ``f_mea``: the true force is zero away from contact (2 ticks of guard,
    the readings shifted by the sensor delay), so the readings about each
    segment's mean are noise (an offset is model error, not noise).
    ``p_act``: away from contact, after ``settle_ticks`` (the start and the
    end of each contact), the table tracks the command's ramp with a
    constant lag, sampled once per tick: the residuals of a straight line
    fitted to each segment are the noise (:func:`ar1_from_segments`).
    """
    on = contact_mask(run.p_act_m)
    guard = 2
    quiet = ~_dilate(on, guard, guard)
    quiet_f = delayed_labels(quiet.astype(int), delay_ticks).astype(bool)
    quiet_f[: min(delay_ticks, len(quiet_f))] = True
    out: dict[str, NoiseModel] = {}
    f_noise = ar1_from_segments([run.f_mea_n[a : b + 1] for a, b in _runs(quiet_f)], 0)
    if f_noise is not None:
        out["f_mea_n"] = f_noise
    quiet_p = ~_dilate(on, guard, settle_ticks)
    quiet_p[: min(settle_ticks, len(quiet_p))] = False
    p_noise = ar1_from_segments([run.p_act_m[a : b + 1] for a, b in _runs(quiet_p)], 1)
    if p_noise is not None:
        out["p_act_m"] = p_noise
    return out


def whiten(e: np.ndarray, noise: NoiseModel) -> np.ndarray:
    """Innovations of an AR(1) residual over their standard deviation
    (unit-variance white noise if ``e`` is the noise)."""
    e = np.asarray(e, dtype=float)
    phi = noise.phi
    w = np.empty_like(e)
    w[0] = e[0] * math.sqrt(1.0 - phi * phi)
    w[1:] = e[1:] - phi * e[:-1]
    return w / noise.innovation_sigma


# -- data ----------------------------------------------------------------------
@dataclass
class RunData:
    """A run with what diagnose needs of it."""

    run: Run
    delay_ticks: int
    labels: np.ndarray
    f_labels: np.ndarray
    noise: dict[str, NoiseModel]
    notes: list[str] = field(default_factory=list)
    #: Numerical resolution of each channel (:data:`NUMERICAL_FLOOR`).
    floors: dict[str, float] = field(default_factory=dict)

    @property
    def run_id(self) -> str:
        return self.run.run_id


def prepare_runs(runs: Sequence[Run]) -> list[RunData]:
    """Check the runs and estimate their noise.

    Raises
    ------
    MeasurementError
        If a run makes no model (its JSON), holds no contact, has too few
        no-contact ticks to estimate the force noise, or if the runs are of
        rigs with other sample rates.
    """
    if not runs:
        raise MeasurementError("no runs to diagnose")
    rates = {r.info.sample_rate_hz for r in runs}
    if len(rates) > 1:
        raise MeasurementError(
            "runs of different sample rates "
            f"({', '.join(f'{x:g}' for x in sorted(rates))} Hz): diagnose one rig at a time"
        )
    out = []
    for run in runs:
        params = rig_params(run.info, run.where("json"))
        try:
            labels = phase_labels(run.p_act_m)
        except ValueError as err:
            raise MeasurementError(f"{run.where('csv')}: {err}") from None
        m = delay_samples(params.sensor_delay_s, run.sample_period_s)
        table = params.table()
        h = run.sample_period_s
        zeta_w = 0.0 if table.is_ideal else table.damping_ratio * table.omega_rad_per_s
        settle = max(2, math.ceil(5.0 / zeta_w / h)) if zeta_w > 0.0 else 2
        noise = estimate_noise(run, m, settle)
        notes = []
        if "f_mea_n" not in noise:
            raise MeasurementError(
                f"{run.where('csv')}: fewer than 20 ticks without contact; "
                "cannot estimate the force noise"
            )
        if "p_act_m" not in noise:
            noise["p_act_m"] = estimate_noise(run, m, 2).get("p_act_m")
            notes.append("p_act noise from stretches where the table may not have settled")
        if noise["p_act_m"] is None:
            noise["p_act_m"] = NoiseModel(
                float(np.std(np.diff(run.p_act_m, 3))) / math.sqrt(20.0), 0.0, 0
            )
            notes.append("p_act noise from third differences of the whole record")
        floors = {
            "f_mea_n": NUMERICAL_FLOOR * max(float(np.abs(run.f_mea_n).max()), 1.0),
            "p_act_m": NUMERICAL_FLOOR * max(float(np.ptp(run.p_act_m)), 1e-6),
        }
        for c, floor in floors.items():
            if not noise[c].sigma > floor:
                noise[c] = NoiseModel(floor, 0.0, noise[c].samples)
                notes.append(f"{c}: no noise found; its floor is set to {floor:.3g}")
        out.append(RunData(run, m, labels, delayed_labels(labels, m), noise, notes, floors))
    return out


# -- evaluation of a model -----------------------------------------------------
@dataclass
class Evaluation:
    """A model's predictions and residuals on one run (replay channels, or
    the closed loop's ``v_des``)."""

    prediction: dict[str, np.ndarray]
    residual: dict[str, np.ndarray]
    whitened: dict[str, np.ndarray]
    failed: bool = False
    #: Smallest variance of a channel's whitened residual credited to a
    #: model: the numerical resolution (negligible against any real noise).
    floor: dict[str, float] = field(default_factory=dict)

    def rss(self) -> dict[str, float]:
        return {c: float(w @ w) for c, w in self.whitened.items()}


class Evaluator:
    """Predicts runs with a :class:`~hybridtable.effects.ModelSpec`.

    ``stage="replay"``: the replay's ``f_mea`` and ``p_act``, whitened with
    the runs' noise. ``stage="closed_loop"``: the closed loop's ``v_des``,
    whitened by first differences (the velocity integrates the force) and
    an AR(1) model of that (:attr:`closed_loop_noise`).
    """

    def __init__(
        self,
        data: Sequence[RunData],
        scale: RigScale,
        accuracy: float = FIT_ACCURACY,
    ) -> None:
        self.data = list(data)
        self.scale = scale
        self.accuracy = accuracy
        #: Force-reading noise added to the closed loop's sensor, per run
        #: (:meth:`inject_noise`).
        self.injected_noise: list[np.ndarray | None] = [None] * len(self.data)
        #: Noise of the closed loop's differenced v_des residual, per run
        #: (:meth:`calibrate_closed_loop`).
        self.closed_loop_noise: list[NoiseModel] = [NoiseModel(1.0, 0.0, 0)] * len(self.data)
        self.simulations = 0

    def evaluate(self, spec: ModelSpec, i: int, stage: str = "replay") -> Evaluation:
        d = self.data[i]
        run = d.run
        self.simulations += 1
        physics = spec.physics()
        if stage == "replay":
            try:
                rep = replay(run, physics, accuracy=self.accuracy)
                pred = {
                    "f_mea_n": rep.f_mea_n,
                    "p_act_m": rep.p_act_m,
                    "f_act_n": rep.f_act_n,
                }
            except SimulationError:
                return self._failed(i, stage)
            res = {c: getattr(run, c) - pred[c] for c in CHANNELS}
            white = {c: whiten(res[c], d.noise[c]) for c in CHANNELS}
            floor = {c: (d.floors.get(c, 0.0) / d.noise[c].innovation_sigma) ** 2 for c in CHANNELS}
            return Evaluation(pred, res, white, floor=floor)
        noise = self.injected_noise[i]
        if noise is not None:
            h = run.sample_period_s
            physics = spec.wrap(
                "sensor",
                lambda p, sensor: chain_output(sensor, RecordedOffset(h, noise), "measured_force"),
            ).physics()
        try:
            cl = simulate_rig(spec.closed_loop_run(run), physics, accuracy=self.accuracy)
        except SimulationError:
            return self._failed(i, stage)
        v = cl.v_des_m_per_s
        res = {"v_des_m_per_s": run.v_des_m_per_s - v}
        noise = self.closed_loop_noise[i]
        w = whiten(np.diff(res["v_des_m_per_s"], prepend=0.0), noise)
        floor = (self._closed_loop_floor(i) / noise.innovation_sigma) ** 2
        return Evaluation(
            {"v_des_m_per_s": v, "f_comp_n": cl.f_comp_n},
            res,
            {"v_des_m_per_s": w},
            floor={"v_des_m_per_s": floor},
        )

    def _closed_loop_floor(self, i: int) -> float:
        """Below a thousandth of the force noise (:data:`CLOSED_LOOP_FLOOR`),
        velocity errors per tick are numerical (integration, rounding)."""
        run = self.data[i].run
        sigma_f = self.data[i].noise["f_mea_n"].sigma
        return CLOSED_LOOP_FLOOR * sigma_f * run.sample_period_s / run.info.spacecraft_mass_kg

    def inject_noise(self, replay_base: Mapping[int, Evaluation]) -> None:
        """Feed the closed loop's compensator the noise the rig's computer
        read: the ``f_mea`` residual of a replay model (the record's reading
        minus the model's). With the command of the record, the closed loop
        then reproduces the record's reading whatever the error of the
        physics model, so the closed loop tests the computer's side (e.g.
        the spacecraft mass) alone; the table position's noise, which the
        MDC reads, is not injected."""
        for i, ev in replay_base.items():
            self.injected_noise[i] = np.asarray(ev.residual["f_mea_n"], dtype=float).copy()

    def calibrate_closed_loop(self, base: Mapping[int, Evaluation]) -> None:
        """Fix the closed loop's whitening from a base model's residuals: an
        AR(1) model of the differenced ``v_des`` residual of each run (the
        velocity integrates the compensated force, whose noise the rig's
        sensors colour)."""
        for i, ev in base.items():
            d = np.diff(ev.residual["v_des_m_per_s"], prepend=0.0)
            floor = self._closed_loop_floor(i)
            s0 = float(d @ d)
            sigma = math.sqrt(s0 / len(d))
            if sigma <= floor:
                self.closed_loop_noise[i] = NoiseModel(floor, 0.0, len(d))
                continue
            phi = float(np.clip(float(d[1:] @ d[:-1]) / s0, -0.95, 0.95))
            self.closed_loop_noise[i] = NoiseModel(sigma, phi, len(d))

    def _failed(self, i: int, stage: str) -> Evaluation:
        n = self.data[i].run.n
        chans = CHANNELS if stage == "replay" else {"v_des_m_per_s": "m/s"}
        big = np.full(n, FAILED_RESIDUAL)
        return Evaluation(
            {c: np.full(n, np.nan) for c in chans},
            {c: big for c in chans},
            {c: big for c in chans},
            failed=True,
        )


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


def _model_spec(
    names: Sequence[str], values: Mapping[str, Mapping[str, float]], scale: RigScale
) -> ModelSpec:
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
            vals[n][p.name] = float(np.clip(origin[n][p.name] + x * p.typical(scale), lo, hi))
        return vals

    def evaluate(vals) -> dict[int, Evaluation]:
        spec = _model_spec(names, vals, scale)
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

    lo = np.array([(p.bounds(scale)[0] - origin[n][p.name]) / p.typical(scale) for n, p in free])
    hi = np.array([(p.bounds(scale)[1] - origin[n][p.name]) / p.typical(scale) for n, p in free])
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
    residuals below a numerical floor (:attr:`Evaluation.floor`)."""
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


def _heldout(
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
        spec = _model_spec(names, fit.values, ev.scale)
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


# -- candidates and the diagnosis ----------------------------------------------
@dataclass
class Candidate:
    """One effect fitted on top of a base model in one round."""

    effect: str
    stage: str
    parameters: dict[str, float]
    model: list[str]
    model_values: dict[str, dict[str, float]]
    error_before: float
    error_after: float
    heldout_error_after: float
    delta_bic: float
    heldout_z: float
    significant: bool
    channel_error_before: dict[str, float]
    channel_error_after: dict[str, float]
    indistinguishable_from: list[str] = field(default_factory=list)
    separation: dict | None = None
    nfev: int = 0
    notes: list[str] = field(default_factory=list)
    fit: Fit | None = None

    def to_json(self) -> dict:
        return {
            "effect": self.effect,
            "stage": self.stage,
            "parameters": dict(self.parameters),
            "units": {p.name: p.unit for p in get_effect(self.effect).parameters},
            "error_before": self.error_before,
            "error_after": self.error_after,
            "heldout_error_after": self.heldout_error_after,
            "delta_bic": self.delta_bic,
            "heldout_z": self.heldout_z,
            "significant": self.significant,
            "indistinguishable_from": list(self.indistinguishable_from),
            "separating_run": self.separation,
            "channel_error_before": dict(self.channel_error_before),
            "channel_error_after": dict(self.channel_error_after),
            "notes": list(self.notes),
        }


@dataclass
class Diagnosis:
    """Everything :func:`diagnose` found."""

    data: list[RunData]
    scale: RigScale
    verdict: str
    selected: list[str]
    selected_values: dict[str, dict[str, float]]
    rounds: list[list[Candidate]]
    staircase: list[dict]
    closed_loop_candidates: list[Candidate]
    nominal: dict[int, Evaluation]
    final: dict[int, Evaluation]
    closed_loop: dict[str, dict]
    simulations: int
    wall_time_s: float = math.nan
    notes: list[str] = field(default_factory=list)

    @property
    def ranking(self) -> list[Candidate]:
        """The first round (every effect against the nominal model; the
        closed-loop effects against the physics selected) by ``delta_bic``."""
        first = self.rounds[0] if self.rounds else []
        return list(first) + list(self.closed_loop_candidates)

    def final_spec(self) -> ModelSpec:
        return _model_spec(self.selected, self.selected_values, self.scale)

    def to_json(self) -> dict:
        return {
            "verdict": self.verdict,
            "selected": list(self.selected),
            "parameters": {n: dict(v) for n, v in self.selected_values.items()},
            "ranking": [c.to_json() for c in self.ranking],
            "staircase": list(self.staircase),
            "rounds": [[c.to_json() for c in r] for r in self.rounds],
            "closed_loop": self.closed_loop,
            "runs": [
                {
                    "run_id": d.run_id,
                    "compensator": d.run.info.compensator,
                    "initial_velocity_m_per_s": d.run.info.initial_velocity_m_per_s,
                    "noise": {
                        c: {"rms": m.sigma, "ar1": m.phi, "samples": m.samples}
                        for c, m in d.noise.items()
                    },
                    "notes": list(d.notes),
                }
                for d in self.data
            ],
            "criteria": {
                "bic_threshold": BIC_THRESHOLD,
                "z_threshold": Z_THRESHOLD,
                "indistinguishable_bic": INDISTINGUISHABLE_BIC,
                "error_unit": "RMS residual / noise RMS, pooled over runs, f_mea and p_act",
            },
            "simulations": self.simulations,
            "wall_time_s": self.wall_time_s,
            "notes": list(self.notes),
        }


def _starts_for(effect: Effect, scale: RigScale, residuals) -> list[dict[str, dict[str, float]]]:
    if effect.starts is None:
        return []
    return [{effect.name: s} for s in effect.starts(scale, residuals)]


def _evaluate_candidate(
    ev: Evaluator,
    base_fit: Fit,
    base_error: tuple[float, dict[str, float]],
    effect: Effect,
    residuals,
    always_heldout: bool,
    stage: str,
) -> Candidate:
    names = [*base_fit.effects, effect.name]
    start = {**base_fit.values, effect.name: effect.start(ev.scale)}
    starts = _starts_for(effect, ev.scale, residuals)
    if base_fit.effects:
        # The new effect alone on the fixed base first; jointly only if it helps.
        fit = fit_effects(ev, names, start=start, fixed=base_fit.values, starts=starts, stage=stage)
        fit.n_parameters += base_fit.n_parameters
        if delta_bic(base_fit, fit) > 0.0:
            joint = fit_effects(ev, names, start=fit.values, stage=stage)
            if delta_bic(base_fit, joint) > delta_bic(base_fit, fit):
                joint.nfev += fit.nfev
                fit = joint
    else:
        fit = fit_effects(ev, names, start=start, starts=starts, stage=stage)
    dbic = delta_bic(base_fit, fit)
    if stage == "replay":
        err_after, chan_after = pooled_error(ev.data, fit.evaluations)
    else:
        err_after, chan_after = _velocity_error(fit.evaluations)
    notes = []
    if fit.failed:
        notes.append("a model run failed during the fit")
    if dbic > BIC_THRESHOLD or always_heldout:
        held = _heldout(ev, base_fit.evaluations, names, fit.values, stage)
    else:
        held = HeldOut(math.nan, math.nan, [])
    if stage != "replay" and len(ev.data) > 1:
        held.error = math.nan
    if len(ev.data) < 2:
        notes.append("one run: no leave-one-run-out check")
    significant = bool(
        dbic > BIC_THRESHOLD
        and not fit.failed
        and (len(ev.data) < 2 or (math.isfinite(held.z) and held.z > Z_THRESHOLD))
    )
    return Candidate(
        effect=effect.name,
        stage=stage,
        parameters=dict(fit.values[effect.name]),
        model=names,
        model_values={n: dict(v) for n, v in fit.values.items()},
        error_before=base_error[0],
        error_after=err_after,
        heldout_error_after=held.error,
        delta_bic=dbic,
        heldout_z=held.z,
        significant=significant,
        channel_error_before=base_error[1],
        channel_error_after=chan_after,
        nfev=fit.nfev,
        notes=notes,
        fit=fit,
    )


def _velocity_error(evaluations: Mapping[int, Evaluation]) -> tuple[float, dict[str, float]]:
    sq = [float(np.mean(ev.residual["v_des_m_per_s"] ** 2)) for ev in evaluations.values()]
    rms = math.sqrt(float(np.mean(sq)))
    return rms, {"v_des_m_per_s": rms}


def _residual_probe(data: Sequence[RunData], evaluations: Mapping[int, Evaluation]):
    return [
        {
            "time_s": data[i].run.time_s,
            "f_mea_n": evaluations[i].residual["f_mea_n"],
            "p_act_m": evaluations[i].residual["p_act_m"],
        }
        for i in sorted(evaluations)
    ]


def _mark_lookalikes(candidates: list[Candidate]) -> None:
    sig = [c for c in candidates if c.significant]
    for c in sig:
        c.indistinguishable_from = [
            o.effect
            for o in sig
            if o is not c and abs(o.delta_bic - c.delta_bic) < INDISTINGUISHABLE_BIC
        ]


def _cor_of(v_des: np.ndarray, f_comp: np.ndarray, v0: float) -> float:
    on = np.flatnonzero(np.asarray(f_comp) != 0.0)
    if on.size == 0:
        return math.nan
    v_in = float(v_des[on[0] - 1]) if on[0] > 0 else v0
    return abs(float(v_des[-1])) / abs(v_in)


def _closed_loop_summary(ev: Evaluator, spec: ModelSpec) -> dict:
    """Closed-loop v_des RMS error and CoR error of a model (noise-free, as
    ``hybridtable compare``), per run."""
    rows = []
    injected, ev.injected_noise = ev.injected_noise, [None] * len(ev.data)
    for i, d in enumerate(ev.data):
        e = ev.evaluate(spec, i, "closed_loop")
        run = d.run
        cor_meas = _cor_of(run.v_des_m_per_s, run.f_comp_n, run.info.initial_velocity_m_per_s)
        if e.failed:
            rows.append({"run_id": d.run_id, "v_des_rms_error_m_per_s": math.nan})
            continue
        cor_model = _cor_of(
            e.prediction["v_des_m_per_s"],
            e.prediction["f_comp_n"],
            run.info.initial_velocity_m_per_s,
        )
        rows.append(
            {
                "run_id": d.run_id,
                "v_des_rms_error_m_per_s": float(
                    np.sqrt(np.mean(e.residual["v_des_m_per_s"] ** 2))
                ),
                "cor_measured": cor_meas,
                "cor_model": cor_model,
                "cor_error": cor_model - cor_meas,
            }
        )
    ev.injected_noise = injected
    return {"runs": rows}


# -- separating runs -----------------------------------------------------------
#: Candidate runs of :func:`separating_run`: (label, changes of the run's JSON).
DESIGNS: tuple[tuple[str, Callable[[Run], dict]], ...] = (
    ("half the approach velocity", lambda r: {"initial_velocity_m_per_s": 0.5 * _vmin(r)}),
    ("twice the approach velocity", lambda r: {"initial_velocity_m_per_s": 2.0 * _vmax(r)}),
    ("three times the approach velocity", lambda r: {"initial_velocity_m_per_s": 3.0 * _vmax(r)}),
    (
        "a quarter of the spacecraft mass",
        lambda r: {"spacecraft_mass_kg": 0.25 * r[0].info.spacecraft_mass_kg},
    ),
    (
        "four times the spacecraft mass",
        lambda r: {"spacecraft_mass_kg": 4.0 * r[0].info.spacecraft_mass_kg},
    ),
)


def _vmin(runs) -> float:
    return min(x.info.initial_velocity_m_per_s for x in runs)


def _vmax(runs) -> float:
    return max(x.info.initial_velocity_m_per_s for x in runs)


def _design_run(run: Run, changes: dict) -> Run:
    info = replace(run.info, run_id=f"{run.run_id}-design", **changes)
    v = info.initial_velocity_m_per_s
    m, k = info.spacecraft_mass_kg, info.contact_stiffness_n_per_m
    duration = info.initial_gap_m / v + 1.6 * math.pi * math.sqrt(m / k) + 0.1
    h = info.sample_period_s
    n = int(math.ceil(duration / h)) + 1
    z = np.zeros(n)
    return Run(info, h * np.arange(n), z, z, z, z, z)


def separating_run(
    ev: Evaluator,
    spec_a: ModelSpec,
    spec_b: ModelSpec,
) -> dict | None:
    """The candidate run (:data:`DESIGNS`) on which two fitted models differ most.

    Each design is the first run with changed JSON values; model A's closed
    loop gives its command, which both models replay. The difference of the
    predictions in noise units, ``sqrt(sum (dy / sigma)^2)`` over ``f_mea``
    and ``p_act``, is compared with the same distance on the recorded runs.
    Returns the best design (label, changes, distances, ``separates``: the
    squared distance of one such run exceeds :data:`BIC_THRESHOLD`, and
    ``runs_needed``: how many such runs would), or None if no design could
    be simulated.
    """
    runs = [d.run for d in ev.data]
    sig = {c: float(np.mean([d.noise[c].sigma for d in ev.data])) for c in CHANNELS}

    def distance(pa, pb) -> float:
        return math.sqrt(sum(float(np.sum(((pa[c] - pb[c]) / sig[c]) ** 2)) for c in CHANNELS))

    recorded = 0.0
    for i in range(len(ev.data)):
        a = ev.evaluate(spec_a, i).prediction
        b = ev.evaluate(spec_b, i).prediction
        if np.isnan(a["f_mea_n"]).any() or np.isnan(b["f_mea_n"]).any():
            continue
        recorded += distance(a, b) ** 2
    recorded = math.sqrt(recorded)
    best = None
    for label, changes_of in DESIGNS:
        changes = changes_of(runs)
        try:
            design = _design_run(runs[0], changes)
            physics_a = spec_a.physics()
            cl = simulate_rig(spec_a.closed_loop_run(design), physics_a, accuracy=ev.accuracy)
            params = rig_params(design.info)
            preds = []
            for spec in (spec_a, spec_b):
                rep = replay_command(
                    params,
                    cl.p_des_m,
                    cl.v_des_m_per_s,
                    spec.physics(),
                    accuracy=ev.accuracy,
                )
                preds.append({"f_mea_n": rep.f_mea_n, "p_act_m": rep.p_act_m})
        except (SimulationError, MeasurementError, ValueError):
            continue
        ev.simulations += 3
        dist = distance(*preds)
        if best is None or dist > best["distance"]:
            best = {
                "run": label,
                "changes": changes,
                "distance": dist,
                "recorded_distance": recorded,
                # One such run would tell them apart at the BIC threshold.
                "separates": dist * dist > BIC_THRESHOLD,
                # Independent runs add their squared distances.
                "runs_needed": (math.ceil(BIC_THRESHOLD / (dist * dist)) if dist > 0.0 else None),
            }
    return best


# -- the procedure -------------------------------------------------------------
def _pool_map(func, jobs, workers: int):
    if workers <= 1 or len(jobs) <= 1:
        return [func(j) for j in jobs]
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("fork")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        return list(pool.map(func, jobs))


_STATE: dict = {}


def _candidate_job(job):
    ev, base_fit, base_error, residuals = (
        _STATE["ev"],
        _STATE["base_fit"],
        _STATE["base_error"],
        _STATE["residuals"],
    )
    name, always, stage = job
    sims = ev.simulations
    c = _evaluate_candidate(ev, base_fit, base_error, get_effect(name), residuals, always, stage)
    return c, ev.simulations - sims


def _run_round(ev, base_fit, base_error, names, always_heldout, stage, workers, progress):
    residuals = _residual_probe(ev.data, base_fit.evaluations) if stage == "replay" else []
    _STATE.update(ev=ev, base_fit=base_fit, base_error=base_error, residuals=residuals)
    jobs = [(n, always_heldout, stage) for n in names]
    # Expensive effects first, so two workers finish together.
    jobs.sort(key=lambda j: -len(get_effect(j[0]).parameters))
    if workers > 1 and len(jobs) > 1:
        if progress:
            print(
                f"fitting {len(jobs)} effect(s) ({stage}) in {workers} processes...",
                file=sys.stderr,
            )
        out = _pool_map(_candidate_job, jobs, workers)
        ev.simulations += sum(s for _, s in out)
        cands = [c for c, _ in out]
    else:
        cands = []
        iterator = jobs
        if progress:
            from tqdm import tqdm

            iterator = tqdm(jobs, desc=f"fit {stage}", unit="effect", file=sys.stderr, leave=False)
        for job in iterator:
            cands.append(_candidate_job(job)[0])
    _STATE.clear()
    _rank(cands)
    _mark_lookalikes(cands)
    return cands


#: ``delta_bic`` differences below this are ties (a likelihood ratio of 1.3).
TIE_BIC = 0.5


def _rank(cands: list[Candidate]) -> None:
    """Sort by ``delta_bic``, ties (:data:`TIE_BIC`) broken by fewer
    parameters, then registration order (a tie between, e.g., a stiffness
    error and a series compliance, which predict the same, is numerical)."""
    order = {n: i for i, n in enumerate(EFFECTS)}
    cands.sort(key=lambda c: -c.delta_bic)
    for _ in range(len(cands)):
        swapped = False
        for i in range(len(cands) - 1):
            a, b = cands[i], cands[i + 1]
            if a.delta_bic - b.delta_bic < TIE_BIC and (
                len(b.parameters),
                order.get(b.effect, len(order)),
            ) < (len(a.parameters), order.get(a.effect, len(order))):
                cands[i], cands[i + 1] = b, a
                swapped = True
        if not swapped:
            break


def diagnose(
    runs: Sequence[Run],
    effects: Sequence[str] | None = None,
    max_effects: int = 3,
    workers: int | None = None,
    separate: bool = True,
    progress: bool = False,
    accuracy: float = FIT_ACCURACY,
) -> Diagnosis:
    """Name the physical effect the rig model is missing (see the module doc).

    Parameters
    ----------
    runs : sequence of Run
        Runs of one rig (same sample rate), each with a contact.
    effects : sequence of str, optional
        Candidate effects (default: every registered one).
    max_effects : int
        Most effects the forward selection adds.
    workers : int, optional
        Processes fitting candidates in parallel (default: up to 2).
    separate : bool
        Look for a run separating look-alikes of the verdict.

    Raises
    ------
    MeasurementError
        If a run cannot be diagnosed (:func:`prepare_runs`).
    """
    import time

    t0 = time.perf_counter()
    data = prepare_runs(runs)
    scale = RigScale.from_runs(runs)
    names = list(effects) if effects is not None else list(EFFECTS)
    for n in names:
        get_effect(n)
    if workers is None:
        workers = min(2, os.cpu_count() or 1)
    ev = Evaluator(data, scale, accuracy)
    replay_names = [n for n in names if get_effect(n).stage == "replay"]
    loop_names = [n for n in names if get_effect(n).stage == "closed_loop"]

    nominal = fit_effects(ev, [], stage="replay")
    base_fit = nominal
    base_error = pooled_error(data, nominal.evaluations)
    staircase = [
        {
            "effects": [],
            "parameters": {},
            "error": base_error[0],
            "heldout_error": base_error[0],
            "channel_error": base_error[1],
            "delta_bic": 0.0,
        }
    ]
    rounds: list[list[Candidate]] = []
    selected: list[str] = []
    while len(selected) < max_effects:
        pool = [
            n
            for n in replay_names
            if n not in selected
            and not any(get_effect(n).conflicts_with(get_effect(s)) for s in selected)
        ]
        if not pool:
            break
        cands = _run_round(ev, base_fit, base_error, pool, not rounds, "replay", workers, progress)
        rounds.append(cands)
        best = next((c for c in cands if c.significant), None)
        if best is None:
            break
        selected.append(best.effect)
        base_fit = best.fit
        base_error = (best.error_after, best.channel_error_after)
        staircase.append(
            {
                "effects": list(selected),
                "parameters": {n: dict(v) for n, v in best.model_values.items()},
                "error": best.error_after,
                "heldout_error": best.heldout_error_after,
                "channel_error": best.channel_error_after,
                "delta_bic": best.delta_bic,
            }
        )

    # Closed-loop effects, on top of the physics selected.
    physics_values = dict(base_fit.values)
    loop_cands: list[Candidate] = []
    if loop_names:
        ev.inject_noise(base_fit.evaluations)
        loop_base = fit_effects(
            ev,
            list(base_fit.effects),
            start=physics_values,
            fixed=physics_values,
            stage="closed_loop",
        )
        ev.calibrate_closed_loop(loop_base.evaluations)
        loop_base = fit_effects(
            ev,
            list(base_fit.effects),
            start=physics_values,
            fixed=physics_values,
            stage="closed_loop",
        )
        loop_error = _velocity_error(loop_base.evaluations)
        for n in loop_names:
            effect = get_effect(n)
            names_n = [*base_fit.effects, n]
            fit = fit_effects(
                ev,
                names_n,
                start={**physics_values, n: effect.start(scale)},
                fixed=physics_values,
                stage="closed_loop",
            )
            dbic = delta_bic(loop_base, fit)
            held = (
                _heldout(
                    ev,
                    loop_base.evaluations,
                    names_n,
                    fit.values,
                    "closed_loop",
                    fixed=physics_values,
                )
                if dbic > BIC_THRESHOLD
                else HeldOut(math.nan, math.nan, [])
            )
            err_after = _velocity_error(fit.evaluations)
            significant = bool(
                dbic > BIC_THRESHOLD
                and not fit.failed
                and (len(data) < 2 or (math.isfinite(held.z) and held.z > Z_THRESHOLD))
            )
            loop_cands.append(
                Candidate(
                    effect=n,
                    stage="closed_loop",
                    parameters=dict(fit.values[n]),
                    model=names_n,
                    model_values={k: dict(v) for k, v in fit.values.items()},
                    error_before=loop_error[0],
                    error_after=err_after[0],
                    heldout_error_after=math.nan,
                    delta_bic=dbic,
                    heldout_z=held.z,
                    significant=significant,
                    channel_error_before=loop_error[1],
                    channel_error_after=err_after[1],
                    nfev=fit.nfev,
                    notes=["closed loop: errors are v_des RMS in m/s"],
                    fit=fit,
                )
            )
        _rank(loop_cands)
        _mark_lookalikes(loop_cands)
        for c in loop_cands:
            if c.significant and len(selected) < max_effects:
                selected.append(c.effect)
                physics_values[c.effect] = dict(c.parameters)
                staircase.append(
                    {
                        "effects": list(selected),
                        "parameters": {n: dict(v) for n, v in physics_values.items()},
                        "error": staircase[-1]["error"],
                        "heldout_error": staircase[-1]["heldout_error"],
                        "channel_error": {
                            **staircase[-1]["channel_error"],
                            **c.channel_error_after,
                        },
                        "delta_bic": c.delta_bic,
                        "stage": "closed_loop",
                    }
                )
                break
    selected_values = {n: dict(physics_values[n]) for n in selected}
    verdict = selected[0] if selected else "none"

    # Look-alikes of the verdict: what run would separate them.
    first = rounds[0] if rounds else []
    if separate:
        for c in first + loop_cands:
            if c.effect == verdict and c.indistinguishable_from:
                spec_a = _model_spec([c.effect], {c.effect: c.parameters}, scale)
                for other in c.indistinguishable_from:
                    o = next(x for x in first + loop_cands if x.effect == other)
                    spec_b = _model_spec([o.effect], {o.effect: o.parameters}, scale)
                    sep = separating_run(ev, spec_a, spec_b)
                    if sep is not None:
                        sep["effects"] = [c.effect, o.effect]
                        hint = get_effect(o.effect).separation_hint
                        sep["hint"] = hint
                        o.separation = sep
                        c.separation = c.separation or sep

    final_spec = _model_spec(selected, selected_values, scale)
    final = {i: ev.evaluate(final_spec, i) for i in range(len(data))}
    closed = {
        "before": _closed_loop_summary(ev, ModelSpec()),
        "after": _closed_loop_summary(ev, final_spec),
    }
    notes = []
    if len(data) < 2:
        notes.append("one run: significance from the BIC alone (no held-out run)")
    return Diagnosis(
        data=data,
        scale=scale,
        verdict=verdict,
        selected=selected,
        selected_values=selected_values,
        rounds=rounds,
        staircase=staircase,
        closed_loop_candidates=loop_cands,
        nominal=nominal.evaluations,
        final=final,
        closed_loop=closed,
        simulations=ev.simulations,
        wall_time_s=time.perf_counter() - t0,
        notes=notes,
    )


def fit_effect(
    runs: Sequence[Run],
    name: str,
    given: Mapping[str, float] | None = None,
    accuracy: float = FIT_ACCURACY,
) -> dict[str, float]:
    """Values of effect ``name`` fitted to ``runs`` (the ``given`` ones held).

    A replay effect is fitted on the replay, a closed-loop effect on the
    closed loop's spacecraft velocity.
    """
    effect = get_effect(name)
    data = prepare_runs(runs)
    scale = RigScale.from_runs(runs)
    checked = effect.check_values(given or {}, scale)
    given = {k: checked[k] for k in (given or {})}
    ev = Evaluator(data, scale, accuracy)
    fixed = {name: dict(given)} if given else None
    if effect.stage == "closed_loop":
        ev.inject_noise(fit_effects(ev, []).evaluations)
        base = fit_effects(ev, [], stage="closed_loop")
        ev.calibrate_closed_loop(base.evaluations)
        fit = fit_effects(ev, [name], fixed=fixed, stage="closed_loop")
    else:
        base = fit_effects(ev, [])
        residuals = _residual_probe(data, base.evaluations)
        fit = fit_effects(ev, [name], fixed=fixed, starts=_starts_for(effect, scale, residuals))
    return dict(fit.values[name])
