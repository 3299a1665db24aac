"""Stewart plant contact: static stiffness from the F/T weld, passive bounce, dissipation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from hybridtable.errors import ParameterError
from hybridtable.stewart.backend import StewartTable
from hybridtable.stewart.hunt_crossley import hunt_crossley_cor, hunt_crossley_dissipation
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.plant import add_stewart_plant


def _pressed_table(stiffness: float, offset_m: float, params: StewartParams):
    """The table held at ``offset_m`` (penetration) until static; returns the
    table, the plant and their root context."""
    builder = DiagramBuilder()
    table = builder.AddSystem(StewartTable(params, stiffness))
    command = builder.AddSystem(ConstantVectorSource(np.array([offset_m, 0.0])))
    builder.Connect(command.get_output_port(), table.GetInputPort("commanded_state"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    table.set_initial_state(table.GetMyMutableContextFromRoot(context), -0.002, 0.0)
    simulator.AdvanceTo(0.4)
    return table, context


@pytest.mark.parametrize("stiffness", [1e4, 1e5, 1e6])
def test_static_contact_stiffness_from_the_sensor_is_k_con(stiffness):
    table, context = _pressed_table(stiffness, 0.004, StewartParams())
    table_context = table.GetMyContextFromRoot(context)
    p, v, _ = table.GetOutputPort("motion").Eval(table_context)
    force, rate = table.GetOutputPort("sensed_force").Eval(table_context)
    assert abs(v) < 1e-6 and abs(rate) < 1e-2 * stiffness * 1e-3  # static
    assert p > 0.003
    # Each geometry gets 2 k: in series they make k.
    assert force / p == pytest.approx(stiffness, rel=0.02)
    # The weld reaction (with the device's weight removed) equals the contact
    # force the plant reports.
    plant = table.plant
    results = plant.get_contact_results_output_port().Eval(plant.GetMyContextFromRoot(context))
    assert results.num_point_pair_contacts() == 1
    f_contact = results.point_pair_contact_info(0).contact_force()
    assert abs(f_contact[2]) == pytest.approx(force, rel=1e-6)
    # The raw wrench carries the device's weight too (gravity on, device
    # frame aligned with the world at rest).
    wrench = table.GetOutputPort("sensor_wrench").Eval(table_context)
    weight = table.params.geometry.device_mass_kg * table.params.gravity_m_per_s2
    assert wrench[5] == pytest.approx(force + weight, rel=1e-4)


def _passive_bounce(time_step_s: float, stiffness: float, dissipation: float, v0: float) -> float:
    """CoR of the unpowered platform (no gravity) hitting the passive device."""
    params = StewartParams(time_step_s=time_step_s, gravity_m_per_s2=0.0)
    builder = DiagramBuilder()
    handles = add_stewart_plant(builder, params, stiffness, dissipation)
    zero = builder.AddSystem(ConstantVectorSource(np.zeros(6)))
    builder.Connect(zero.get_output_port(), handles.plant.get_actuation_input_port())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    plant_context = handles.plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    handles.set_axis_state(plant_context, -0.0005, v0)
    simulator.AdvanceTo(0.35)
    v_out = handles.plant.EvalBodySpatialVelocityInWorld(plant_context, handles.plate)
    return -v_out.translational()[2] / v0


def test_passive_bounce_without_dissipation_keeps_its_energy():
    # The plate (~75 kg with legs) on k = 1e5: w ~ 36 rad/s. The discrete
    # contact (implicit in the stiffness) loses about exp(-pi w h / 2).
    fine = _passive_bounce(1e-4, 1e5, 0.0, 0.1)
    assert fine >= 0.99
    coarse = _passive_bounce(2e-4, 1e5, 0.0, 0.1)
    # First-order numerical loss: halving the step halves it.
    assert (1.0 - coarse) / (1.0 - fine) == pytest.approx(2.0, rel=0.15)


def test_hunt_crossley_dissipation_gives_the_viscous_cor():
    # Small-dissipation limit of the HC impact: e = 1 - (2/3) d v.
    assert hunt_crossley_cor(1e-3) == pytest.approx(1.0 - 2e-3 / 3, abs=1e-6)
    k, m, v = 1e5, 2533.0, 0.1
    c = 2000.0
    zeta = c / (2 * math.sqrt(k * m))
    d = hunt_crossley_dissipation(k, c, m, v)
    assert hunt_crossley_cor(d * v) == pytest.approx(
        math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)), abs=1e-8
    )
    assert hunt_crossley_dissipation(k, 0.0, m, v) == 0.0
    with pytest.raises(ParameterError, match="damping ratio"):
        hunt_crossley_dissipation(k, 3 * math.sqrt(k * m), m, v)


def test_dissipation_in_the_plant_lowers_the_bounce_cor_as_hunt_crossley_says():
    k, v0, h = 1e5, 0.1, 1e-4
    elastic = _passive_bounce(h, k, 0.0, v0)
    d = 0.5  # s/m: d v = 0.05, e_HC = 0.967
    damped = _passive_bounce(h, k, d, v0)
    # The plant's numerical loss multiplies the Hunt–Crossley one.
    assert damped / elastic == pytest.approx(hunt_crossley_cor(d * v0), abs=0.01)
