"""Table response model: the step response matches the closed form."""

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from hybridtable import ParameterError, SecondOrderTable, TableParams
from hybridtable.systems.table import table_step_response


def _simulate(table, command, t_end, x0=(0.0, 0.0)):
    builder = DiagramBuilder()
    src = builder.AddSystem(ConstantVectorSource(np.asarray(command, dtype=float)))
    tab = builder.AddSystem(table)
    builder.Connect(src.get_output_port(), tab.GetInputPort("commanded_state"))
    log = LogVectorOutput(tab.GetOutputPort("motion"), builder, 1e-3)
    diagram = builder.Build()
    sim = Simulator(diagram)
    ctx = sim.get_mutable_context()
    tab.set_initial_state(tab.GetMyMutableContextFromRoot(ctx), *x0)
    sim.get_mutable_integrator().set_target_accuracy(1e-11)
    sim.AdvanceTo(t_end)
    lg = log.FindLog(ctx)
    return lg.sample_times(), lg.data()


@pytest.mark.parametrize("zeta", [0.0, 0.3, 0.8, 1.0, 1.7])
def test_step_response_matches_closed_form(zeta):
    params = TableParams(25.0, zeta)
    t, y = _simulate(SecondOrderTable(params), [1e-3, 0.0], 0.3)
    expected = 1e-3 * table_step_response(params, t)
    np.testing.assert_allclose(y[0], expected, atol=2e-9)
    # Acceleration output is w^2 (p_des - p) - 2 zeta w v.
    w = params.omega_rad_per_s
    np.testing.assert_allclose(y[2], w * w * (1e-3 - y[0]) - 2 * zeta * w * y[1], atol=1e-9)


def test_closed_form_overshoot():
    # Peak overshoot of an underdamped second-order system: exp(-pi z / sqrt(1 - z^2)).
    params = TableParams(10.0, 0.4)
    t = np.linspace(0, 0.5, 200001)
    y = table_step_response(params, t)
    assert y.max() - 1 == pytest.approx(math.exp(-math.pi * 0.4 / math.sqrt(1 - 0.16)), rel=1e-6)


def test_ramp_lag_is_two_zeta_over_omega():
    params = TableParams(25.0, 0.8)
    v = 0.1
    lag = params.ramp_lag_s
    assert lag == pytest.approx(2 * 0.8 / (2 * math.pi * 25.0))
    # Started in steady tracking of a ramp, the table stays exactly lag behind.
    from pydrake.systems.primitives import Integrator

    builder = DiagramBuilder()
    vel = builder.AddSystem(ConstantVectorSource([v, 0.0]))
    integ = builder.AddSystem(Integrator(2))
    builder.Connect(vel.get_output_port(), integ.get_input_port())
    tab = builder.AddSystem(SecondOrderTable(params))
    from pydrake.systems.primitives import Adder

    add = builder.AddSystem(Adder(2, 2))
    const_v = builder.AddSystem(ConstantVectorSource([0.0, v]))
    builder.Connect(integ.get_output_port(), add.get_input_port(0))
    builder.Connect(const_v.get_output_port(), add.get_input_port(1))
    builder.Connect(add.get_output_port(), tab.GetInputPort("commanded_state"))
    diagram = builder.Build()
    sim = Simulator(diagram)
    ctx = sim.get_mutable_context()
    tab.set_initial_state(tab.GetMyMutableContextFromRoot(ctx), -lag * v, v)
    sim.get_mutable_integrator().set_target_accuracy(1e-11)
    sim.AdvanceTo(0.4)
    p, pv, _ = tab.GetOutputPort("motion").Eval(tab.GetMyContextFromRoot(ctx))
    assert p == pytest.approx(0.4 * v - lag * v, abs=1e-10)
    assert pv == pytest.approx(v, abs=1e-9)


def test_ideal_table_follows_the_command():
    t, y = _simulate(SecondOrderTable(TableParams(math.inf)), [2e-3, 0.3], 0.01)
    np.testing.assert_allclose(y[0], 2e-3)
    np.testing.assert_allclose(y[1], 0.3)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"response_frequency_hz": 0.0}, "response_frequency_hz"),
        ({"response_frequency_hz": float("nan")}, "response_frequency_hz"),
        ({"damping_ratio": -0.1}, "damping_ratio"),
    ],
)
def test_bad_parameters_name_the_field(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        TableParams(**kwargs)


def _drake_ticks(sampled, commands, x0):
    """The sampled table's own Drake system, tick by tick: the output ``motion``
    at each tick for the command sent there, then its discrete update."""
    ctx = sampled.CreateDefaultContext()
    sampled.set_initial_state(ctx, *x0)
    port = sampled.get_input_port()
    linear = sampled.GetSubsystemByName("sampled_table")
    inner = sampled.GetMutableSubsystemContext(linear, ctx)
    out = []
    for u in commands:
        port.FixValue(ctx, u)
        out.append(sampled.get_output_port().Eval(ctx).copy())
        update = linear.EvalUniquePeriodicDiscreteUpdate(inner)
        inner.SetDiscreteState(update.get_vector().CopyToVector())
    return np.array(out)


@pytest.mark.parametrize("compiled", [False, True], ids=["python", "compiled"])
def test_the_sampled_response_is_its_drake_system_bit_for_bit(monkeypatch, compiled):
    """``SampledTable.respond`` (the replay's table, no simulator) gives what its
    Drake system computes, bit for bit, in Python and compiled by numba; for
    the second-order table and one with a structural mode (four states)."""
    from hybridtable.systems import table as table_module
    from hybridtable.systems.resonant_table import ResonantTable, StructuralModeParams

    monkeypatch.setattr(table_module, "COMPILE_AFTER_RESPONSES", 0 if compiled else 10**12)
    monkeypatch.setattr(table_module, "_compiled_states", None)
    rng = np.random.default_rng(7)
    for params, mode, h in [
        (TableParams(25.0, 0.8), None, 1e-3),
        (TableParams(60.0, 0.3), StructuralModeParams(140.0, 0.02), 5e-4),
    ]:
        table = SecondOrderTable(params) if mode is None else ResonantTable(params, mode)
        sampled = table.sampled(h)
        commands = np.column_stack([np.cumsum(rng.normal(size=400)) * 1e-4, rng.normal(size=400)])
        x0 = (0.002, -0.05)
        got = sampled.respond(commands, *x0)
        assert np.array_equal(got, _drake_ticks(sampled, commands, x0))
    assert bool(table_module._compiled_states) == compiled
