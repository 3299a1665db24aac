"""Noise models of a recorded run: autoregressive fits of detrended quiet
segments (AR(1), or AR(p) up to :data:`MAX_AR_ORDER` where the data demand it)
and prewhitening of residuals.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hybridtable.measurement.phases import contact_mask, delayed_labels, dilate, true_runs
from hybridtable.measurement.run_format import Run

__all__ = [
    "MAX_AR_ORDER",
    "NoiseModel",
    "estimate_noise",
    "run_noise",
    "is_coloured",
    "third_difference_gain",
    "ar1_from_segments",
    "ar_from_segments",
    "whiten",
]


#: Highest order of an autoregressive noise model (AR(2) covers a resonant
#: coloured noise; the order is chosen by BIC, AR(1) unless the data demand more).
MAX_AR_ORDER = 3


# -- noise ---------------------------------------------------------------------
@dataclass(frozen=True)
class NoiseModel:
    """Autoregressive noise of a channel.

    AR(1) (``ar`` empty): ``e[k] = phi e[k-1] + sigma sqrt(1 - phi^2) xi[k]``.
    AR(p): ``e[k] = sum_j ar[j-1] e[k-j] + innovation``, ``phi`` its lag-1
    autocorrelation. ``sigma`` is the marginal standard deviation (the noise
    RMS), ``samples`` the ticks the estimate used.
    """

    sigma: float
    phi: float
    samples: int
    ar: tuple[float, ...] = ()

    @property
    def order(self) -> int:
        return len(self.ar) if self.ar else 1

    @property
    def coefficients(self) -> tuple[float, ...]:
        """The AR coefficients ``a_1 .. a_p``."""
        return tuple(self.ar) if self.ar else (self.phi,)

    @property
    def innovation_sigma(self) -> float:
        if not self.ar:
            return self.sigma * math.sqrt(1.0 - self.phi * self.phi)
        return self.sigma * math.sqrt(_levinson(_ar_acf(self.ar))[1][-1])

    def describe(self) -> str:
        """``"AR(1) +0.70"`` or ``"AR(2) +1.20 -0.50"``."""
        return f"AR({self.order}) " + " ".join(f"{a:+.2f}" for a in self.coefficients)


def _ar_acf(a: Sequence[float]) -> np.ndarray:
    """Autocorrelations ``rho_0 .. rho_p`` of a stationary AR(p) (Yule-Walker solved for rho)."""
    a = np.asarray(a, dtype=float)
    p = len(a)
    # rho_k = sum_j a_j rho_|k-j| for k = 1..p, rho_0 = 1.
    m = np.eye(p)
    rhs = np.zeros(p)
    for k in range(1, p + 1):
        for j in range(1, p + 1):
            lag = abs(k - j)
            if lag == 0:
                rhs[k - 1] += a[j - 1]
            else:
                m[k - 1, lag - 1] -= a[j - 1]
    rho = np.linalg.solve(m, rhs)
    return np.concatenate([[1.0], rho])


def _levinson(rho: np.ndarray) -> tuple[list[np.ndarray], list[float]]:
    """Levinson-Durbin: the order-k predictors (k = 0..p) of a process with
    autocorrelations ``rho`` and their prediction-error variances (over the
    marginal variance)."""
    p = len(rho) - 1
    preds = [np.zeros(0)]
    var = [1.0]
    a = np.zeros(0)
    v = 1.0
    for k in range(1, p + 1):
        acc = rho[k] - (a @ rho[1:k][::-1] if k > 1 else 0.0)
        kappa = acc / v
        a = np.concatenate([a - kappa * a[::-1], [kappa]])
        v = v * (1.0 - kappa * kappa)
        preds.append(a.copy())
        var.append(max(v, 1e-12))
    return preds, var


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


def _detrended(
    segments: Sequence[np.ndarray],
    degree: int,
    regressors: Sequence[np.ndarray | None] | None = None,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each segment long enough (``degree + 5`` samples, and 4 more than its
    trend's columns) without its least-squares trend, with the trend's
    orthonormal basis: a polynomial of ``degree``, and the segment's
    ``regressors`` (columns, or None) where given."""
    q = degree + 1
    out = []
    for i, seg in enumerate(segments):
        seg = np.asarray(seg, dtype=float)
        extra = regressors[i] if regressors is not None else None
        width = q if extra is None else q + extra.shape[1]
        if len(seg) < max(q, width) + 4:
            continue
        t = np.linspace(-1.0, 1.0, len(seg))
        trend = np.vander(t, q, increasing=True)
        if extra is not None:
            trend = np.column_stack([trend, extra])
        basis, _ = np.linalg.qr(trend)
        out.append((seg - basis @ (basis.T @ seg), basis))
    return out


