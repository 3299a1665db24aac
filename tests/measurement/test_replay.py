"""Replay of a recorded command and the closed-loop rig model, against an
independent fixed-step RK4 simulation of the rig (tests/generators/rigsim.py) and closed
forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.systems.framework import Diagram, DiagramBuilder

from hybridtable.errors import ParameterError
from hybridtable.measurement.replay import replay, replay_command
from hybridtable.measurement.rig import RigPhysics, rig_params, simulate_rig
from hybridtable.measurement.run_format import RunInfo
from hybridtable.measurement.run_reader import read_run
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.noise import MeasurementNoiseParams
from hybridtable.systems.resonant_table import ResonantTable, StructuralModeParams
from hybridtable.systems.table import SecondOrderTable, TableParams, table_step_response
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record, write_run

#: A rig unlike the examples: 500 Hz, 3-tick delay, slower and less damped table, MDC.
OTHER_RIG = dict(
    NOMINAL,
    run_id="other-rig",
    sample_rate_hz=500,
    sensor_delay_s=0.006,
    table_natural_frequency_hz=20.0,
    table_damping_ratio=0.5,
    compensator="MDC",
    spacecraft_mass_kg=400.0,
    contact_stiffness_n_per_m=40000.0,
    initial_velocity_m_per_s=0.1,
)


def read_info(info: dict) -> RunInfo:
    return RunInfo(**info)


def _noiseless_run(tmp_path, info, contact=None, duration_s=0.9):
    cols = simulate_record(info, contact, duration_s=duration_s, noise_f_n=0.0, noise_p_m=0.0)
    return read_run(write_run(tmp_path, info["run_id"], info, cols)), cols


@pytest.mark.parametrize("info", [NOMINAL, OTHER_RIG], ids=["examples_rig", "other_rig"])
def test_replay_reproduces_an_independent_simulation(tmp_path, info):
    run, cols = _noiseless_run(tmp_path, info)
    rep = replay(run)
    # The CSV holds 10 significant digits; the rest is integration error.
    assert np.abs(rep.p_act_m - run.p_act_m).max() < 1e-9
    assert np.abs(rep.f_mea_n - run.f_mea_n).max() < 1e-3
    assert np.abs(rep.f_act_n - cols["f_act_n"]).max() < 1e-3
    assert run.f_mea_n.max() > 300.0  # a real contact was replayed


def test_sampled_sensor_is_an_exact_shift(tmp_path):
    run, _ = _noiseless_run(tmp_path, OTHER_RIG)
    rep = replay(run)
    m = 3
    np.testing.assert_array_equal(rep.f_mea_n[m:], rep.f_act_n[:-m])
    np.testing.assert_array_equal(rep.f_mea_n[:m], 0.0)


def test_command_is_held_from_its_tick():
    """A step in the command sent at tick j moves the table from t_j on, as the
    closed-form step response of the second-order table."""
    info = dict(NOMINAL, table_natural_frequency_hz=25.0, table_damping_ratio=0.6)
    params = rig_params(read_info(info)).with_(table_initial_state="rest", initial_gap_m=0.0)
    h, n, j, step = 1e-3, 120, 7, 2e-3
    p_des = np.where(np.arange(n) >= j, step, 0.0)
    rep = replay_command(params, p_des, np.zeros(n))
    expected = step * table_step_response(TableParams(25.0, 0.6), (np.arange(n) - j) * h)
    expected[:j] = 0.0
    np.testing.assert_allclose(rep.p_act_m, expected, rtol=0, atol=1e-10)
    assert rep.p_act_m[j] == 0.0 and rep.p_act_m[j + 1] > 0.0


def test_closed_loop_reproduces_an_independent_simulation(tmp_path):
    run, _ = _noiseless_run(tmp_path, OTHER_RIG)
    model = simulate_rig(run)
    assert len(model.time_s) == run.n
    np.testing.assert_allclose(model.v_des_m_per_s, run.v_des_m_per_s, rtol=0, atol=1e-8)
    np.testing.assert_allclose(model.f_comp_n, run.f_comp_n, rtol=0, atol=1e-3)
    np.testing.assert_allclose(model.p_des_m, run.p_des_m, rtol=0, atol=1e-10)


def test_closed_loop_runs_on_the_fast_engine_where_it_can(tmp_path):
    """The nominal systems (parameter changes only) run on the exact discrete
    engine, one step a tick; a system factory, measurement noise or a fixed-step
    integrator on the diagram, whose rows agree within its integrator's error."""
    run, _ = _noiseless_run(tmp_path, OTHER_RIG)
    fast = simulate_rig(run, RigPhysics(changes={"contact_damping_n_s_per_m": 50.0}))
    assert fast.steps == run.n
    factory = RigPhysics(
        table=lambda p: SecondOrderTable(p.plant.table),
        changes={"contact_damping_n_s_per_m": 50.0},
    )
    diagram = simulate_rig(run, factory)
    assert diagram.steps > 2 * run.n  # the table integrated between the ticks
    for name, x in fast.signals().items():
        y = getattr(diagram, name)
        assert np.max(np.abs(x - y)) <= 1e-6 * np.max(np.abs(y)), name
    fixed = simulate_rig(run, integrator="runge_kutta2")
    assert fixed.steps != run.n
    noisy = simulate_rig(run, noise=MeasurementNoiseParams(force_std_n=1.0, seed=3))
    assert noisy.steps != run.n


