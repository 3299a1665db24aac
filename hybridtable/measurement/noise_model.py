"""Noise models of a recorded run: AR(1) fits of detrended quiet segments and
prewhitening of residuals.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hybridtable.measurement.phases import contact_mask, delayed_labels, dilate, true_runs
from hybridtable.measurement.run_format import Run

__all__ = [
    "NoiseModel",
    "estimate_noise",
    "ar1_from_segments",
    "whiten",
]


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
    quiet = ~dilate(on, guard, guard)
    quiet_f = delayed_labels(quiet.astype(int), delay_ticks).astype(bool)
    quiet_f[: min(delay_ticks, len(quiet_f))] = True
    out: dict[str, NoiseModel] = {}
    f_noise = ar1_from_segments([run.f_mea_n[a : b + 1] for a, b in true_runs(quiet_f)], 0)
    if f_noise is not None:
        out["f_mea_n"] = f_noise
    quiet_p = ~dilate(on, guard, settle_ticks)
    quiet_p[: min(settle_ticks, len(quiet_p))] = False
    p_noise = ar1_from_segments([run.p_act_m[a : b + 1] for a, b in true_runs(quiet_p)], 1)
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