def ar1_from_segments(
    segments: Sequence[np.ndarray],
    degree: int,
    regressors: Sequence[np.ndarray | None] | None = None,
) -> NoiseModel | None:
    """AR(1) noise of segments that hold noise plus a polynomial of ``degree``.

    Each segment's polynomial trend is removed; the pooled lag-1
    autocorrelation is corrected for the bias of short detrended segments
    (``E[phi_hat] ~ phi - (q + (q + 2) phi) / n``, ``q = degree + 1``), and
    the variance for the noise the trend removes:
    ``E[sum x^2] = sigma^2 sum_s (n_s - trace(Q_s' R(phi) Q_s))`` with ``Q_s``
    an orthonormal basis of the trend and ``R`` the AR(1) correlation. A
    segment's ``regressors`` (columns, or None) join its trend (with ``q``
    then its trend's columns).
    Returns None with fewer than 20 degrees of freedom.
    """
    s0 = s1 = 0.0
    kept = []
    for x, basis in _detrended(segments, degree, regressors):
        s0 += float(x @ x)
        s1 += float(x[1:] @ x[:-1])
        kept.append(basis)
    total = sum(len(b) for b in kept)
    kq = sum(b.shape[1] for b in kept)  # trend columns, summed over the segments
    if total - kq < 20:
        return None
    if not s0 > 0.0:  # a noise-free record
        return NoiseModel(0.0, 0.0, total)
    phi_hat = s1 / s0
    phi = (phi_hat + kq / total) / (1.0 - (kq + 2 * len(kept)) / total)
    phi = float(np.clip(phi, -0.95, 0.98))
    dof = sum(len(b) - float(np.trace(b.T @ _ar1_apply(b, phi))) for b in kept)
    dof = max(dof, 0.25 * total)
    return NoiseModel(math.sqrt(s0 / dof), phi, total)


def ar_from_segments(
    segments: Sequence[np.ndarray],
    degree: int,
    max_order: int = MAX_AR_ORDER,
    regressors: Sequence[np.ndarray | None] | None = None,
) -> NoiseModel | None:
    """AR(p) noise of segments holding noise plus a polynomial of ``degree``,
    the order ``p <= max_order`` chosen by BIC over the pooled conditional
    least-squares fits of the detrended segments.

    AR(1) is :func:`ar1_from_segments` (its bias corrections); a higher order
    is kept only if its BIC is lower, with coefficients from the least squares
    and the marginal variance ``sum x^2 / (N - q S)`` (``S`` segments).
    Returns None with fewer than 20 degrees of freedom.
    """
    base = ar1_from_segments(segments, degree, regressors)
    if base is None or base.sigma == 0.0 or max_order < 2:
        return base
    detrended = _detrended(segments, degree, regressors)
    xs = [x for x, _ in detrended]
    kq = sum(b.shape[1] for _, b in detrended)
    best: tuple[float, int, np.ndarray] | None = None
    for p in range(1, max_order + 1):
        rows, target = [], []
        for x in xs:
            if len(x) <= p + 2:
                continue
            rows.append(np.column_stack([x[p - j : len(x) - j] for j in range(1, p + 1)]))
            target.append(x[p:])
        if not rows:
            break
        a_mat, y = np.vstack(rows), np.concatenate(target)
        if len(y) < 20 + p:
            break
        coef, *_ = np.linalg.lstsq(a_mat, y, rcond=None)
        r = y - a_mat @ coef
        n = len(y)
        bic = n * math.log(max(float(r @ r), 1e-300) / n) + p * math.log(n)
        if best is None or bic < best[0] - 1e-9:
            best = (bic, p, coef)
    if best is None or best[1] == 1:
        return base
    coef = best[2]
    roots = np.roots(np.concatenate([[1.0], -coef]))
    if np.any(np.abs(roots) >= 0.99):
        return base
    total = sum(len(x) for x in xs)
    s0 = sum(float(x @ x) for x in xs)
    sigma = math.sqrt(s0 / max(total - kq, 0.25 * total))
    rho1 = float(_ar_acf(coef)[1])
    return NoiseModel(sigma, rho1, total, tuple(float(c) for c in coef))


