"""The end test of a diagnosis: are the model's residuals the noise, and if not, where not?

Under a right model the prewhitened replay residuals (:mod:`hybridtable.diagnosis.evaluate`)
are white with the innovation variance of the noise model estimated where there
is no contact. :func:`goodness_of_fit` tests that in every window a misfit can sit
in: each run, each channel (``f_mea``, ``p_act``), each contact phase
(approach, compression, restitution, free flight; the force's phases delayed by
the sensor delay), and at several time scales. At scale ``L`` the window's
whitened residual ``w`` is cut into blocks of ``L`` ticks and
``B_j = sum(block_j) / sqrt(L)``; under the null ``B_j`` are unit normal, and
``mean(B_j^2)`` is F-distributed with ``(blocks, n0)`` degrees of freedom, ``n0``
the ticks the noise was estimated from (its own uncertainty). Scale 1 is the
plain variance test, larger scales catch slow misfits (a wrong pulse shape, a
lag) that a variance test dilutes, the whole window its mean.

The family of tests is held to one false-alarm rate per set of runs
(:data:`FALSE_ALARM_RATE`) by Bonferroni: the test fails if a p-value times
the number of tests is below it in a window whose error is at least
:data:`WINDOW_ERROR_FLOOR` times the noise, with two standard errors of the
window's noise power to spare (a statistically sure but tiny
misfit, e.g. of a JSON value rounded to 0.1 %, is not one a user can act on;
such windows are still listed). The worst window says where the
misfit sits: run, channel, phase, time window (the block with the largest
``|B_j|``), frequency band (the octave of the window's residual spectrum with
the most power over the noise's) and the error there in noise units.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from hybridtable.diagnosis.evaluate import Evaluation, RunData
from hybridtable.diagnosis.settings import CHANNELS
from hybridtable.measurement.phases import PHASES, true_runs

__all__ = [
    "FALSE_ALARM_RATE",
    "SCALES",
    "WINDOW_ERROR_FLOOR",
    "WindowTest",
    "GoodnessOfFit",
    "goodness_of_fit",
]


#: Probability that the end test fails on a set whose model is right.
FALSE_ALARM_RATE = 0.01

#: Block lengths (ticks) of the test, besides the whole window.
SCALES: tuple[int, ...] = (1, 4, 16, 64)

#: Shortest window tested (ticks).
MIN_WINDOW = 4

#: Smallest error (RMS residual over the noise RMS) of a window whose failed
#: test counts: a misfit under half the noise (``sqrt(1.1^2 - 1) = 0.46``) over
#: a whole contact phase is below practical significance (a JSON value
#: rounded to 0.1 % can leave that much).
WINDOW_ERROR_FLOOR = 1.1


@dataclass(frozen=True)
class WindowTest:
    """The test of one window (SI units; ``error`` in noise units)."""

    run_id: str
    channel: str
    phase: str
    start_s: float
    end_s: float
    ticks: int
    scale_ticks: int
    statistic: float
    p_value: float
    error: float
    misfit_start_s: float
    misfit_end_s: float
    band_hz: tuple[float, float]
    #: Whether the error is large enough to count (over
    #: :data:`WINDOW_ERROR_FLOOR` with the noise's own spread to spare): a
    #: window below it can be statistically detectable and still negligible.
    relevant: bool = True

    def to_json(self) -> dict:
        return {
            "run_id": self.run_id,
            "channel": self.channel,
            "phase": self.phase,
            "window_s": [self.start_s, self.end_s],
            "ticks": self.ticks,
            "scale_ticks": self.scale_ticks,
            "statistic": self.statistic,
            "p_value": self.p_value,
            "error": self.error,
            "misfit_window_s": [self.misfit_start_s, self.misfit_end_s],
            "band_hz": list(self.band_hz),
            "relevant": self.relevant,
        }


@dataclass
class GoodnessOfFit:
    """The end test's result: passed, the family's p-value, the worst windows."""

    passed: bool
    p_value: float
    tests: int
    false_alarm_rate: float
    worst: list[WindowTest] = field(default_factory=list)

    @property
    def where(self) -> WindowTest | None:
        return self.worst[0] if self.worst else None

    def to_json(self) -> dict:
        return {
            "passed": self.passed,
            "p_value": self.p_value,
            "tests": self.tests,
            "false_alarm_rate": self.false_alarm_rate,
            "window_error_floor": WINDOW_ERROR_FLOOR,
            "test": "block-sum F tests of the whitened replay residuals per run, channel, "
            f"contact phase and time scale ({', '.join(map(str, SCALES))} ticks and the "
            "whole window) against the no-contact noise model; Bonferroni over the family",
            "where": self.where.to_json() if self.where else None,
            "worst": [w.to_json() for w in self.worst],
        }


def _band(w: np.ndarray, h: float) -> tuple[float, float]:
    """The octave band (Hz) of ``w``'s periodogram with the largest mean power."""
    n = len(w)
    if n < 8:
        return (0.0, 0.5 / h)
    power = np.abs(np.fft.rfft(w)) ** 2 / n  # 1 per bin for unit white noise
    freqs = np.fft.rfftfreq(n, h)
    nyq = 0.5 / h
    lo = freqs[1] if len(freqs) > 1 else nyq
    best, band = -math.inf, (0.0, nyq)
    edges = [0.0]
    f = lo
    while f < nyq:
        edges.append(f)
        f *= 2.0
    edges.append(nyq * (1 + 1e-9))
    for a, b in zip(edges[:-1], edges[1:], strict=False):
        sel = (freqs >= a) & (freqs < b)
        if not sel.any():
            continue
        excess = float(np.sum(power[sel] - 1.0))
        if excess > best:
            best, band = excess, (float(a), float(min(b, nyq)))
    return band


