"""Compensators: SDC phase lead, MDC response-error force, gating, clamp."""

import numpy as np
import pytest
from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from hybridtable import Compensator, CompensatorParams, ParameterError


def _eval(params, f_mea, rate=0.0, table=(0.0, 0.0, 0.0), cmd=(0.0, 0.0), **kw):
    comp = Compensator(params, **kw)
    ctx = comp.CreateDefaultContext()
    comp.GetInputPort("measured_force").FixValue(ctx, [f_mea])
    comp.GetInputPort("measured_force_rate").FixValue(ctx, [rate])
    comp.GetInputPort("table_motion").FixValue(ctx, list(table))
    comp.GetInputPort("commanded_state").FixValue(ctx, list(cmd))
    return comp.GetOutputPort("compensated_force").Eval(ctx)[0]


def test_none_passes_the_measured_force():
    assert (
        _eval(CompensatorParams("none"), 123.0, rate=1e4, table=(1e-3, 0, 0), cmd=(2e-3, 0))
        == 123.0
    )


def test_sdc_is_first_order_lead():
    p = CompensatorParams("SDC", lead_time_s=5e-3)
    assert _eval(p, 100.0, rate=2000.0) == pytest.approx(100.0 + 5e-3 * 2000.0)


def test_mdc_adds_stiffness_and_damping_times_response_error():
    p = CompensatorParams("MDC", stiffness_n_per_m=1e5, damping_n_s_per_m=200.0)
    f = _eval(p, 50.0, table=(1e-3, 0.05, 0.0), cmd=(1.4e-3, 0.08))
    assert f == pytest.approx(50.0 + 1e5 * 0.4e-3 + 200.0 * 0.03)


def test_sdmdc_is_sum_of_both():
    p = CompensatorParams("SDMDC", lead_time_s=3e-3, stiffness_n_per_m=2e5)
    f = _eval(p, 80.0, rate=-1000.0, table=(2e-3, 0, 0), cmd=(2.5e-3, 0))
    assert f == pytest.approx(80.0 - 3.0 + 2e5 * 0.5e-3)


def test_measured_force_gate_and_clamp():
    p = CompensatorParams("SDMDC", lead_time_s=5e-3, stiffness_n_per_m=1e5, force_deadband_n=5.0)
    # At or below the deadband: no contact, no force, whatever the MDC term says.
    assert _eval(p, 5.0, rate=1e4, table=(0, 0, 0), cmd=(1e-2, 0)) == 0.0
    # Pulling force passes unless clamped.
    args = dict(rate=-1e4, table=(1e-3, 0, 0), cmd=(0.0, 0))
    assert _eval(p, 10.0, **args) == pytest.approx(10.0 - 50.0 - 100.0)
    clamped = CompensatorParams(**{**p.__dict__, "clamp_nonnegative": True})
    assert _eval(clamped, 10.0, **args) == 0.0
    # The linear (ungated) version used for analysis keeps everything.
    assert _eval(clamped, 0.0, **args, gated=False) == pytest.approx(-50.0 - 100.0)


def test_table_position_gate_applies_mdc_only_in_contact():
    p = CompensatorParams("MDC", stiffness_n_per_m=1e5, contact_gate="table_position")
    assert _eval(p, 0.0, table=(1e-3, 0, 0), cmd=(1.5e-3, 0)) == pytest.approx(50.0)
    assert _eval(p, 7.0, table=(-1e-3, 0, 0), cmd=(1.5e-3, 0)) == pytest.approx(7.0)


def test_backward_difference_lead_on_a_ramp_is_exact():
    # f_mea = 1000 t: the backward difference at period h is exactly the slope.
    h, lead = 1e-3, 4e-3
    builder = DiagramBuilder()
    from pydrake.systems.primitives import Integrator

    slope = builder.AddSystem(ConstantVectorSource([1000.0]))
    ramp = builder.AddSystem(Integrator(1))
    builder.Connect(slope.get_output_port(), ramp.get_input_port())
    comp = builder.AddSystem(
        Compensator(CompensatorParams("SDC", lead_time_s=lead), derivative_period_s=h)
    )
    builder.Connect(ramp.get_output_port(), comp.GetInputPort("measured_force"))
    zeros3 = builder.AddSystem(ConstantVectorSource(np.zeros(3)))
    zeros2 = builder.AddSystem(ConstantVectorSource(np.zeros(2)))
    builder.Connect(zeros3.get_output_port(), comp.GetInputPort("table_motion"))
    builder.Connect(zeros2.get_output_port(), comp.GetInputPort("commanded_state"))
    log = LogVectorOutput(comp.GetOutputPort("compensated_force"), builder, h)
    sim = Simulator(builder.Build())
    ramp.set_integral_value(ramp.GetMyMutableContextFromRoot(sim.get_mutable_context()), [1.0])
    sim.AdvanceTo(0.05)
    lg = log.FindLog(sim.get_context())
    t, f = lg.sample_times(), lg.data()[0]
    late = t > 2 * h
    np.testing.assert_allclose(f[late], 1.0 + 1000.0 * t[late] + lead * 1000.0, rtol=1e-9)


def test_converts_to_autodiff():
    comp = Compensator(CompensatorParams("SDMDC", 5e-3, 1e5), derivative_period_s=1e-3)
    ad = comp.ToAutoDiffXd()
    ctx = ad.CreateDefaultContext()
    ad.GetInputPort("measured_force").FixValue(ctx, [AutoDiffXd(10.0, [1.0])])
    ad.GetInputPort("table_motion").FixValue(ctx, [AutoDiffXd(0.0)] * 3)
    ad.GetInputPort("commanded_state").FixValue(ctx, [AutoDiffXd(0.0)] * 2)
    out = ad.GetOutputPort("compensated_force").Eval(ctx)[0]
    # d f_comp / d f_mea = 1 + T_lead / h with the backward difference.
    assert out.derivatives()[0] == pytest.approx(1.0 + 5e-3 / 1e-3)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"kind": "PID"}, "compensator"),
        ({"lead_time_s": -1.0}, "lead_time_s"),
        ({"stiffness_n_per_m": float("nan")}, "stiffness_n_per_m"),
        ({"contact_gate": "psychic"}, "contact_gate"),
    ],
)
def test_bad_parameters_name_the_field(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        CompensatorParams(**kwargs)
