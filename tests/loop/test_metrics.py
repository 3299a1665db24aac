"""Contact metrics on a record with a closed-form answer."""

import math

import numpy as np
import pytest

from hybridtable.loop.metrics import contact_intervals, contact_metrics


def test_metrics_of_an_analytic_bounce():
    # Half-sine force pulse of an elastic contact with restitution e.
    m, k, v0, e = 100.0, 4e4, 0.2, 0.9
    w = math.sqrt(k / m)
    t = np.linspace(0, 0.5, 50001)
    on = (t >= 0.1) & (t <= 0.1 + math.pi / w)
    f = np.where(on, m * v0 * w * np.sin(w * (t - 0.1)), 0.0)
    # Velocity: v0 until the contact, then -e v0 afterwards.
    v = np.where(t < 0.1, v0, np.where(on, v0 * np.cos(w * (t - 0.1)), -e * v0))
    res = contact_metrics(t, v, f, f, m)
    assert res.cor == pytest.approx(e)
    assert res.contact_duration_s == pytest.approx(math.pi / w, abs=2e-5)
    assert res.peak_force_n == pytest.approx(m * v0 * w, rel=1e-6)
    assert res.energy_gain_j == pytest.approx(0.5 * m * v0**2 * (e * e - 1))


def test_no_contact_is_an_error():
    t = np.linspace(0, 1, 11)
    with pytest.raises(ValueError, match="no contact"):
        contact_metrics(t, np.ones_like(t), np.zeros_like(t), np.zeros_like(t), 1.0)


def test_contact_intervals():
    t = np.arange(10.0)
    active = np.array([0, 1, 1, 0, 0, 1, 0, 1, 1, 1], dtype=bool)
    assert contact_intervals(t, active) == [(1.0, 2.0), (5.0, 5.0), (7.0, 9.0)]
