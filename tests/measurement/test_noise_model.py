"""Autoregressive noise models: the order the data demand, exact whitening."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.measurement.noise_model import NoiseModel, ar_from_segments, whiten


def _ar(rng, n, coef, sigma_innov=1.0):
    p = len(coef)
    x = np.zeros(n + 500)
    xi = sigma_innov * rng.standard_normal(n + 500)
    for k in range(p, n + 500):
        x[k] = sum(c * x[k - j - 1] for j, c in enumerate(coef)) + xi[k]
    return x[500:]


@pytest.mark.parametrize(
    "coef, order",
    [((0.0,), 1), ((0.7,), 1), ((1.2, -0.5), 2), ((0.5, 0.3), 2)],
    ids=["white", "ar1", "ar2-resonant", "ar2-slow"],
)
def test_order_and_coefficients_from_detrended_segments(coef, order):
    rng = np.random.default_rng(5)
    segments = [_ar(rng, 400, coef) + 3.0 + 0.01 * np.arange(400) for _ in range(4)]
    m = ar_from_segments(segments, degree=1)
    assert m.order == order
    np.testing.assert_allclose(m.coefficients[: len(coef)], coef, atol=0.08)
    marginal = np.concatenate(
        [s - np.polyval(np.polyfit(np.arange(400), s, 1), np.arange(400)) for s in segments]
    ).std()
    assert m.sigma == pytest.approx(marginal, rel=0.08)
    w = np.concatenate([whiten(_ar(rng, 4000, coef), m)])
    assert np.var(w) == pytest.approx(1.0, rel=0.1)
    for lag in (1, 2, 3):
        assert abs(np.corrcoef(w[lag:], w[:-lag])[0, 1]) < 0.06


def test_whitening_an_ar2_is_exact_from_the_first_sample():
    rng = np.random.default_rng(1)
    m = NoiseModel(sigma=1.0, phi=0.0, samples=0, ar=(1.2, -0.5))
    m = NoiseModel(
        sigma=1.0 / m.innovation_sigma, phi=0.0, samples=0, ar=(1.2, -0.5)
    )  # unit innovations
    # many short records: the first samples' innovations must be unit too
    first = np.array([whiten(_ar(rng, 6, (1.2, -0.5)), m)[:3] for _ in range(3000)])
    np.testing.assert_allclose(first.var(axis=0), 1.0, rtol=0.1)
