"""The one search for a critical sensor delay: the smallest delay at which a
figure of the loop crosses a limit.

Every delay limit the library reports is this search with its own figure:

- the **critical sensor delay** of a 1-D model (:func:`~hybridtable.analysis.
  margins.critical_sensor_delay`): the growth rate of the right-most pole;
- the **CoR-limited delay** (:func:`~hybridtable.analysis.robustness.
  cor_limited_delay`): the predicted CoR minus its limit;
- the **6-DoF loop's critical delay** (:func:`~hybridtable.six_dof.linear.
  critical_delay_s`): the growth rate of its fastest mode.

A rig computer that samples every ``h`` seconds reads a delay between two
ticks as the two neighbouring samples mixed (:func:`hybridtable.systems.sensor.
sample_taps`), so a sampled loop's figures are continuous in the delay: the
scan runs over whole ticks (where the tap mix is exact) and the tick of the
first crossing is refined like a continuous bracket.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

__all__ = ["critical_delay", "first_crossing_delay"]


def critical_delay(
    excess: Callable[[float], float],
    max_delay_s: float,
    sample_period_s: float | None = None,
    scan_points: int = 33,
    tolerance: float = 0.0,
) -> float:
    """Smallest sensor delay ``T`` [s] in ``[0, max_delay_s]`` at which
    ``excess(T)`` reaches the limit: 0 when already at zero delay, ``inf``
    when nowhere.

    ``excess(T)`` is a figure of the loop at delay ``T`` minus its limit (NaN:
    beyond the limit); ``excess(T) > -tolerance`` counts as reached (a
    neutral pole within round-off is not a stable one). The scan of
    :func:`first_crossing_delay` brackets the first such delay; Brent's method
    refines ``excess = 0`` in it to 1e-12 s. With no sign change to refine
    (the far end within the tolerance band, or a figure not finite at an end)
    the answer is an end: the far end when it is neutral, else the last delay
    known within the limit. A window beyond the limit narrower than a scan
    step can be missed.
    """
    seen: dict[float, float] = {}  # the scan's delays, met again at the bracket's ends

    def f(T: float) -> float:
        if T not in seen:
            x = float(excess(T))
            seen[T] = math.inf if math.isnan(x) else x
        return seen[T]

    def reached(T: float) -> bool:
        return f(T) > -tolerance

    if reached(0.0):
        return 0.0
    bracket = first_crossing_delay(reached, max_delay_s, sample_period_s, scan_points)
    if bracket is None:
        return math.inf
    within, beyond = bracket
    if not (math.isfinite(f(within)) and math.isfinite(f(beyond))):
        return within
    if f(beyond) <= 0.0:
        return beyond  # neutral within the tolerance: no crossing to refine
    return float(brentq(f, within, beyond, xtol=1e-12, rtol=1e-10))


def first_crossing_delay(
    crossed: Callable[[float], bool],
    max_delay_s: float,
    sample_period_s: float | None = None,
    scan_points: int = 33,
) -> tuple[float, float] | None:
    """The first sensor delay bracket ``(a, b)`` [s] with ``crossed(a)`` false and
    ``crossed(b)`` true, scanning from 0 (not crossed there) to ``max_delay_s``,
    or None. A sampled loop (``sample_period_s``) is scanned over whole
    samples, every ``max_delay / scan_points`` samples and then sample by sample,
    so ``b - a`` is one sample; a continuous one over ``scan_points`` delays (the
    caller refines the bracket). A window narrower than a scan step can be
    missed."""
    h = sample_period_s
    if h is not None:
        n_max = max(1, math.floor(max_delay_s / h + 1e-9))
        step = max(1, n_max // (scan_points - 1))
        prev = 0
        for n in [*range(step, n_max + 1, step), n_max]:
            if crossed(n * h):
                for k in range(prev + 1, n + 1):
                    if crossed(k * h):
                        return (k - 1) * h, k * h
            prev = n
        return None
    prev_t = 0.0
    for t in np.linspace(0.0, max_delay_s, scan_points)[1:]:
        if crossed(float(t)):
            return prev_t, float(t)
        prev_t = float(t)
    return None