def test_physics_variants_swap_in(tmp_path):
    """A damped contact given as a parameter change or as a system factory
    reproduces a damped rig, replay and closed loop; the compensator keeps the
    nominal beliefs."""
    k, c = NOMINAL["contact_stiffness_n_per_m"], 500.0
    info = dict(NOMINAL, run_id="damped")
    run, cols = _noiseless_run(tmp_path, info, damped_spring(k, c))
    nominal = replay(run)
    assert np.abs(nominal.f_mea_n - run.f_mea_n).max() > 20.0  # the effect is visible
    by_change = RigPhysics(changes={"contact_damping_n_s_per_m": c}, name="damped")
    by_factory = RigPhysics(
        contact=lambda p: UnilateralSpringContact(ContactParams(k, c)), name="damped"
    )
    for physics in (by_change, by_factory):
        rep = replay(run, physics)
        assert np.abs(rep.f_mea_n - run.f_mea_n).max() < 1e-3
        loop = simulate_rig(run, physics)
        np.testing.assert_allclose(loop.v_des_m_per_s, run.v_des_m_per_s, rtol=0, atol=1e-8)
    p = by_change.apply(rig_params(run.info))
    assert p.contact_damping_n_s_per_m == c
    assert p.compensator_params().damping_n_s_per_m == 0.0
    stiffer = RigPhysics(changes={"contact_stiffness_n_per_m": 2 * k}).apply(rig_params(run.info))
    assert stiffer.compensator_params().stiffness_n_per_m == k
    with pytest.raises(ParameterError, match="compensator"):
        RigPhysics(changes={"compensator": "MDC"})


def test_rig_params_follow_the_format():
    p = rig_params(read_info(NOMINAL))
    assert p.sample_period_s == pytest.approx(1e-3)
    assert p.clamp_nonnegative and p.contact_gate == "measured_force"
    assert p.table_initial_state == "command" and p.contact_damping_n_s_per_m == 0.0
    cp = p.compensator_params()
    assert (cp.kind, cp.lead_time_s, cp.force_deadband_n) == ("SDMDC", 0.004, 6.0)
    assert math.isclose(cp.stiffness_n_per_m, NOMINAL["contact_stiffness_n_per_m"])


class _ContinuousOnly(Diagram):
    """A linear table hidden in a diagram without ``sampled()``: the replay
    must integrate it (the continuous path)."""

    def __init__(self, table) -> None:
        Diagram.__init__(self)
        builder = DiagramBuilder()
        self._table = builder.AddSystem(table)
        builder.ExportInput(self._table.GetInputPort("commanded_state"), "commanded_state")
        builder.ExportOutput(self._table.GetOutputPort("motion"), "motion")
        builder.BuildInto(self)

    def set_initial_state(self, context, p, v):
        self._table.set_initial_state(self.GetSubsystemContext(self._table, context), p, v)


@pytest.mark.parametrize("mode", [None, StructuralModeParams(70.0, 0.05)])
def test_the_sampled_table_is_the_integrated_one_at_the_ticks(tmp_path, mode):
    run, _ = _noiseless_run(tmp_path, OTHER_RIG, damped_spring(40000.0, 300.0))

    def table(params):
        if mode is None:
            return SecondOrderTable(params.plant.table)
        return ResonantTable(params.plant.table, mode)

    fast = replay(run, RigPhysics(table=table))
    slow = replay(run, RigPhysics(table=lambda p: _ContinuousOnly(table(p))), accuracy=1e-11)
    assert fast.steps < slow.steps  # no integrator: one event per tick
    peak = float(np.max(np.abs(slow.f_mea_n)))
    assert np.max(np.abs(fast.f_mea_n - slow.f_mea_n)) < 1e-8 * peak
    assert np.max(np.abs(fast.p_act_m - slow.p_act_m)) < 1e-11
    assert np.max(np.abs(fast.v_act_m_per_s - slow.v_act_m_per_s)) < 1e-9
