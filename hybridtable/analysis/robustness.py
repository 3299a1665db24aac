"""Gain, phase and delay margins of the loop, and the delay a CoR limit allows.

**Where the loop is broken.** Every linear model of this package
(:class:`~hybridtable.analysis.linearize.LinearLoop`) is open at the
spacecraft model's force input: ``G`` maps the force applied to the spacecraft
model ``u`` (N) to the compensated force the rig computer feeds it ``y`` (N);
the rig closes ``u = y``. In python-control's negative-feedback convention the
loop transfer function is ``L = -G`` (closed loop ``1 + L = 0``). The
spacecraft model is a double integrator ``1 / (m s^2)`` right behind the
break, so

- the **gain margin** ``gm`` (:func:`control.stability_margins`) is the factor
  by which the force fed to the spacecraft model may be scaled before the loop
  reaches the stability boundary: a force-path gain error (a force-sensor
  calibration for the uncompensated loop), or, exactly, a spacecraft model
  ``gm`` times lighter (``m / gm``). For a stable loop ``gm > 1`` is head room;
  a ``gm < 1`` says the loop is stable only with the force path scaled below
  ``gm``. ``inf``: the phase never crosses -180 deg above ``w_con / 100``;
- the **phase margin** ``pm`` (deg) at the gain crossover ``w_gc`` nearest the
  ideal contact loop's crossover (the contact mode);
- the **delay margin** ``pm / w_gc`` (s, ``pm`` in rad): the extra pure delay
  of the whole force feedback path (not followed by any lead) that brings the
  loop to the stability boundary; negative: the lead the loop still lacks.

**Undamped contact.** With a perfect rig the loop is ``L = k / (m s^2)``: its
phase is -180 deg at every frequency, so ``pm = 0``, the delay margin is 0 and
no phase crossover is counted (``gm = inf``), yet every gain leaves the contact
poles on the imaginary axis, marginal (python-control finds no margin because
there is none to find). A real rig adds a net lag (``pm < 0``, the loop gains
energy at every gain) or a net lead (``pm > 0``); the useful figures are then the
predicted CoR and :func:`cor_limited_delay`, the delay up to which it stays
within a limit.

Closed forms (tested): for ``m s^2 + (c s + k) e^{-sT}`` (ideal table, no
compensator) ``w_gc`` solves ``m^2 w^4 = k^2 + c^2 w^2``, ``pm = atan(c w_gc /
k) - w_gc T`` and the delay margin is ``atan(c w_gc / k) / w_gc - T``, the
critical delay minus ``T``; undamped, ``pm = -w_con T`` and the delay margin is
``-T``. The gain margin is ``m w_pc^2 / |k + i c w_pc|`` at ``atan(c w_pc / k) =
w_pc T``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass

import control
import numpy as np

from hybridtable.analysis.critical import critical_delay
from hybridtable.analysis.linearize import LinearLoop
from hybridtable.analysis.margins import (
    contact_pole,
    contact_reference_frequency,
    continuous_poles,
    cor_from_pole,
    ideal_crossover_frequency,
)
from hybridtable.analysis.sweep import SweepResult
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "DEFAULT_COR_LIMIT",
    "BROKEN_AT",
    "GainDelayMargins",
    "gain_delay_margins",
    "predicted_cor_of",
    "cor_limited_delay",
    "cor_limited_delay_on_grid",
    "cor_limited_table_on_grid",
    "grid_cor_limits",
]

#: Default CoR limit of :func:`cor_limited_delay` (1 % velocity gain per contact).
DEFAULT_COR_LIMIT = 1.01

#: Where the loop is broken, in words (for reports and exported models).
BROKEN_AT = (
    "at the spacecraft model's force input: G maps the force applied to the spacecraft "
    "model (N) to the compensated force (N); the rig closes u = y, and L = -G"
)


@dataclass(frozen=True)
class GainDelayMargins:
    """Classical margins of ``L = -G`` (python-control's ``stability_margins``).

    Attributes
    ----------
    gain_margin : float
        Ratio (``inf``: no phase crossover above ``w_con / 100``).
    gain_margin_db : float
        ``20 log10(gain_margin)``, dB.
    phase_crossover_rad_per_s : float
        Frequency of that phase crossover, rad/s (NaN when none).
    phase_margin_deg : float
        At the gain crossover of the contact mode, deg (NaN when none).
    gain_crossover_rad_per_s : float
        That gain crossover, rad/s.
    delay_margin_s : float
        ``radians(phase_margin_deg) / gain_crossover_rad_per_s``, s.
    closed_loop_stable : bool
        Every closed-loop pole strictly in the left half plane (inside the
        unit circle when sampled); a marginal loop is not stable.
    """

    gain_margin: float
    gain_margin_db: float
    phase_crossover_rad_per_s: float
    phase_margin_deg: float
    gain_crossover_rad_per_s: float
    delay_margin_s: float
    closed_loop_stable: bool

    def to_dict(self) -> dict:
        return asdict(self)


def _margins_input(loop: LinearLoop, w_lo: float):
    """What ``stability_margins`` is given: the state-space ``L``, or for a
    sampled loop its response on a dense grid up to the Nyquist frequency (the
    polynomial method is ill-conditioned for a loop sampled far above the
    contact frequency)."""
    if not loop.is_discrete:
        return loop.loop_transfer()
    w_hi = math.pi / loop.dt * (1 - 1e-9)
    w = np.geomspace(w_lo, w_hi, 2001)
    return control.frd(-loop.transfer(np.exp(1j * w * loop.dt)), w)


def gain_delay_margins(loop: LinearLoop) -> GainDelayMargins:
    """Gain margin, phase margin, their crossovers and the delay margin of
    ``loop`` (see the module doc for what they mean).

    ``control.stability_margins(L, returnall=True, epsw=w_con / 100)``: phase
    crossovers below ``w_con / 100`` are left out (there the double integrator
    holds the phase at -180 deg and round-off makes crossings of no meaning).
    Of the phase crossovers, python-control's choice (gain margin nearest 1 in
    log); of the gain crossovers, the one nearest the ideal contact loop's,
    as :func:`~hybridtable.analysis.margins.phase_margin_at_contact` picks it.
    """
    w_con = contact_reference_frequency(loop.params)
    epsw = 0.01 * w_con
    with warnings.catch_warnings():
        # python-control warns when it falls back to its 'frd' method and on
        # divisions by zero at the double integrator; scipy on poor scaling.
        warnings.simplefilter("ignore")
        gm_all, pm_all, _, wpc_all, wgc_all, _ = control.stability_margins(
            _margins_input(loop, epsw), returnall=True, epsw=epsw
        )
    gm_all, wpc_all = np.atleast_1d(gm_all).astype(float), np.atleast_1d(wpc_all).astype(float)
    ok = np.isfinite(wpc_all) & (wpc_all >= epsw) & np.isfinite(gm_all) & (gm_all > 0)
    if ok.any():
        i = int(np.argmin(np.abs(np.log(gm_all[ok]))))
        gm, wpc = float(gm_all[ok][i]), float(wpc_all[ok][i])
    else:
        gm, wpc = math.inf, math.nan
    pm_all, wgc_all = np.atleast_1d(pm_all).astype(float), np.atleast_1d(wgc_all).astype(float)
    ok = np.isfinite(wgc_all) & (wgc_all > 0)
    if ok.any():
        w0 = ideal_crossover_frequency(loop.params)
        i = int(np.argmin(np.abs(np.log(wgc_all[ok] / w0))))
        pm, wgc = float(pm_all[ok][i]), float(wgc_all[ok][i])
        dm = math.radians(pm) / wgc
    else:
        pm = wgc = dm = math.nan
    poles = continuous_poles(loop.closed_loop_poles(), loop.dt)
    stable = bool(np.max(poles.real) < -1e-9 * w_con)
    return GainDelayMargins(
        gain_margin=gm,
        gain_margin_db=20.0 * math.log10(gm) if gm > 0 else -math.inf,
        phase_crossover_rad_per_s=wpc,
        phase_margin_deg=pm,
        gain_crossover_rad_per_s=wgc,
        delay_margin_s=dm,
        closed_loop_stable=stable,
    )


# -- the delay a CoR limit allows ----------------------------------------------------

CorFn = Callable[[HybridLoopParams], float]


def predicted_cor_of(model: Callable[[HybridLoopParams], LinearLoop]) -> CorFn:
    """``params -> predicted CoR`` of ``model(params)``'s contact pole."""

    def cor(params: HybridLoopParams) -> float:
        loop = model(params)
        ps = continuous_poles(loop.closed_loop_poles(), loop.dt)
        return cor_from_pole(contact_pole(ps, loop.params))

    return cor