def estimate_noise(run: Run, delay_ticks: int, settle_ticks: int) -> dict[str, NoiseModel]:
    """Model-free autoregressive noise of ``f_mea`` and ``p_act`` from the
    no-contact ticks (:func:`ar_from_segments`).

    ``f_mea``: the true force is zero away from contact (2 ticks of guard,
    the readings shifted by the sensor delay), so the readings about each
    segment's mean are noise (an offset is model error, not noise); a
    stretch after a contact starts where its readings have fallen into the
    noise (:func:`_past_the_tail`: a sensor's filter rings on).
    ``p_act``: away from contact, after ``settle_ticks`` (the start and the
    end of each contact), the table tracks the command's ramp with a
    constant lag, sampled once per tick: the residuals of a straight line
    fitted to each segment are the noise (:func:`ar1_from_segments`). Where
    the command is no straight line there (the model kicked by the noise
    that a deadband lets through), the command and the model's velocity
    join the line (:func:`_command_regressors`).
    """
    on = contact_mask(run.p_act_m)
    guard = 2
    quiet = ~dilate(on, guard, guard)
    quiet_f = delayed_labels(quiet.astype(int), delay_ticks).astype(bool)
    quiet_f[: min(delay_ticks, len(quiet_f))] = True
    out: dict[str, NoiseModel] = {}
    f_noise = ar_from_segments(
        [_past_the_tail(run.f_mea_n[a : b + 1], a > 0) for a, b in true_runs(quiet_f)], 0
    )
    if f_noise is not None:
        out["f_mea_n"] = f_noise
    quiet_p = ~dilate(on, guard, settle_ticks)
    quiet_p[: min(settle_ticks, len(quiet_p))] = False
    spans = true_runs(quiet_p)
    p_noise = ar_from_segments(
        [run.p_act_m[a : b + 1] for a, b in spans],
        1,
        regressors=[_command_regressors(run, a, b) for a, b in spans],
    )
    if p_noise is not None:
        out["p_act_m"] = p_noise
    return out


#: A stretch after a contact starts where the median of the next
#: :data:`_TAIL_WINDOW` readings is within this many robust noise levels of the
#: stretch's median.
_TAIL_LEVELS = 0.5
_TAIL_WINDOW = 11


def _past_the_tail(x: np.ndarray, after_contact: bool) -> np.ndarray:
    """A quiet stretch of force readings from where they have settled into
    the noise on, if it follows a contact: a sensor's filter (or a slow
    release of the contact) holds the reading above the noise for a while
    after the contact, which no guard of fixed ticks covers. The stretch
    starts where the median of the next :data:`_TAIL_WINDOW` readings is
    within :data:`_TAIL_LEVELS` robust noise levels of the stretch's median.
    Unchanged where the first readings hold no tail (their median within
    four of its standard errors), or the stretch does not follow a contact."""
    w = _TAIL_WINDOW
    if not after_contact or len(x) < 4 * w:
        return x
    mid = float(np.median(x))
    level = 1.4826 * float(np.median(np.abs(x - mid)))
    if not level > 0.0:
        return x
    ahead = np.median(np.lib.stride_tricks.sliding_window_view(x, w), axis=1)
    # no tail: the first readings' median within 4 of its standard errors
    # (1.2533 level / sqrt(w) for a noise) leaves the stretch whole
    if abs(ahead[0] - mid) <= 4.0 * 1.2533 * level / math.sqrt(w):
        return x
    settled = np.flatnonzero(np.abs(ahead - mid) <= _TAIL_LEVELS * level)
    start = int(settled[0]) if settled.size else 0
    return x[start:] if start < len(x) - 2 * w else x


#: A quiet segment's command counts as a straight line when it departs from
#: one by less than this fraction of the table's noise about a line.
_STRAIGHT = 0.1


