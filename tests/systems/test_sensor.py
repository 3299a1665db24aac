"""Force-sensor delay: the delay shifts a signal by exactly its delay."""

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, Sine, ZeroOrderHold

from hybridtable import ForceSensorDelay, ParameterError, SensorParams
from hybridtable.systems.sensor import continuous_delay_period, pade_state_space

W = 2 * math.pi * 3.0  # test signal: sin(W t) starting at t = 0


def _sampled_reads(delay_s, h, t_end=0.2):
    """What a discrete consumer (a ZOH ticking with the sensor) reads at each tick."""
    builder = DiagramBuilder()
    src = builder.AddSystem(Sine(1.0, W, 0.0, 1))
    sensor = builder.AddSystem(ForceSensorDelay(SensorParams(delay_s), "sampled", h))
    zoh = builder.AddSystem(ZeroOrderHold(h, 1))
    builder.Connect(src.get_output_port(0), sensor.GetInputPort("force"))
    builder.Connect(sensor.GetOutputPort("measured_force"), zoh.get_input_port())
    log = LogVectorOutput(zoh.get_output_port(), builder, h)
    sim = Simulator(builder.Build())
    sim.AdvanceTo(t_end)
    lg = log.FindLog(sim.get_context())
    # The log at tick k+1 (before its update) holds what the ZOH read at tick k.
    t = lg.sample_times()[:-1]
    return t, lg.data()[0][1:]


@pytest.mark.parametrize("samples", [0, 1, 4, 7])
def test_sampled_delay_is_exact_at_the_ticks(samples):
    h = 1e-3
    t, read = _sampled_reads(samples * h, h)
    expected = np.where(t - samples * h >= -1e-12, np.sin(W * (t - samples * h)), 0.0)
    np.testing.assert_allclose(read, expected, atol=1e-12)


def test_continuous_delay_mean_shift_equals_delay():
    delay = 5e-3
    builder = DiagramBuilder()
    src = builder.AddSystem(Sine(1.0, W, 0.0, 1))
    sensor = builder.AddSystem(ForceSensorDelay(SensorParams(delay), "continuous", 1e-4))
    builder.Connect(src.get_output_port(0), sensor.GetInputPort("force"))
    log = LogVectorOutput(sensor.GetOutputPort("measured_force"), builder, 1e-5)
    sim = Simulator(builder.Build())
    sim.AdvanceTo(1.0)
    lg = log.FindLog(sim.get_context())
    t, y = lg.sample_times(), lg.data()[0]
    keep = t > 0.1
    # Fit the phase of the delayed sine: y ~ sin(W (t - d)).
    a = np.linalg.lstsq(
        np.column_stack([np.sin(W * t[keep]), np.cos(W * t[keep])]), y[keep], rcond=None
    )[0]
    measured_delay = math.atan2(-a[1], a[0]) / W
    assert measured_delay == pytest.approx(delay, abs=2e-6)
    h, n = continuous_delay_period(delay, 1e-4)
    assert n * h + h / 2 == pytest.approx(delay)
    assert h <= 1e-4


def test_pade_matches_delay_phase_at_low_frequency():
    import control

    delay = 5e-3
    A, B, C, D = pade_state_space(delay, 3)
    sys = control.ss(A, B, C, D)
    for f_hz in (1.0, 10.0, 50.0):
        w = 2 * math.pi * f_hz
        resp = complex(sys(1j * w))
        assert abs(resp) == pytest.approx(1.0, abs=1e-9)  # all-pass
        # Leading phase error of the [n/n] Pade approximant:
        # 2 (n!)^2 / ((2n)! (2n+1)!) (w T)^(2n+1).
        x = w * delay
        bound = 2 * math.factorial(3) ** 2 / (math.factorial(6) * math.factorial(7)) * x**7
        assert np.angle(resp) == pytest.approx(-x, abs=1.2 * bound + 1e-12)


def test_pade_sensor_delays_both_channels():
    sensor = ForceSensorDelay(SensorParams(2e-3), "pade", pade_order=2, size=2)
    ctx = sensor.CreateDefaultContext()
    assert ctx.num_continuous_states() == 4
    sensor.GetInputPort("force").FixValue(ctx, [0.0, 0.0])
    # DC gain 1 on each channel: steady state of a constant input.
    from pydrake.systems.primitives import Linearize

    lin = Linearize(sensor, ctx)
    dc = lin.D() - lin.C() @ np.linalg.solve(lin.A(), lin.B())
    np.testing.assert_allclose(dc, np.eye(2), atol=1e-9)


def test_negative_delay_names_the_field():
    with pytest.raises(ParameterError, match="sensor_delay_s"):
        SensorParams(-1e-3)
