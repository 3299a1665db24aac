"""The measurement chain: the first-order-hold filter is exact for a ramp; taps."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.errors import ParameterError
from hybridtable.systems.measurement_chain import MeasurementChainParams, first_order_hold_filter


# -- measurement chain and table -------------------------------------------------
def test_first_order_hold_filter_is_exact_for_a_ramp():
    tau, h = 2e-3, 1e-3
    a, b0, b1 = first_order_hold_filter(tau, h)
    t = h * np.arange(50)
    u = 3.0 * t
    y = np.zeros_like(t)
    for k in range(len(t) - 1):
        y[k + 1] = a * y[k] + b0 * u[k] + b1 * u[k + 1]
    np.testing.assert_allclose(y, 3.0 * (t - tau * (1 - np.exp(-t / tau))), rtol=0, atol=1e-12)
    assert first_order_hold_filter(0.0, h) == (0.0, 0.0, 1.0)


def test_measurement_chain_taps():
    c = MeasurementChainParams(1e-3, delay_s=0.0045)
    assert c.taps() == (4, pytest.approx(0.5))
    assert MeasurementChainParams(1e-3, delay_s=0.004).taps() == (4, 0.0)
    with pytest.raises(ParameterError, match="delay_s"):
        MeasurementChainParams(1e-3, delay_s=-1e-3)
