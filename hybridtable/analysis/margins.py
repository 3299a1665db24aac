"""Stability figures of a linear hybrid-loop model: contact pole, CoR, margins.

For one linear model (:class:`~hybridtable.analysis.linearize.LinearLoop`, continuous or
sampled):

- the **contact pole**: the closed-loop pole of the contact mode, the one
  nearest ``i w_con`` (``w_con = sqrt(k / m)``) in the log metric
  ``|ln(s / (i w_con))|``; a sampled model's z-plane pole is mapped to
  ``s = ln(z) / h``;
- its **damping ratio** ``zeta = -sigma / |s|`` and the **predicted CoR**
  ``exp(sigma pi / w_d)``: the velocity amplitude grows as ``exp(sigma t)``
  over the half period ``pi / w_d`` of a contact; the **energy growth per
  contact** ``CoR^2 - 1`` (kinetic energy out / in, minus one);
- the **phase margin at the contact crossover**: python-control's
  ``stability_margins`` of ``L = -G``, at the gain crossover nearest the
  crossover ``w_0`` of the ideal loop ``(k + c s) / (m s^2)``;
- the **effective delay** ``(atan(c w_gc / k) - PM) / w_gc``: the phase the rig
  (sensor, table, computer, compensator) takes from the ideal contact loop at
  the crossover, as a delay (negative: net lead);
- **critical sensor delay** and **critical table frequency**: where the loop's
  right-most pole crosses into the right half plane (``|z| = 1`` when
  sampled), by a scan and Brent's method on the pole's real part.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass

import control
import numpy as np
from scipy.optimize import brentq

from hybridtable.analysis.critical import critical_delay
from hybridtable.analysis.linearize import LinearLoop
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "LoopMargins",
    "contact_reference_frequency",
    "ideal_crossover_frequency",
    "continuous_poles",
    "contact_pole",
    "cor_from_pole",
    "damping_ratio",
    "growth_rate",
    "phase_margin_at_contact",
    "effective_delay",
    "loop_margins",
    "crossover_phase_margin",
    "growth_of",
    "critical_sensor_delay",
    "critical_table_frequency",
]


@dataclass(frozen=True)
class LoopMargins:
    """Stability figures of one linear loop model (SI units, see module doc).

    Attributes
    ----------
    contact_pole : complex
        Contact-mode pole in the s-plane (rad/s; ``ln(z) / h`` when sampled).
    damping_ratio : float
        ``-Re(s) / |s|`` of the contact pole (negative: growing).
    predicted_cor : float
        ``exp(sigma pi / w_d)``; 0 for an overdamped (real) contact mode.
    energy_growth_per_contact : float
        ``predicted_cor**2 - 1``.
    growth_rate_per_s : float
        Largest real part of all closed-loop poles (s-plane equivalent).
    stable : bool
        Every closed-loop pole in the left half plane by more than
        ``1e-9 w_con`` (inside the unit circle when sampled): a marginal loop,
        e.g. an undamped contact with a perfect rig, is not stable.
    phase_margin_deg : float
        Phase margin at the contact crossover (NaN if no crossover).
    crossover_rad_per_s : float
        That gain-crossover frequency.
    effective_delay_s : float
        Phase the rig takes at the crossover, as a delay.
    """

    contact_pole: complex
    damping_ratio: float
    predicted_cor: float
    energy_growth_per_contact: float
    growth_rate_per_s: float
    stable: bool
    phase_margin_deg: float
    crossover_rad_per_s: float
    effective_delay_s: float

    def to_dict(self) -> dict:
        d = asdict(self)
        d["contact_pole"] = [self.contact_pole.real, self.contact_pole.imag]
        return d


def contact_reference_frequency(params: HybridLoopParams) -> float:
    """Undamped contact natural frequency ``sqrt(k / m)`` (rad/s)."""
    return math.sqrt(params.contact_stiffness_n_per_m / params.spacecraft_mass_kg)


def ideal_crossover_frequency(params: HybridLoopParams) -> float:
    """Gain crossover of the ideal loop ``(k + c s) / (m s^2)``:
    ``m^2 w^4 = k^2 + c^2 w^2``."""
    m, k, c = (
        params.spacecraft_mass_kg,
        params.contact_stiffness_n_per_m,
        params.contact_damping_n_s_per_m,
    )
    return math.sqrt((c * c + math.sqrt(c**4 + 4 * m * m * k * k)) / (2 * m * m))


def continuous_poles(poles: np.ndarray, dt: float) -> np.ndarray:
    """Poles as s-plane values: unchanged if ``dt == 0``, else ``ln(z) / dt``
    (poles at z = 0 map to ``-inf``)."""
    poles = np.asarray(poles, dtype=complex)
    if dt <= 0.0:
        return poles
    out = np.full(poles.shape, -np.inf + 0j)
    nz = np.abs(poles) > 0
    out[nz] = np.log(poles[nz]) / dt
    return out


def contact_pole(poles_s: np.ndarray, params: HybridLoopParams) -> complex:
    """The contact-mode pole among s-plane poles (see module doc); a real pole
    when the nearest candidate is real (overdamped contact)."""
    w = contact_reference_frequency(params)
    p = np.asarray(poles_s, dtype=complex)
    p = p[np.isfinite(p) & (p.imag >= 0) & (p != 0)]
    if p.size == 0:
        return complex("nan")
    dist = np.abs(np.log(p / (1j * w)))
    return complex(p[np.argmin(dist)])


def cor_from_pole(s: complex) -> float:
    """``exp(sigma pi / w_d)``; 0 for a real (overdamped) pole, NaN for NaN."""
    if not np.isfinite(s):
        return math.nan
    if s.imag <= 0.0:
        return 0.0
    return math.exp(s.real * math.pi / s.imag)


def damping_ratio(s: complex) -> float:
    """``-Re(s) / |s|``."""
    return -s.real / abs(s) if abs(s) > 0 else math.nan


def growth_rate(loop: LinearLoop, poles: np.ndarray | None = None) -> float:
    """Largest real part of the closed-loop poles (s-plane equivalent, 1/s)."""
    poles = loop.closed_loop_poles() if poles is None else poles
    return float(np.max(continuous_poles(poles, loop.dt).real))


def _loop_response(loop: LinearLoop, w: np.ndarray) -> np.ndarray:
    if w.size == 1:
        return np.array([-loop.response(float(w[0]))])
    pts = np.exp(1j * w * loop.dt) if loop.is_discrete else 1j * w
    return -loop.transfer(pts)


def phase_margin_at_contact(
    loop: LinearLoop, method: str = "python-control"
) -> tuple[float, float]:
    """Phase margin (deg) and frequency (rad/s) of the gain crossover nearest
    the ideal loop's crossover.

    Parameters
    ----------
    loop : LinearLoop
    method : {"python-control", "fast"}
        ``"python-control"``: ``control.stability_margins(L, returnall=True)``.
        ``"fast"``: the same crossover solved directly on the frequency
        response (bracketing and Brent's method), for sweeps; the two agree to
        solver tolerance (checked by the tests).

    Returns
    -------
    (phase_margin_deg, crossover_rad_per_s), NaN if ``|L| = 1`` has no
    solution near the contact crossover.
    """
    w0 = ideal_crossover_frequency(loop.params)
    if method == "python-control":
        L = loop.loop_transfer()
        if loop.is_discrete:
            # The polynomial method is ill-conditioned for a z-domain loop
            # sampled far above the contact frequency (python-control then
            # misses the crossover); give it the response on a dense grid.
            w_hi = min(8.0 * w0, math.pi / loop.dt * (1 - 1e-9))
            w = w0 * np.geomspace(0.125, w_hi / w0, 4001)
            L = control.frd(_loop_response(loop, w), w)
        with warnings.catch_warnings():
            # python-control falls back to its 'frd' method for discrete
            # loops and says so; scipy warns on badly scaled polynomials.
            warnings.simplefilter("ignore")
            _, pm, _, _, wgc, _ = control.stability_margins(L, returnall=True)
        pm, wgc = np.atleast_1d(pm), np.atleast_1d(wgc)
        ok = np.isfinite(wgc) & (wgc > 0)
        if not ok.any():
            return math.nan, math.nan
        i = int(np.argmin(np.abs(np.log(wgc[ok] / w0))))
        return float(pm[ok][i]), float(wgc[ok][i])
    if method != "fast":
        raise ValueError(f"unknown phase-margin method {method!r}")
    w_hi = 8.0 * w0
    if loop.is_discrete:
        w_hi = min(w_hi, math.pi / loop.dt * (1 - 1e-9))
    return crossover_phase_margin(lambda w: _loop_response(loop, w), w0, w_hi)


def crossover_phase_margin(
    response: Callable[[np.ndarray], np.ndarray], w0: float, w_hi: float | None = None
) -> tuple[float, float]:
    """Phase margin (deg) and frequency of the gain crossover of a loop
    frequency response ``L(w)`` (vectorized in ``w``, rad/s) nearest ``w0``:
    sign changes of ``ln|L|`` on a log grid over ``[w0 / 8, w_hi]``, refined
    with Brent's method. NaN if there is none."""
    w_hi = 8.0 * w0 if w_hi is None else w_hi
    w = w0 * np.geomspace(0.125, w_hi / w0, 25)
    g = np.log(np.abs(response(w)))
    idx = np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:]))
    if idx.size == 0:
        return math.nan, math.nan
    i = idx[np.argmin(np.abs(np.log(w[idx] / w0)))]

    def f(x: float) -> float:
        return math.log(abs(response(np.array([x]))[0]))

    a, b = float(w[i]), float(w[i + 1])
    fa, fb = f(a), f(b)
    if fa * fb < 0.0:
        wgc = brentq(f, a, b, xtol=1e-13 * w0, rtol=1e-13)
    else:  # a crossing at a grid point (|ln|L|| at round-off level)
        wgc = a if abs(fa) <= abs(fb) else b
    phase = math.degrees(np.angle(response(np.array([wgc]))[0]))
    pm = (phase + 180.0) % 360.0
    pm = pm - 360.0 if pm > 180.0 else pm
    return float(pm), float(wgc)


