"""Polynomial extrapolation of the measured force: exact for polynomials up to
the order, gating and clamp, horizon of the loop delay.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable import ParameterError
from hybridtable.compensators.polynomial import (
    PolynomialExtrapolator,
    PolynomialParams,
    extrapolation_weights,
    make_polynomial,
)
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params
from tests.compensators.support import compensator_inputs, run_ticks


def test_extrapolation_weights_are_exact_for_polynomials_up_to_the_order():
    rng = np.random.default_rng(0)
    for order in (1, 2, 3):
        for horizon in (0.3, 1.0, 2.5):
            w = extrapolation_weights(order, horizon)
            assert w.sum() == pytest.approx(1.0)
            coef = rng.standard_normal(order + 1)
            samples = np.polyval(coef, -np.arange(order + 1.0))
            assert w @ samples == pytest.approx(np.polyval(coef, horizon))
    # Order 1, one-tick spacing, horizon T: the paper's SDC backward difference.
    assert extrapolation_weights(1, 5.0) == pytest.approx([6.0, -5.0])


def test_polynomial_step_response_is_the_partial_sums_of_the_weights():
    h = 1e-3
    p = PolynomialParams(horizon_s=6e-3, order=2, spacing_s=3e-3)
    comp = PolynomialExtrapolator(p, h)
    w = p.weights(h)  # spacing 3 ticks, horizon 2 spacings
    assert w == pytest.approx(extrapolation_weights(2, 2.0))
    n = 10
    y = run_ticks(comp, compensator_inputs(n, f=np.where(np.arange(n) >= 2, 10.0, 0.0)))[:, 0]
    expected = [0, 0, w[0], w[0], w[0], w[0] + w[1], w[0] + w[1], w[0] + w[1], 1.0, 1.0]
    assert y == pytest.approx(10.0 * np.array(expected))


def test_polynomial_ramp_and_parabola_are_extrapolated_exactly():
    h, horizon = 1e-3, 7e-3
    n = 30
    t = h * np.arange(n)
    for order, f in ((1, 1e3 * t + 5.0), (2, 1e3 * t + 4e5 * t**2 + 5.0)):
        p = PolynomialParams(horizon_s=horizon, order=order, spacing_s=2e-3)
        y = run_ticks(PolynomialExtrapolator(p, h), compensator_inputs(n, f=f))[:, 0]
        start = order * 2  # the history is full from here on
        tt = t[start:] + horizon
        exact = 1e3 * tt + 5.0 if order == 1 else 1e3 * tt + 4e5 * tt**2 + 5.0
        assert y[start:] == pytest.approx(exact, rel=1e-9)


def test_polynomial_gating_and_clamp():
    h = 1e-3
    p = PolynomialParams(horizon_s=2e-3, order=1, spacing_s=1e-3, force_deadband_n=5.0)
    y = run_ticks(PolynomialExtrapolator(p, h), compensator_inputs(4, f=[5.0, 20.0, 10.0, 6.0]))[
        :, 0
    ]
    # 5 N is in the deadband; then 3 f[k] - 2 f[k-1].
    assert y == pytest.approx([0.0, 50.0, -10.0, -2.0])
    pc = PolynomialParams(2e-3, 1, 1e-3, force_deadband_n=5.0, clamp_nonnegative=True)
    y = run_ticks(PolynomialExtrapolator(pc, h), compensator_inputs(4, f=[5.0, 20.0, 10.0, 6.0]))[
        :, 0
    ]
    assert y == pytest.approx([0.0, 50.0, 0.0, 0.0])
    with pytest.raises(ParameterError, match="order"):
        PolynomialParams(1e-3, order=0)


def test_polynomial_factory_horizon_is_the_loop_delay():
    params = table1_params("polynomial")
    comp = make_polynomial(params, 1e-4)
    assert comp.params.horizon_s == pytest.approx(params.effective_delay_s)
    assert comp.params.order == 2
    assert make_polynomial(params.with_(lead_time_s=2e-3), 1e-4).params.horizon_s == 2e-3


def test_polynomial_needs_no_stiffness():
    a = simulate(table1_params("polynomial")).metrics.cor
    b = simulate(table1_params("polynomial", compensator_stiffness_n_per_m=3e4)).metrics.cor
    assert a == b and abs(a - 1.0) < 0.01
