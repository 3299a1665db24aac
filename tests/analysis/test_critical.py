"""The one critical-delay search, on figures whose crossing is known in closed form."""

from __future__ import annotations

import math

import pytest

from hybridtable.analysis.critical import critical_delay, first_crossing_delay


def test_a_continuous_crossing_is_refined_to_the_root():
    # A figure with its root between two scan points, not on one.
    assert critical_delay(lambda T: math.sin(37.0 * T - 0.5), 0.05) == pytest.approx(
        0.5 / 37.0, abs=1e-12
    )


def test_a_sampled_loop_is_scanned_on_ticks_and_refined_within_the_tick():
    h, calls = 1e-3, []

    def excess(T: float) -> float:
        calls.append(T)
        return T - 3.4e-3

    assert critical_delay(excess, 0.02, sample_period_s=h) == pytest.approx(3.4e-3, abs=1e-12)
    scanned = [T for T in calls if abs(T / h - round(T / h)) < 1e-9]
    assert max(scanned) >= 4e-3 - 1e-12  # the first whole tick beyond ...
    assert all(T <= 4e-3 + 1e-12 for T in calls)  # ... and nothing past it
    assert len(calls) == len(set(calls))  # no delay asked twice


def test_reached_at_zero_never_and_nan():
    assert critical_delay(lambda T: 1.0, 0.01) == 0.0
    assert critical_delay(lambda T: -1.0, 0.01) == math.inf
    # NaN counts as beyond the limit; with nothing to refine, the last delay within
    nan_after = critical_delay(lambda T: -1.0 if T < 0.004 else math.nan, 0.01, 1e-3)
    assert nan_after == pytest.approx(3e-3)


def test_a_neutral_figure_within_the_tolerance_counts_as_reached():
    # Zero at delay 0 (e.g. an undamped contact): reached at once.
    assert critical_delay(lambda T: 0.0, 0.01, tolerance=1e-9) == 0.0
    # Negative, then neutral within the band from 2 ms on: the far end of the tick.
    neutral = critical_delay(lambda T: -1.0 if T < 2e-3 else -1e-12, 0.01, 1e-3, tolerance=1e-9)
    assert neutral == pytest.approx(2e-3)
    # Without the tolerance, the same figure never reaches the limit.
    assert critical_delay(lambda T: -1.0 if T < 2e-3 else -1e-12, 0.01, 1e-3) == math.inf


def test_the_bracket_of_a_sampled_scan_is_one_tick():
    h = 1e-4
    a, b = first_crossing_delay(lambda T: T > 0.01234, 0.05, h, scan_points=9)
    assert b - a == pytest.approx(h) and a < 0.01234 < b
    assert first_crossing_delay(lambda T: False, 0.05, h) is None