def cor_limited_delay(
    cor: CorFn,
    params: HybridLoopParams,
    cor_limit: float = DEFAULT_COR_LIMIT,
    max_delay_s: float | None = None,
    scan_points: int = 33,
) -> float:
    """Largest sensor delay up to which the predicted CoR stays within
    ``cor_limit``, the rest of ``params`` fixed (the lead time follows the
    delay when ``params.lead_time_s`` is None), in s.

    ``cor(params)`` is the predicted CoR (e.g. :func:`predicted_cor_of`).
    Returns 0 when the limit is exceeded already at zero delay (or at the
    first delay of the scan's refinement), ``inf`` when the CoR stays within
    it up to ``max_delay_s`` (default: a quarter of the contact period). A
    sampled model is scanned over whole samples and refined within the tick
    of the first excess (between two ticks the sensor reads the neighbouring
    samples mixed). The scan of ``scan_points`` delays
    is refined with Brent's method at the first excess; a window narrower than
    a scan step can be missed. A NaN CoR counts as an excess.
    """
    if max_delay_s is None:
        max_delay_s = 0.25 / params.contact_frequency_hz
    return critical_delay(
        lambda T: cor(params.with_(sensor_delay_s=T)) - cor_limit,
        max_delay_s,
        params.sample_period_s,
        scan_points,
    )


