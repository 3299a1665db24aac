"""A sensor delay between ticks on a sampled rig: the reading interpolates the
two neighbouring samples (systems.sensor.sample_taps), in the Drake diagram,
the sampled sensor's readings law and the fast engine alike."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, Sine

from hybridtable.loop.fast import simulate_fast
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams, sample_taps

H = 1e-3


def test_taps_split_a_delay_into_whole_ticks_and_a_fraction():
    assert sample_taps(0.004, H) == (4, 0.0)
    m, alpha = sample_taps(0.0034, H)
    assert m == 3 and alpha == pytest.approx(0.4, abs=1e-12)
    assert sample_taps(0.004 + 1e-15, H) == (4, 0.0)  # rounding is whole
    assert sample_taps(0.004 + 1e-10, H)[1] == pytest.approx(1e-7)  # a fit's step is not
    assert sample_taps(0.0, H) == (0, 0.0)
    m, alpha = sample_taps(0.0003, H)
    assert m == 0 and alpha == pytest.approx(0.3)


@pytest.mark.parametrize("delay_s", [0.0003, 0.0034, 0.0071])
def test_the_diagram_reads_what_the_readings_law_says(delay_s):
    sensor = ForceSensorDelay(SensorParams(delay_s), "sampled", H)
    builder = DiagramBuilder()
    source = builder.AddSystem(Sine(1.0, 7.0, 0.3, 1))
    delay = builder.AddSystem(sensor)
    builder.Connect(source.get_output_port(0), delay.GetInputPort("force"))
    log = LogVectorOutput(delay.GetOutputPort("measured_force"), builder, H)
    diagram = builder.Build()
    sim = Simulator(diagram)
    sim.AdvanceTo(0.05)
    got = log.FindLog(sim.get_context()).data()[0]
    t = np.arange(len(got)) * H
    force = np.sin(7.0 * t + 0.3)
    expected = sensor.readings(force)
    np.testing.assert_array_equal(got[5:], expected[5:])
    # and it is the force (1 - alpha) M ticks and alpha M + 1 ticks back
    m, alpha = sample_taps(delay_s, H)
    k = np.arange(m + 1, len(got))
    np.testing.assert_allclose(
        got[k], (1 - alpha) * force[k - m] + alpha * force[k - m - 1], rtol=0, atol=1e-15
    )


@pytest.mark.parametrize("compensator", ["none", "SDMDC"])
def test_the_fast_engine_and_the_diagram_agree_between_ticks(compensator):
    base = table1_params(compensator).with_(sample_rate_hz=1000.0)
    cors = []
    for delay_s in (0.004, 0.0043, 0.0047, 0.005):
        p = base.with_physics(sensor_delay_s=delay_s)
        fast, diagram = simulate_fast(p).cor, simulate(p).metrics.cor
        assert fast == pytest.approx(diagram, abs=1e-9)
        cors.append(fast)
    # a delay between two ticks gives a CoR between theirs, in order
    assert cors[0] < cors[1] < cors[2] < cors[3]
