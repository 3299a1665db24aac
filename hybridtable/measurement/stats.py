"""Error statistics of a residual: RMS, NRMSE and fit, the model-free noise floor
of force and position, and whiteness tests (auto- and cross-correlation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridtable.measurement.phases import true_runs

__all__ = [
    "CONFIDENCE_Z",
    "ChannelError",
    "Correlation",
    "channel_error",
    "force_noise_rms",
    "position_noise_rms",
    "correlation",
]


#: Two-sided 99 % point of the normal distribution (whiteness bands).
CONFIDENCE_Z = 2.5758293035489004


# -- basic error measures ------------------------------------------------------
@dataclass(frozen=True)
class ChannelError:
    """Error of a model channel against a measured one (unit of the channel)."""

    rms_error: float
    nrmse: float
    fit_percent: float
    mean_error: float
    max_abs_error: float

    def to_dict(self) -> dict[str, float]:
        return dict(self.__dict__)


def channel_error(measured: np.ndarray, model: np.ndarray) -> ChannelError:
    """RMS error, NRMSE, fit %, mean and largest error of ``model`` against ``measured``."""
    y = np.asarray(measured, dtype=float)
    e = y - np.asarray(model, dtype=float)
    spread = float(np.linalg.norm(y - y.mean()))
    nrmse = float(np.linalg.norm(e)) / spread if spread > 0.0 else math.inf
    return ChannelError(
        rms_error=float(np.sqrt(np.mean(e * e))),
        nrmse=nrmse,
        fit_percent=100.0 * (1.0 - nrmse),
        mean_error=float(e.mean()),
        max_abs_error=float(np.abs(e).max()),
    )


# -- noise floor ---------------------------------------------------------------
def force_noise_rms(f_mea_n: np.ndarray, quiet: np.ndarray) -> tuple[float, float, int]:
    """Noise RMS of a force reading from the ticks where the true force is zero.

    Returns the pooled standard deviation about each quiet segment's own mean,
    the mean reading over the quiet ticks (an offset), and the ticks used.
    """
    f = np.asarray(f_mea_n, dtype=float)
    sq, dof, total, count = 0.0, 0, 0.0, 0
    for a, b in true_runs(quiet):
        seg = f[a : b + 1]
        if len(seg) < 2:
            continue
        sq += float(np.sum((seg - seg.mean()) ** 2))
        dof += len(seg) - 1
        total += float(seg.sum())
        count += len(seg)
    if dof == 0:
        return math.nan, math.nan, 0
    return math.sqrt(sq / dof), total / count, count


def position_noise_rms(p_act_m: np.ndarray, quiet: np.ndarray) -> tuple[float, int]:
    """Noise RMS of a position reading from third differences over the quiet
    segments: ``sqrt(mean(diff3^2) / 20)`` (white noise); returns it and the
    number of differences used."""
    p = np.asarray(p_act_m, dtype=float)
    d3 = [np.diff(p[a : b + 1], 3) for a, b in true_runs(quiet) if b - a + 1 >= 4]
    d3 = np.concatenate(d3) if d3 else np.empty(0)
    if d3.size == 0:
        return math.nan, 0
    return math.sqrt(float(np.mean(d3 * d3)) / 20.0), int(d3.size)


# -- whiteness -----------------------------------------------------------------
@dataclass(frozen=True)
class Correlation:
    """Normalized residual autocorrelation and residual-input cross-correlation.

    ``auto[j]`` is at lag ``lags[j]`` (``lags`` from 0); ``cross[j]`` pairs the
    residual at ``k + lags[j]`` with the input at ``k``. ``band`` is the
    confidence half-width ``z / sqrt(N)``.
    """

    lags: np.ndarray
    auto: np.ndarray
    cross: np.ndarray
    band: float
    sample_period_s: float

    def summary(self) -> dict[str, float | int]:
        auto = np.abs(self.auto[1:])
        cross = np.abs(self.cross)
        return {
            "max_lag_s": float(self.lags[-1] * self.sample_period_s),
            "band": self.band,
            "auto_lags_outside": int(np.sum(auto > self.band)),
            "auto_lags": int(auto.size),
            "auto_max_abs": float(auto.max()) if auto.size else math.nan,
            "cross_lags_outside": int(np.sum(cross > self.band)),
            "cross_lags": int(cross.size),
            "cross_max_abs": float(cross.max()) if cross.size else math.nan,
            "cross_max_lag_s": float(self.lags[int(np.argmax(cross))] * self.sample_period_s),
        }


def correlation(
    residual: np.ndarray,
    input_signal: np.ndarray,
    max_lag: int,
    sample_period_s: float = 1.0,
    z: float = CONFIDENCE_Z,
) -> Correlation:
    """Whiteness test of ``residual``: autocorrelation at lags ``0..max_lag``
    and cross-correlation with ``input_signal`` at the same (positive) lags,
    both normalized (means removed) and biased (divided by ``N``)."""
    e = np.asarray(residual, dtype=float)
    u = np.asarray(input_signal, dtype=float)
    n = len(e)
    max_lag = int(min(max_lag, n - 1))
    e = e - e.mean()
    u = u - u.mean()
    see = float(e @ e)
    suu = float(u @ u)
    lags = np.arange(max_lag + 1)
    auto = np.array([e[k:] @ e[: n - k] for k in lags]) / see if see > 0 else np.zeros(len(lags))
    denom = math.sqrt(see * suu)
    cross = (
        np.array([e[k:] @ u[: n - k] for k in lags]) / denom if denom > 0 else np.zeros(len(lags))
    )
    return Correlation(lags, auto, cross, z / math.sqrt(n), sample_period_s)