def _first_excess(values: np.ndarray, limit: float) -> int | None:
    bad = ~(np.asarray(values, dtype=float) <= limit)  # NaN counts as an excess
    idx = np.flatnonzero(bad)
    return int(idx[0]) if idx.size else None


def cor_limited_delay_on_grid(
    delays_s: np.ndarray, cor: np.ndarray, cor_limit: float, interpolate: bool = True
) -> float:
    """:func:`cor_limited_delay` read off a grid: ``cor[i]`` the predicted CoR
    at ``delays_s[i]`` (increasing). Linear interpolation between the last
    delay within the limit and the first beyond it (``interpolate=False``: the
    last grid delay within it, for a sampled grid); 0 if the first grid delay
    exceeds it, ``inf`` if no grid delay does."""
    d = np.asarray(delays_s, dtype=float)
    c = np.asarray(cor, dtype=float)
    i = _first_excess(c, cor_limit)
    if i is None:
        return math.inf
    if i == 0:
        return 0.0
    if not interpolate or not math.isfinite(c[i]):
        return float(d[i - 1])
    return float(d[i - 1] + (cor_limit - c[i - 1]) / (c[i] - c[i - 1]) * (d[i] - d[i - 1]))


def cor_limited_table_on_grid(tables_hz: np.ndarray, cor: np.ndarray, cor_limit: float) -> float:
    """Lowest table response frequency above which the predicted CoR stays
    within ``cor_limit`` at every faster grid table, read off a grid
    (``cor[j]`` at ``tables_hz[j]``, increasing; ``inf`` allowed), Hz.

    Linear interpolation between the grid frequencies around the crossing;
    ``inf`` when even the fastest grid table exceeds the limit, 0 when no
    grid table does."""
    f = np.asarray(tables_hz, dtype=float)
    c = np.asarray(cor, dtype=float)
    i = _first_excess(c[::-1], cor_limit)
    if i is None:
        return 0.0
    if i == 0:
        return math.inf
    j = f.size - 1 - i  # the fastest table beyond the limit; j + 1 is within it
    lo, hi = f[j], f[j + 1]
    if not (math.isfinite(hi) and math.isfinite(c[j])):
        return float(hi)
    return float(lo + (cor_limit - c[j]) / (c[j + 1] - c[j]) * (hi - lo))


def grid_cor_limits(result: SweepResult, cor_limit: float) -> dict[str, dict[str, np.ndarray]]:
    """Per compensator, read off the grid: ``cor_limited_delay_s[j]`` (per
    table frequency, interpolated between grid delays, sampled or not; inf:
    within the limit over the whole grid) and
    ``cor_limited_table_hz[i]`` (per delay, the slowest table with the CoR
    within the limit at it and every faster grid table; 0: every grid table)."""
    out = {}
    d, f = result.sensor_delay_s, result.table_response_hz
    order_d, order_f = np.argsort(d), np.argsort(f)
    for c, cs in result.compensators.items():
        cor = cs.predicted_cor[np.ix_(order_d, order_f)]
        out[c] = {
            "cor_limited_delay_s": np.array(
                [cor_limited_delay_on_grid(d[order_d], cor[:, j], cor_limit) for j in range(f.size)]
            )[np.argsort(order_f)],
            "cor_limited_table_hz": np.array(
                [cor_limited_table_on_grid(f[order_f], cor[i, :], cor_limit) for i in range(d.size)]
            )[np.argsort(order_d)],
        }
    return out
