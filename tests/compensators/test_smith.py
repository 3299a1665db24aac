"""The Smith predictor: step and ramp closed forms, deadband, CoR 1 with the
true model.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.compensators.smith import SmithParams, SmithPredictor, make_smith
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params
from tests.compensators.support import compensator_inputs, run_ticks


def _smith_inputs(n, p_des, p_act, f):
    return compensator_inputs(n, f=f, p_act=p_act, v_act=0.0, p_des=p_des, v_des=0.0)


def test_smith_step_predicts_the_force_before_it_is_measured():
    k = 2e4
    comp = SmithPredictor(SmithParams(k))
    ctx = comp.CreateDefaultContext()
    for name, value in (
        ("measured_force", [0.0]),
        ("measured_force_rate", [0.0]),
        ("table_motion", [0.0, 0.0, 0.0]),
        ("commanded_state", [1e-3, 0.0]),  # command steps into contact
        ("delayed_table_motion", [0.0, 0.0, 0.0]),
    ):
        comp.GetInputPort(name).FixValue(ctx, value)
    assert comp.GetOutputPort("compensated_force").Eval(ctx)[0] == pytest.approx(k * 1e-3)


@pytest.mark.parametrize("k_model_ratio", [1.0, 0.5])
def test_smith_ramp_closed_form_in_the_sampled_loop(k_model_ratio):
    # 1 kHz, 3 ms delay: f_mea[k] = K p_act[k - 3]; model stiffness K_m.
    k_true, h, n = 1e5, 1e-3, 30
    params = table1_params(
        "smith", sample_rate_hz=1e3, compensator_stiffness_n_per_m=k_model_ratio * k_true
    ).with_(sensor_delay_s=3e-3)
    comp = make_smith(params, h)
    t = h * np.arange(n)
    p_act = 0.1 * t - 1e-3
    p_des = p_act + 1.6e-3
    p_old = np.concatenate([np.full(3, -1.0), p_act[:-3]])
    f = np.maximum(k_true * p_old, 0.0)
    y = run_ticks(comp, _smith_inputs(n, p_des, p_act, f))[:, 0]
    k_m = k_model_ratio * k_true
    expected = np.maximum(k_m * p_des, 0) + f - np.maximum(k_m * p_old, 0)
    assert y == pytest.approx(expected, rel=1e-12, abs=1e-9)
    if k_model_ratio == 1.0:  # exact model: the ideal force k p_des
        assert y == pytest.approx(np.maximum(k_true * p_des, 0.0), abs=1e-9)


def test_smith_deadband_applies_to_measured_and_predicted_force():
    comp = SmithPredictor(SmithParams(1e4, force_deadband_n=5.0))
    ctx = comp.CreateDefaultContext()
    comp.GetInputPort("measured_force").FixValue(ctx, [4.0])
    comp.GetInputPort("measured_force_rate").FixValue(ctx, [0.0])
    comp.GetInputPort("table_motion").FixValue(ctx, [0.0, 0.0, 0.0])
    comp.GetInputPort("commanded_state").FixValue(ctx, [2e-3, 0.0])
    comp.GetInputPort("delayed_table_motion").FixValue(ctx, [4e-4, 0.0, 0.0])  # predicts 4 N
    assert comp.GetOutputPort("compensated_force").Eval(ctx)[0] == pytest.approx(20.0)


@pytest.mark.parametrize("sampled", [False, True])
def test_smith_with_the_true_model_restores_cor_1(sampled):
    kw = {"sample_rate_hz": 1e3} if sampled else {}
    assert simulate(table1_params("smith", **kw)).metrics.cor == pytest.approx(1.0, abs=1e-3)