def _command_regressors(run: Run, a: int, b: int) -> np.ndarray | None:
    """Columns that join the straight line of ``p_act``'s trend over ticks
    ``a..b`` where the command is not a straight line there: the command
    ``p_des`` and the model's velocity ``v_des`` (the table tracks them, to
    first order, with a constant lag). That is where the computer's model
    moved under a force in free flight (a deadband that lets the sensor's
    noise through: the noise kicks the model's velocity); ``None`` where the
    command is straight (the table's own noise about a line is then the
    estimate, as always)."""
    n = b - a + 1
    if n < 10:
        return None
    t = np.arange(n, dtype=float)
    cmd = run.p_des_m[a : b + 1]
    act = run.p_act_m[a : b + 1]
    bend = cmd - np.polyval(np.polyfit(t, cmd, 1), t)
    spread = act - np.polyval(np.polyfit(t, act, 1), t)
    if not float(np.max(np.abs(bend))) > _STRAIGHT * float(np.std(spread)):
        return None
    return np.column_stack([bend, run.v_des_m_per_s[a : b + 1]])


def run_noise(
    run: Run, delay_ticks: int, settle_ticks: int
) -> tuple[dict[str, NoiseModel], list[str]]:
    """The noise of a recorded run as ``compare`` and ``diagnose`` both use it:
    :func:`estimate_noise`, and where the record has no quiet stretch of a
    settled table, ``p_act``'s noise from stretches where it may not have
    settled, else from third differences of the whole record (white), each
    said in the notes. ``f_mea_n`` is missing if fewer than 20 ticks are
    without contact."""
    noise = estimate_noise(run, delay_ticks, settle_ticks)
    notes: list[str] = []
    if "p_act_m" not in noise:
        p_noise = estimate_noise(run, delay_ticks, 2).get("p_act_m")
        if p_noise is not None:
            noise["p_act_m"] = p_noise
            notes.append("p_act noise from stretches where the table may not have settled")
        else:
            third = np.diff(run.p_act_m, 3)
            noise["p_act_m"] = NoiseModel(float(np.std(third)) / math.sqrt(20.0), 0.0, len(third))
            notes.append("p_act noise from third differences of the whole record")
    return noise, notes


#: Fewest samples from which a noise's colour is told: on shorter quiet
#: stretches (the events of a long log) what a straight line leaves of the
#: table's settling motion reads as correlation.
MIN_COLOUR_SAMPLES = 200


def is_coloured(noise: NoiseModel) -> bool:
    """True if the noise's lag-1 correlation is significant (beyond 2.58
    standard errors of a white noise's, ``1 / sqrt(N)``: 1 %) on at least
    :data:`MIN_COLOUR_SAMPLES` samples."""
    n = noise.samples
    return n >= MIN_COLOUR_SAMPLES and abs(noise.phi) > 2.58 / math.sqrt(n)


def third_difference_gain(noise: NoiseModel) -> float:
    """``E[(d3 e)^2] / (20 sigma^2)`` of the noise: how much more (or less) of
    its variance third differences see than of a white noise's (1 for white
    noise; ``20 - 30 rho_1 + 12 rho_2 - 2 rho_3`` over 20 for correlations
    ``rho_k``)."""
    a = list(noise.coefficients)
    rho = list(_ar_acf(a))
    while len(rho) < 4:
        k = len(rho)
        rho.append(sum(a[j] * rho[k - 1 - j] for j in range(len(a))))
    return (20.0 - 30.0 * rho[1] + 12.0 * rho[2] - 2.0 * rho[3]) / 20.0


def whiten(e: np.ndarray, noise: NoiseModel) -> np.ndarray:
    """Innovations of an autoregressive residual over their standard deviation
    (unit-variance white noise if ``e`` is the noise). The first ``p`` samples
    of an AR(p) use the exact lower-order predictors (Levinson-Durbin)."""
    e = np.asarray(e, dtype=float)
    if noise.ar:
        a = np.asarray(noise.ar, dtype=float)
        p = len(a)
        preds, var = _levinson(_ar_acf(a))
        w = e.copy()
        for j in range(1, p + 1):
            w[p:] -= a[j - 1] * e[p - j : len(e) - j]
        for k in range(min(p, len(e))):
            pk = preds[k]
            w[k] = (e[k] - (pk @ e[:k][::-1] if k else 0.0)) * math.sqrt(var[-1] / var[k])
        return w / noise.innovation_sigma
    phi = noise.phi
    w = np.empty_like(e)
    w[0] = e[0] * math.sqrt(1.0 - phi * phi)
    w[1:] = e[1:] - phi * e[:-1]
    return w / noise.innovation_sigma
