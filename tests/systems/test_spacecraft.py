"""Spacecraft model (Eq. 1): momentum change equals the impulse of the force."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, Sine

from hybridtable import ParameterError, Spacecraft, SpacecraftParams


def _run(sample_period_s, t_end=1.0):
    m = 250.0
    builder = DiagramBuilder()
    # f(t) = 300 + 200 sin(3 t): impulse = 300 t + 200 (1 - cos 3t) / 3
    force = builder.AddSystem(Sine(200.0, 3.0, 0.0, 1))
    from pydrake.systems.primitives import Adder, ConstantVectorSource

    bias = builder.AddSystem(ConstantVectorSource([300.0]))
    add = builder.AddSystem(Adder(2, 1))
    builder.Connect(force.get_output_port(0), add.get_input_port(0))
    builder.Connect(bias.get_output_port(), add.get_input_port(1))
    sc = builder.AddSystem(Spacecraft(SpacecraftParams(m), sample_period_s=sample_period_s))
    builder.Connect(add.get_output_port(), sc.GetInputPort("force"))
    log = LogVectorOutput(sc.GetOutputPort("state"), builder)
    diagram = builder.Build()
    sim = Simulator(diagram)
    ctx = sim.get_mutable_context()
    sc.set_initial_state(sc.GetMyMutableContextFromRoot(ctx), 0.01, 0.2)
    sim.get_mutable_integrator().set_target_accuracy(1e-10)
    sim.AdvanceTo(t_end)
    return m, sc.GetOutputPort("state").Eval(sc.GetMyContextFromRoot(ctx)), log


def test_momentum_change_equals_impulse_continuous():
    m, x, _ = _run(None)
    impulse = 300.0 + 200.0 * (1.0 - np.cos(3.0)) / 3.0
    # The spacecraft is pushed by -f.
    assert m * (x[1] - 0.2) == pytest.approx(-impulse, rel=1e-8)


def test_momentum_change_equals_impulse_sampled():
    h = 1e-3
    m, x, _ = _run(h)
    # Semi-implicit Euler: v changes by -f(t_k) h / m at each tick t_k = k h
    # (ticks 0 .. 999 by t = 1 s; the tick at t = 1 is not yet applied).
    t = np.arange(1000) * h
    impulse = np.sum((300.0 + 200.0 * np.sin(3.0 * t)) * h)
    assert m * (x[1] - 0.2) == pytest.approx(-impulse, rel=1e-10)


def test_free_flight_is_uniform_motion():
    builder = DiagramBuilder()
    from pydrake.systems.primitives import ConstantVectorSource

    zero = builder.AddSystem(ConstantVectorSource([0.0]))
    sc = builder.AddSystem(Spacecraft(SpacecraftParams(10.0)))
    builder.Connect(zero.get_output_port(), sc.GetInputPort("force"))
    diagram = builder.Build()
    sim = Simulator(diagram)
    ctx = sim.get_mutable_context()
    sc.set_initial_state(sc.GetMyMutableContextFromRoot(ctx), -0.5, 0.1)
    sim.AdvanceTo(2.0)
    x = sc.GetOutputPort("state").Eval(sc.GetMyContextFromRoot(ctx))
    np.testing.assert_allclose(x, [-0.3, 0.1], atol=1e-12)


@pytest.mark.parametrize("mass", [0.0, -1.0, float("nan"), float("inf"), "heavy"])
def test_bad_mass_names_the_field(mass):
    with pytest.raises(ParameterError, match="mass_kg"):
        SpacecraftParams(mass)
