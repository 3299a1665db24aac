"""The arithmetic an audit of a rig computer's record solves with: least
squares to the CSV's precision, and the test of a stated law against logged
readings the computer did not see.

Both audits (:mod:`hybridtable.measurement.audit`, 1-D;
:mod:`hybridtable.six_dof.audit_law6`, the wrench) solve the compensation
law's constants by :func:`linear_fit` on the law's own terms. A log whose
readings carry noise the computer did not see (a logger of its own; the
formats log what the computer read) leaves a residual no constant removes,
and a fit on such readings is biased (errors in variables); then only the
stated law is tested, over means of blocks of ticks (:func:`stated_law_levels`).
"""

from __future__ import annotations

import math

import numpy as np

from hybridtable.measurement.channels import noise_level_of_differences

__all__ = [
    "NOISE_LEVELS",
    "block_means",
    "block_ticks",
    "deadband_bounds",
    "deadband_used",
    "linear_fit",
    "reading_noise",
    "stated_law_levels",
]

#: A stated law's misfit within this many noise levels of logged readings the
#: computer did not see (:func:`stated_law_levels`) is their noise, not another
#: law. With the readings' noise from every tick of a record (hundreds), the
#: stated law of 40 seeds of the independent 6-DoF generator's logger noise
#: reached at most 1.5 (about 27 blocks a component; chi2's 99.9 % point for 8
#: blocks is 1.8).
NOISE_LEVELS = 3.0


def linear_fit(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Least squares ``y ~ x @ c``: coefficients, standard errors (the residual's
    variance not below the CSV's rounding, 1e-10 of ``y``), residual RMS."""
    c, *_ = np.linalg.lstsq(x, y, rcond=None)
    r = y - x @ c
    n, p = x.shape
    dof = max(n - p, 1)
    s2 = float(r @ r) / dof
    # Rounding of the CSV (about 1e-10 relative) bounds the resolution.
    s2 = max(s2, (1e-10 * float(np.max(np.abs(y)) if y.size else 0.0)) ** 2)
    try:
        cov = s2 * np.linalg.inv(x.T @ x)
        se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        se = np.full(p, math.inf)
    return c, se, math.sqrt(float(r @ r) / max(n, 1))


def block_ticks(rows: int) -> int:
    """The ticks of a block of :func:`stated_law_levels` for ``rows`` ticks with a
    force: 4 to 25 ticks, at least eight blocks where there are enough (the
    lead's share of the readings' noise in a mean falls as ``1 / m``)."""
    return int(np.clip(rows // 8, 4, 25))


def block_means(a: np.ndarray, rows: np.ndarray, m: int) -> np.ndarray:
    """Means of ``a``'s ``rows`` over blocks of ``m`` consecutive ones (a law
    linear with constant constants holds for the means too)."""
    idx = np.flatnonzero(rows)
    out = []
    for seg in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
        n = len(seg) // m
        if n:
            out.append(a[seg[: n * m]].reshape(n, m, *a.shape[1:]).mean(axis=1))
    return np.concatenate(out) if out else np.zeros((0, *a.shape[1:]))


def stated_law_levels(
    misfit: np.ndarray,
    rows: np.ndarray,
    var_reading: np.ndarray,
    var_motion: np.ndarray,
    lead_ticks: float,
    m: int,
) -> np.ndarray:
    """The stated law's misfit (ticks x components) over means of blocks of
    ``m`` of its ``rows`` (:func:`block_means`, :func:`block_ticks`), per component in noise levels of what
    logged readings the computer did not see carry into those means: the
    reading's ``var_reading`` (per component) through ``a n + T_lead (n_k -
    n_k-m) / (m h)`` (``lead_ticks = T_lead / h``) and the MDC term's
    ``var_motion`` (ticks x components). About 1 for such readings of the
    stated law; a wrong constant survives the means and the noise does not.
    A fit of the constants on such readings would be biased (errors in
    variables), so only the stated law is tested."""
    res = block_means(misfit, rows, m)
    if not len(res):
        return np.full(misfit.shape[1:], math.nan)
    # a mean of n_j + L (n_j - n_j-1) / h over m ticks: (1/m) sum n + (L / (m h)) (n_m - n_0)
    lead = lead_ticks
    noise = var_reading * (1.0 / m + 2.0 * (lead / m) ** 2 + 2.0 * lead / m**2)
    noise = noise + block_means(var_motion, rows, m) / m
    return np.sqrt(np.mean(res**2, axis=0) / np.maximum(np.mean(noise, axis=0), 1e-300))


def reading_noise(values: np.ndarray, before: int) -> tuple[np.ndarray, bool]:
    """The white-noise level of each column of logged readings (rows x
    columns), robust, from the second differences of every row (hundreds: a
    contact's force is smooth at a rig computer's rate and its kinks are few;
    a mount ringing at 40-150 Hz moved it by at most 0.7-1.3x on the test
    rigs), and whether the readings carry noise at all: white noise above
    1e-6 of the column's size in the ``before`` rows before the first touch
    (every row with fewer than 5), read from fourth differences, in which a
    smooth motion (a table settling) vanishes and white noise does not
    (finer is the round-off of a smooth motion, or a CSV's six digits).

    Noise the computer saw and a logger's own noise both count: where a
    record has both, the level is the two together, and a test against it
    is weaker than it could be (on the test rig a lead error's levels fell
    1.6x)."""
    values = np.asarray(values, dtype=float).reshape(len(values), -1)
    d2 = np.diff(values, n=2, axis=0)
    levels = np.array([noise_level_of_differences(c) for c in d2.T])
    # white noise, not a smooth motion (a table settling): fourth differences, in
    # which white noise grows (std sqrt(70) sigma) and a smooth motion shrinks
    d4 = np.diff(values[: before if before >= 5 else len(values)], n=4, axis=0)
    early = 1.4826 * np.median(np.abs(d4), axis=0) / math.sqrt(70.0) if len(d4) else 0.0
    size = np.maximum(np.max(np.abs(values), axis=0), 1e-300)
    return levels, bool(np.any(early > 1e-6 * size))


def deadband_bounds(
    level: np.ndarray, open_: np.ndarray, pending: np.ndarray, slack: float = 0.0
) -> tuple[float, float]:
    """Where a dead band on ``level`` lies, ``[lower, upper)``: above the
    levels of the ticks the law would compensate (``pending``) that got no
    compensation, at or below those of the ticks that got one (``open_``),
    each ``slack`` wider (the readings' noise the computer did not see)."""
    gated = pending & ~open_
    lower = float(np.max(level[gated])) - slack if gated.any() else -math.inf
    upper = float(np.min(level[open_])) + slack if open_.any() else math.inf
    return lower, upper


def deadband_used(lower: float, upper: float, stated: float) -> tuple[float, float] | None:
    """What the bounds ``[lower, upper)`` of :func:`deadband_bounds` say of a
    stated dead band: None where it lies within them; else the dead band
    used and its half-width (inf where a bound is open). With ``lower >=
    upper`` the readings gated are not a dead band at all: ``(lower, nan)``."""
    if lower >= upper:
        return lower, math.nan
    if lower <= stated < upper:
        return None
    if math.isfinite(lower) and math.isfinite(upper):
        return 0.5 * (lower + upper), 0.5 * (upper - lower)
    return (lower if math.isfinite(lower) else upper), math.inf