def effective_delay(params: HybridLoopParams, phase_margin_deg: float, wgc: float) -> float:
    """``(atan(c w / k) - PM) / w`` at the crossover ``w`` (see module doc)."""
    if not (math.isfinite(phase_margin_deg) and math.isfinite(wgc)):
        return math.nan
    ideal = math.atan(params.contact_damping_n_s_per_m * wgc / params.contact_stiffness_n_per_m)
    return (ideal - math.radians(phase_margin_deg)) / wgc


def loop_margins(loop: LinearLoop, pm_method: str = "python-control") -> LoopMargins:
    """All figures of :class:`LoopMargins` for one model."""
    poles = loop.closed_loop_poles()
    ps = continuous_poles(poles, loop.dt)
    s = contact_pole(ps, loop.params)
    cor = cor_from_pole(s)
    sigma = float(np.max(ps.real))
    pm, wgc = phase_margin_at_contact(loop, pm_method)
    return LoopMargins(
        contact_pole=s,
        damping_ratio=damping_ratio(s),
        predicted_cor=cor,
        energy_growth_per_contact=cor * cor - 1.0,
        growth_rate_per_s=sigma,
        stable=bool(sigma < -_tolerance(loop.params)),
        phase_margin_deg=pm,
        crossover_rad_per_s=wgc,
        effective_delay_s=effective_delay(loop.params, pm, wgc),
    )


