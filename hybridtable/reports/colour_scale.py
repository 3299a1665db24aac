"""The colour scale of a metric's map: its norm and colour map, centred on the
level that separates gain from loss where the values cross it, with ticks on
both sides of that level, and whether a level crosses the values at all."""

from __future__ import annotations

import numpy as np

__all__ = ["colour_scale", "crosses", "ticks_both_sides"]


def colour_scale(
    values, level: float | None = None, higher_worse: bool = True, fraction: bool = False
):
    """``(norm, cmap)`` for ``values``: a fraction on [0, 1] (red to green);
    centred on ``level`` (blue to red, red the worse side) when the values
    cross it; else their range (viridis)."""
    from matplotlib.colors import Normalize, TwoSlopeNorm

    if fraction:
        return Normalize(0.0, 1.0), "RdYlGn"
    lo, hi = float(values.min()), float(values.max())
    if lo == hi:
        lo, hi = lo - (abs(lo) * 1e-3 or 1e-3), hi + (abs(hi) * 1e-3 or 1e-3)
    if level is not None and lo < level < hi:
        return TwoSlopeNorm(level, lo, hi), "RdBu_r" if higher_worse else "RdBu"
    return Normalize(lo, hi), "viridis"


def ticks_both_sides(bar, norm) -> None:
    """Ticks on both sides of a centred colour bar's level: matplotlib's own put
    them all on the longer side (a CoR map from 0.99 to 1.16 had none above 1.000)."""
    if hasattr(norm, "vcenter"):  # TwoSlopeNorm
        low = np.linspace(norm.vmin, norm.vcenter, 3)
        high = np.linspace(norm.vcenter, norm.vmax, 3)
        bar.set_ticks(np.unique(np.r_[low, high]))


def crosses(level: float | None, values) -> bool:
    """True when finite ``values`` lie on both sides of ``level``."""
    v = np.asarray(values)[np.isfinite(values)]
    return level is not None and v.size > 0 and v.min() < level < v.max()
