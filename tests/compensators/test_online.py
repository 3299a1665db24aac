"""SDMDC with online identification: closed forms tick by tick, and the loop
restored to CoR 1 with a wrong prior stiffness.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.compensators.online import AdaptiveSDMDC, make_online_sdmdc
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params
from tests.compensators.support import compensator_inputs, run_ticks


def test_adaptive_sdmdc_step_and_ramp_closed_forms():
    from hybridtable import CompensatorParams

    h, lead, k, c = 1e-3, 4e-3, 2e4, 150.0
    comp = AdaptiveSDMDC(CompensatorParams("SDMDC", lead_time_s=lead), h)
    n = 12
    # Force step of 50 N at tick 3 with a response error (1 mm, 0.02 m/s).
    f = np.where(np.arange(n) >= 3, 50.0, 0.0)
    u = compensator_inputs(n, f=f, p_act=1e-3, v_act=0.08, p_des=2e-3, v_des=0.1)
    u["contact_parameters"] = np.tile([k, c], (n, 1))
    y = run_ticks(comp, u)[:, 0]
    mdc = k * 1e-3 + c * 0.02
    assert np.all(y[:3] == 0.0)  # gated: no measured force
    assert y[3] == pytest.approx(50.0 + lead * 50.0 / h + mdc)
    assert y[4:] == pytest.approx(50.0 + mdc)
    # Ramp 1e4 N/s: f + lead * rate.
    f = 1e4 * h * np.arange(1, n + 1)
    u = compensator_inputs(n, f=f)
    u["contact_parameters"] = np.tile([k, c], (n, 1))
    y = run_ticks(comp, u)[:, 0]
    assert y[1:] == pytest.approx(f[1:] + lead * 1e4)


def test_sdmdc_online_identifies_then_compensates_with_the_true_stiffness():
    # Sampled loop at 1 kHz, 3 ms sensor delay: f_mea[k] = K p_act[k - 3].
    k_true, h, n = 1e5, 1e-3, 40
    params = table1_params(
        "sdmdc-online", sample_rate_hz=1e3, compensator_stiffness_n_per_m=0.5 * k_true
    ).with_(sensor_delay_s=3e-3)
    comp = make_online_sdmdc(params, h)
    t = h * np.arange(n)
    p_act = 0.1 * t - 1e-3  # contact from tick 10
    p_des = p_act + 1.6e-3  # the table lags the command
    f = np.maximum(k_true * np.concatenate([np.full(3, -1.0), p_act[:-3]]), 0.0)
    y = run_ticks(comp, compensator_inputs(n, f=f, p_act=p_act, v_act=0.1, p_des=p_des, v_des=0.1))[
        :, 0
    ]
    rate = np.concatenate([[0.0], np.diff(f)]) / h
    expected = f + 3e-3 * rate + k_true * 1.6e-3
    first = np.argmax(f > 0)
    assert first == 14
    # The first contact tick uses the prior, then the identified stiffness.
    assert y[first] == pytest.approx(f[first] + 3e-3 * rate[first] + 0.5 * k_true * 1.6e-3)
    assert y[first + 2 :] == pytest.approx(expected[first + 2 :], rel=1e-6)


def test_sdmdc_online_within_001_of_cor_1_where_fixed_k_sdmdc_is_not():
    for ratio in (0.5, 2.0):
        kw = dict(compensator_stiffness_n_per_m=ratio * 1e5)
        fixed = simulate(table1_params("SDMDC", **kw)).metrics.cor
        online = simulate(table1_params("sdmdc-online", **kw)).metrics.cor
        assert abs(fixed - 1.0) > 0.04  # the mismatch matters ...
        assert abs(online - 1.0) < 0.01  # ... and the identification removes it
