"""Linear models of the in-contact loop from Drake's Linearize (hybridtable.analysis.linearize,
hybridtable.analysis.blockwise, hybridtable.analysis.sampled, hybridtable.analysis.interconnect)."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.interconnect import Interconnection, StateSpaceBlock
from hybridtable.analysis.linearize import linearize_contact_loop, linearize_system
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.compensators.paper import COMPENSATORS, Compensator
from hybridtable.errors import InterconnectionError, LinearizationError
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import run_loop
from hybridtable.studies.paper import paper_params
from hybridtable.systems.contact import UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable, TableParams, table_matrices
from tests.analysis.support import damped


@pytest.mark.parametrize("comp", COMPENSATORS)
def test_assembled_model_equals_direct_linearize_of_full_diagram(lin, comp):
    # Block-wise linearization + assembly against Drake's Linearize of the
    # whole diagram, at points that exercise every parameter scaling.
    points = [
        paper_params(compensator=comp),
        paper_params(compensator=comp, sensor_delay_s=0.0137, table_response_hz=7.5),
        damped(paper_params(compensator=comp, sensor_delay_s=0.002, table_damping_ratio=0.3), 0.2),
        paper_params(compensator=comp, sensor_delay_s=0.0, table_response_hz=180.0),
        paper_params(compensator=comp, table_response_hz=math.inf, lead_time_s=0.011),
    ]
    for p in points:
        assert lin.verify(p) < 1e-8
        a, b = lin.open_loop(p), linearize_contact_loop(p, 3)
        assert a.A.shape == b.A.shape


def test_other_pade_orders_match_direct_linearize():
    for order in (1, 2, 5):
        ContactLoopLinearizer(order).verify(paper_params(compensator="SDMDC", sensor_delay_s=0.008))


def test_undelayed_ideal_loop_is_the_physical_contact(lin):
    # T = 0, ideal table, no compensation: G(s) = -(k + c s) / (m s^2) exactly.
    p = damped(paper_params(sensor_delay_s=0.0, table_response_hz=math.inf), 0.1)
    m, k, c = p.spacecraft_mass_kg, p.contact_stiffness_n_per_m, p.contact_damping_n_s_per_m
    s = np.array([0.3j, 2j, 1 + 5j, 40j])
    np.testing.assert_allclose(lin.open_loop(p).transfer(s), -(k + c * s) / (m * s * s), rtol=1e-12)


def test_mdc_makes_the_slow_table_transparent_without_delay(lin):
    # MDC adds k (p_des - p_act): with T = 0 the fed-back force is k p_des,
    # whatever the table does, so G = -k / (m s^2).
    p = paper_params(compensator="MDC", sensor_delay_s=0.0, table_response_hz=5.0)
    s = np.array([1j, 3j, 30j])
    np.testing.assert_allclose(
        lin.open_loop(p).transfer(s),
        -p.contact_stiffness_n_per_m / (p.spacecraft_mass_kg * s * s),
        rtol=1e-10,
    )


def test_table_block_equals_table_matrices(lin):
    for f, z in ((3.0, 0.2), (25.0, 0.8), (400.0, 1.5)):
        b = lin.table_block(TableParams(f, z))
        A, B, C, D = table_matrices(TableParams(f, z))
        for x, y in ((b.A, A), (b.B, B), (b.C, C), (b.D, D)):
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * abs(y).max())


def test_pade_block_is_control_pade(lin):
    T = 0.0123
    blk = lin.sensor_block(T)
    num, den = control.pade(T, 3)
    w = np.array([10.0, 100.0, 600.0])
    ref = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    H = blk.transfer(1j * w)
    np.testing.assert_allclose(H[:, 0, 0], ref, rtol=1e-10)
    np.testing.assert_allclose(H[:, 1, 1], ref, rtol=1e-10)
    np.testing.assert_allclose(H[:, 0, 1], 0.0, atol=1e-12)


def test_sampled_sensor_linearizes_to_pure_sample_delay():
    S = SampledLoopLinearizer()
    h = 1e-3
    for m in (0, 1, 4):
        blk = S.sensor_block(m * h, h)
        z = np.exp(1j * np.array([0.1, 1.0, 2.5]))
        np.testing.assert_allclose(blk.transfer(z)[:, 0, 0], z ** (-m), rtol=1e-12)


@pytest.mark.parametrize(
    "comp,table_hz",
    [("SDMDC", 25.0), ("none", math.inf), ("SDC", 12.0), ("MDC", math.inf)],
)
def test_sampled_model_reproduces_drake_sampled_loop_tick_by_tick(comp, table_hz):
    # The linear sampled loop simulated by Drake (bilateral contact, ungated
    # compensator, rig-computer semantics of add_hybrid_loop) must equal the
    # sampled-data model iterated from the same state, to round-off.
    p = paper_params(
        compensator=comp,
        sensor_delay_s=0.004,
        table_response_hz=table_hz,
        sample_rate_hz=500.0,
        table_initial_state="rest",
        initial_gap_m=0.0,
    )
    h = p.sample_period_s
    loop = build_hybrid_loop(
        p,
        contact=UnilateralSpringContact(p.plant.contact, bilateral=True),
        compensator=Compensator(p.compensator_params(), derivative_period_s=h, gated=False),
    )
    sim = run_loop(loop, t_max_s=0.4, stop_at_separation=False, accuracy=1e-12)
    model = SampledLoopLinearizer().open_loop(p)
    A = np.asarray(model.closed_loop().A)
    C = np.asarray(model.closed_loop().C)
    # State: spacecraft [p, v], table [p, v] (if any) + held command, delay line, lead memory.
    x = np.zeros(A.shape[0])
    x[1] = p.initial_velocity_m_per_s
    ntab = 0 if math.isinf(table_hz) else 2
    x[2 + ntab : 4 + ntab] = x[0:2]
    f_comp = []
    for _ in range(len(sim.time_s)):
        f_comp.append((C @ x)[0])
        x = A @ x
    scale = np.abs(sim.f_comp_n).max()
    assert scale > 100.0
    np.testing.assert_allclose(np.array(f_comp), sim.f_comp_n, rtol=0, atol=1e-9 * scale)


def test_closed_loop_matrix_is_control_feedback(lin):
    model = lin.open_loop(paper_params(compensator="SDMDC"))
    ev_fast = np.sort_complex(model.closed_loop_poles())
    ev_ctrl = np.sort_complex(np.linalg.eigvals(np.asarray(model.closed_loop().A)))
    np.testing.assert_allclose(ev_fast, ev_ctrl, rtol=1e-9, atol=1e-9)


def test_drake_refusal_is_a_linearization_error():
    # Continuous table driven by a discrete spacecraft: Drake's Linearize
    # refuses mixed continuous/discrete state (a C++ assert in pydrake).
    b = DiagramBuilder()
    sc = b.AddSystem(Spacecraft(SpacecraftParams(1.0), sample_period_s=1e-3))
    tb = b.AddSystem(SecondOrderTable(TableParams(10.0)))
    b.Connect(sc.GetOutputPort("state"), tb.GetInputPort("commanded_state"))
    b.ExportInput(sc.GetInputPort("force"))
    b.ExportOutput(tb.GetOutputPort("motion"))
    with pytest.raises(LinearizationError):
        linearize_system(b.Build(), "mixed")


def test_linearize_system_names_every_port_channel():
    blk = linearize_system(
        ForceSensorDelay(SensorParams(0.01), "pade", pade_order=2, size=2), "force_sensor"
    )
    assert blk.inputs == ("force_sensor.force[0]", "force_sensor.force[1]")
    assert blk.outputs == ("force_sensor.measured_force[0]", "force_sensor.measured_force[1]")
    assert blk.num_states == 4


def test_interconnection_rejects_bad_wiring():
    gain = StateSpaceBlock(
        "g", np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.eye(1), ("g.u",), ("g.y",)
    )
    with pytest.raises(InterconnectionError, match="unwired"):
        Interconnection([("g", gain.inputs, gain.outputs)], {}, [], ["g.y"])
    with pytest.raises(InterconnectionError, match="unknown"):
        Interconnection([("g", gain.inputs, gain.outputs)], {"g.u": "h.y"}, [], [])
    # u = y with unit gain: a singular algebraic loop.
    wiring = Interconnection([("g", gain.inputs, gain.outputs)], {"g.u": "g.y"}, [], ["g.y"])
    with pytest.raises(InterconnectionError, match="algebraic"):
        wiring.assemble([gain])


def test_interconnection_of_two_integrators_is_a_double_integrator():
    integ = [
        StateSpaceBlock(
            n,
            np.zeros((1, 1)),
            np.ones((1, 1)),
            np.ones((1, 1)),
            np.zeros((1, 1)),
            (f"{n}.u",),
            (f"{n}.y",),
        )
        for n in ("a", "b")
    ]
    wiring = Interconnection(
        [(b.name, b.inputs, b.outputs) for b in integ], {"b.u": "a.y"}, ["a.u"], ["b.y"]
    )
    m = wiring.assemble(integ)
    s = np.array([1j, 2 + 1j])
    np.testing.assert_allclose(m.transfer(s)[:, 0, 0], 1 / s**2, rtol=1e-14)


def test_held_tick_is_the_zero_order_hold_solution():
    from scipy.linalg import expm

    from hybridtable.laws.table import held_tick

    rng = np.random.default_rng(3)
    w = 2 * math.pi * 200.0  # a stiff table over a 1 ms period, as in the ZOH
    stiff = (np.array([[0.0, 1.0], [-w * w, -1.6 * w]]), np.array([[0.0], [w * w]]))
    cases = (stiff, (rng.standard_normal((5, 5)), rng.standard_normal((5, 2))))
    for A, B in cases:
        n, m = B.shape
        big = np.zeros((n + m, n + m))
        big[:n, :n], big[:n, n:] = A, B
        ref = expm(big * 1e-3)
        Phi, Gamma = held_tick(A, B, 1e-3)
        scale = np.abs(ref).max()
        np.testing.assert_allclose(Phi, ref[:n, :n], rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(Gamma, ref[:n, n:], rtol=0, atol=1e-12 * scale)
    # A double integrator under a held force: the closed form.
    Phi, Gamma = held_tick([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], 0.5)
    np.testing.assert_allclose(Phi, [[1.0, 0.5], [0.0, 1.0]], atol=1e-15)
    np.testing.assert_allclose(Gamma, [[0.125], [0.5]], atol=1e-15)
    assert held_tick(np.zeros((0, 0)), np.zeros((0, 1)), 1e-3)[0].shape == (0, 0)