def _window_tests(
    d: RunData, ev: Evaluation, channel: str
) -> list[tuple[float, int, float, int, int, int]]:
    """(p, scale, statistic, start, end, worst block start) of each test of one channel."""
    labels = d.f_labels if channel == "f_mea_n" else d.labels
    w_all = ev.whitened[channel]
    n0 = max(d.noise[channel].samples - 2, 10)
    out = []
    for phase in range(len(PHASES)):
        for a, b in true_runs(labels == phase):
            w = w_all[a : b + 1]
            n = len(w)
            if n < MIN_WINDOW:
                continue
            for scale in (*[s for s in SCALES if s <= n // 2], n):
                nb = n // scale
                blocks = w[: nb * scale].reshape(nb, scale).sum(axis=1) / math.sqrt(scale)
                stat = float(np.mean(blocks**2))
                p = float(stats.f.sf(stat, nb, n0))
                j = int(np.argmax(np.abs(blocks)))
                out.append((p, scale, stat, a, b, a + j * scale))
    return out


def goodness_of_fit(
    data: Sequence[RunData],
    evaluations: Mapping[int, Evaluation],
    false_alarm_rate: float = FALSE_ALARM_RATE,
    keep: int = 3,
) -> GoodnessOfFit:
    """Test a model's whitened replay residuals against the noise (see the module doc).

    Parameters
    ----------
    data : sequence of RunData
        The runs (noise models, phase labels).
    evaluations : mapping run index -> Evaluation
        The model's replay evaluations.
    false_alarm_rate : float
        Probability of failing a right model, per set.
    keep : int
        Worst windows reported (each from another run x channel x phase).
    """
    rows = []
    for i, ev in evaluations.items():
        if ev.failed:
            continue
        for c in CHANNELS:
            noise = data[i].noise[c]
            rho2 = noise.phi * noise.phi
            for t in _window_tests(data[i], ev, c):
                a, b = t[3], t[4]
                error = float(np.sqrt(np.mean(ev.residual[c][a : b + 1] ** 2)) / noise.sigma)
                # The window's mean square holds the noise's too: two of its
                # standard errors to spare before a misfit counts.
                spare = 2.0 * np.sqrt(2.0 * (1.0 + rho2) / ((1.0 - rho2) * (b - a + 1)))
                relevant = error * error - 1.0 - spare >= WINDOW_ERROR_FLOOR**2 - 1.0
                rows.append((i, c, *t, error, relevant))
    m = len(rows)
    if m == 0:
        return GoodnessOfFit(False, 0.0, 0, false_alarm_rate)
    # Windows with a practically relevant error first, then by p-value.
    rows.sort(key=lambda r: (not r[-1], r[2]))
    relevant_rows = [r for r in rows if r[-1]]
    p_family = min(1.0, relevant_rows[0][2] * m) if relevant_rows else 1.0
    worst: list[WindowTest] = []
    seen = set()
    for i, c, p, scale, stat, a, b, j, error, relevant in rows:
        d = data[i]
        labels = d.f_labels if c == "f_mea_n" else d.labels
        key = (i, c, int(labels[a]))
        if key in seen:
            continue
        seen.add(key)
        h = d.run.sample_period_s
        t = d.run.time_s
        worst.append(
            WindowTest(
                run_id=d.run_id,
                channel=c,
                phase=PHASES[int(labels[a])],
                start_s=float(t[a]),
                end_s=float(t[b]),
                ticks=int(b - a + 1),
                scale_ticks=scale,
                statistic=stat,
                p_value=min(1.0, p * m),
                error=error,
                misfit_start_s=float(t[j]),
                misfit_end_s=float(t[min(j + scale - 1, b)]),
                band_hz=_band(evaluations[i].whitened[c][a : b + 1], h),
                relevant=bool(relevant),
            )
        )
        if len(worst) >= keep:
            break
    return GoodnessOfFit(p_family >= false_alarm_rate, p_family, m, false_alarm_rate, worst)
