"""Error statistics of a residual: RMS, NRMSE and fit, the model-free noise floor
of force and position, and whiteness tests (auto- and cross-correlation).

Whiteness verdict: under a white residual each lag's correlation lies outside
the 99 % band with probability ``p = 0.01``, so the number of lags outside is
(nearly) binomial ``B(L, p)``. More lags outside than a white residual shows
with probability :data:`WHITENESS_ALPHA` (0.1 %) means the residual is not
white: e.g. at most 4 of 50 lags may fall outside by chance
(:func:`lags_outside_by_chance`). A short memory puts few lags outside, each
far: so is any lag beyond the Bonferroni limit ``z / sqrt(N)``, ``P(|Z| > z) =
0.1 % / L`` (:func:`peak_limit`, 4.26 / sqrt(N) for 50 lags).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridtable.measurement.phases import true_runs

__all__ = [
    "CONFIDENCE_Z",
    "WHITENESS_ALPHA",
    "ChannelError",
    "Correlation",
    "channel_error",
    "force_noise_rms",
    "position_noise_rms",
    "correlation",
    "lags_outside_by_chance",
    "peak_limit",
]


#: Two-sided 99 % point of the normal distribution (whiteness bands).
CONFIDENCE_Z = 2.5758293035489004

#: Chance, for a white residual, of more lags outside the band than
#: :func:`lags_outside_by_chance` allows (the whiteness verdict's false alarms).
WHITENESS_ALPHA = 1e-3


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
    """RMS error, NRMSE, fit %, mean and largest error of ``model`` against ``measured``.

    ``nrmse = ||y - y_hat|| / ||y - mean(y)||`` and ``fit_percent = 100 (1 - nrmse)``
    (the fit of MATLAB's ``compare``/``goodnessOfFit`` "NRMSE"): 100 % is a
    perfect model, 0 % no better than the measurement's mean, negative worse
    than that. Every error is in the unit of the channel (N, m, m/s); a
    constant measurement has ``nrmse = inf``.
    """
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

    A correlation is white (:attr:`auto_white`, :attr:`cross_white`) when no
    more lags lie outside the band than chance explains
    (:func:`lags_outside_by_chance`) and no lag exceeds the peak limit
    (:func:`peak_limit`): the count catches a long memory, the peak a short one
    (e.g. a residual correlated over 1-3 ticks only).
    """

    lags: np.ndarray
    auto: np.ndarray
    cross: np.ndarray
    band: float
    sample_period_s: float
    z: float = CONFIDENCE_Z

    @property
    def auto_outside(self) -> int:
        """Lags ``1..L`` of the autocorrelation outside the band."""
        return int(np.sum(np.abs(self.auto[1:]) > self.band))

    @property
    def cross_outside(self) -> int:
        """Lags ``0..L`` of the cross-correlation with the input outside the band."""
        return int(np.sum(np.abs(self.cross) > self.band))

    def _peak(self, lags: int) -> float:
        return self.band * peak_limit(lags) / self.z

    @property
    def auto_white(self) -> bool:
        """The autocorrelation is what a white residual shows by chance."""
        auto = np.abs(self.auto[1:])
        return bool(
            self.auto_outside <= lags_outside_by_chance(auto.size, self.z)
            and (auto.size == 0 or auto.max() <= self._peak(auto.size))
        )

    @property
    def cross_white(self) -> bool:
        """The cross-correlation with the input is what chance gives a white residual."""
        cross = np.abs(self.cross)
        return bool(
            self.cross_outside <= lags_outside_by_chance(cross.size, self.z)
            and (cross.size == 0 or cross.max() <= self._peak(cross.size))
        )

    @property
    def white(self) -> bool:
        """Both tests pass: what is left is noise, with no memory and nothing of the input."""
        return self.auto_white and self.cross_white

    def summary(self) -> dict[str, float | int | bool]:
        """Counts, largest values and limits of both tests (lags in s)."""
        auto = np.abs(self.auto[1:])
        cross = np.abs(self.cross)
        h = self.sample_period_s
        return {
            "max_lag_s": float(self.lags[-1] * h),
            "band": self.band,
            "auto_lags_outside": int(np.sum(auto > self.band)),
            "auto_lags": int(auto.size),
            "auto_max_abs": float(auto.max()) if auto.size else math.nan,
            "auto_max_lag_s": float(self.lags[1 + int(np.argmax(auto))] * h)
            if auto.size
            else math.nan,
            "cross_lags_outside": int(np.sum(cross > self.band)),
            "cross_lags": int(cross.size),
            "cross_max_abs": float(cross.max()) if cross.size else math.nan,
            "cross_max_lag_s": float(self.lags[int(np.argmax(cross))] * h),
            "auto_chance_limit": lags_outside_by_chance(auto.size, self.z),
            "cross_chance_limit": lags_outside_by_chance(cross.size, self.z),
            "auto_peak_limit": self._peak(auto.size),
            "cross_peak_limit": self._peak(cross.size),
            "auto_white": self.auto_white,
            "cross_white": self.cross_white,
        }


def peak_limit(lags: int, alpha: float = WHITENESS_ALPHA) -> float:
    """The largest ``|correlation| sqrt(N)`` that a white residual reaches at any
    of ``lags`` lags but with probability ``alpha`` (two-sided, Bonferroni):
    ``z`` with ``P(|Z| > z) = alpha / lags`` (4.26 for 50 lags)."""
    from statistics import NormalDist

    return NormalDist().inv_cdf(1.0 - alpha / (2.0 * max(lags, 1)))


def lags_outside_by_chance(
    lags: int, z: float = CONFIDENCE_Z, alpha: float = WHITENESS_ALPHA
) -> int:
    """The most of ``lags`` correlation lags that a white residual puts outside
    the band ``+-z / sqrt(N)`` by chance: the smallest ``k`` with
    ``P(B(lags, p) > k) <= alpha``, ``p = erfc(z / sqrt(2))`` (0.01 for the 99 %
    band).

    Parameters
    ----------
    lags : int
        Number of lags tested.
    z : float
        Half-width of the band in standard deviations of one lag's correlation.
    alpha : float
        Accepted chance of calling a white residual not white.
    """
    p = math.erfc(z / math.sqrt(2.0))
    tail = 1.0  # P(X > k - 1) = P(X >= k)
    for k in range(lags + 1):
        tail -= math.comb(lags, k) * p**k * (1.0 - p) ** (lags - k)
        if tail <= alpha:
            return k
    return lags


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
    return Correlation(lags, auto, cross, z / math.sqrt(n), sample_period_s, z)