# -- critical parameters -------------------------------------------------------

ModelFn = Callable[[HybridLoopParams], LinearLoop]
GrowthFn = Callable[[HybridLoopParams], float]


def growth_of(model: ModelFn) -> GrowthFn:
    """``params -> growth_rate(model(params))``, for the critical-parameter
    searches."""
    return lambda params: growth_rate(model(params))


def _tolerance(params: HybridLoopParams) -> float:
    return 1e-9 * contact_reference_frequency(params)


def critical_sensor_delay(
    growth: GrowthFn,
    params: HybridLoopParams,
    max_delay_s: float | None = None,
    scan_points: int = 33,
) -> float:
    """Smallest sensor delay at which the loop is unstable, the rest of
    ``params`` fixed (the lead time follows the delay when
    ``params.lead_time_s`` is None). ``growth(params)`` is the growth rate
    (largest pole real part, 1/s) of a model, e.g. ``growth_of(model)``.

    Returns 0 when the loop is not asymptotically stable at zero delay (e.g.
    an undamped contact), ``inf`` when it stays stable up to ``max_delay_s``
    (default: a quarter of the contact period). The search is
    :func:`~hybridtable.analysis.critical.critical_delay` on the growth rate
    (a sampled model: whole ticks scanned, the tick of the crossing refined);
    "unstable" is a growth rate above -1e-9 of the contact's reference
    frequency (round-off of a neutral pole counts as unstable).
    """
    if max_delay_s is None:
        max_delay_s = 0.25 / params.contact_frequency_hz
    return critical_delay(
        lambda T: growth(params.with_(sensor_delay_s=T)),
        max_delay_s,
        params.sample_period_s,
        scan_points,
        tolerance=_tolerance(params),
    )


def critical_table_frequency(
    growth: GrowthFn,
    params: HybridLoopParams,
    min_hz: float | None = None,
    max_hz: float | None = None,
    scan_points: int = 33,
) -> float:
    """Lowest table response frequency above which the loop is stable, the
    rest of ``params`` fixed.

    Returns ``inf`` when even an ideal table leaves the loop unstable, 0 when
    it is stable down to ``min_hz`` (default: the contact frequency / 2).
    The scan runs down from ``max_hz`` (default: 1000 x the contact
    frequency, or half the sample rate) on a log grid, then Brent's method.
    """
    f_con = params.contact_frequency_hz
    min_hz = 0.5 * f_con if min_hz is None else min_hz
    max_hz = 1000.0 * f_con if max_hz is None else max_hz
    if params.sample_rate_hz is not None:
        max_hz = min(max_hz, 0.5 * params.sample_rate_hz)
    tol = _tolerance(params)

    def sig(f: float) -> float:
        return growth(params.with_(table_response_hz=f))

    if sig(math.inf) > -tol:
        return math.inf
    fs = np.geomspace(max_hz, min_hz, scan_points)
    hi = fs[0]
    while sig(hi) > -tol:  # stable when ideal, not yet at max_hz: search higher
        if hi > 1e6 * max_hz or params.sample_rate_hz is not None:
            return math.inf
        lo, hi = hi, 10.0 * hi
        if sig(hi) <= -tol:
            return brentq(sig, lo, hi, xtol=1e-9 * lo, rtol=1e-10)
    prev = fs[0]
    for f in fs[1:]:
        if sig(f) > -tol:
            return brentq(sig, f, prev, xtol=1e-9 * f, rtol=1e-10)
        prev = f
    return 0.0
