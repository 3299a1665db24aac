"""The 6-DoF loop linearized in contact: modes against closed forms and the simulation."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from hybridtable.six_dof.linear import contact_modes
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.conftest import INERTIA_KG_M2, docking_params


def _axial(modes):
    """The mode nearest the 1 Hz contact frequency."""
    i = min(range(len(modes.frequencies_hz)), key=lambda j: abs(modes.frequencies_hz[j] - 1.0))
    return modes.frequencies_hz[i], modes.growth_rates_per_s[i]


def test_modes_of_the_ideal_rig_are_the_contacts_closed_forms():
    """No delay, ideal table: the axial mode at sqrt(k/m), the tilt modes at
    sqrt(k a^2 / 2 / I) (the ring's tilt stiffness), none growing."""
    modes = contact_modes(docking_params())
    f_axial, growth = _axial(modes)
    assert f_axial == pytest.approx(1.0, rel=2e-3)
    tilt_hz = math.sqrt(1e5 * 0.3**2 / 2 / INERTIA_KG_M2[0]) / (2 * math.pi)
    assert min(modes.frequencies_hz) == pytest.approx(tilt_hz, rel=0.01)
    assert modes.stable
    assert modes.max_growth_rate_per_s < 1e-6


@pytest.mark.parametrize("compensator", ["none", "SDC", "MDC"])
def test_the_axial_modes_growth_predicts_the_simulated_cor(compensator):
    """exp(sigma pi / w_d) of the linearized axial mode is the simulated
    on-axis CoR within 0.5 % of CoR - 1 plus 1e-3."""
    params = docking_params(
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        compensator=compensator,
        stiffness_model="nominal",
    )
    f, sigma = _axial(contact_modes(params))
    predicted = math.exp(sigma * math.pi / (2 * math.pi * f))
    simulated = simulate6(params).metrics.cor_normal
    assert predicted == pytest.approx(simulated, abs=0.005 * (simulated - 1) + 1e-3)


def test_critical_delay_of_a_damped_contact_and_of_sdmdc():
    """A damped contact stands some delay before a mode grows; SDMDC (lead
    5 ms) keeps every mode from growing at shorter delays than without
    compensation."""
    damped = contact_modes(docking_params(dissipation=2.0, table_response_hz=25.0))
    assert 0.0 < damped.critical_delay_s < 0.05
    sdmdc = contact_modes(
        docking_params(
            dissipation=2.0, table_response_hz=25.0, sensor_delay_s=0.005, compensator="SDMDC"
        )
    )
    assert sdmdc.critical_delay_s > damped.critical_delay_s


def test_a_loop_that_grows_at_any_delay_has_a_critical_delay_of_zero():
    """Ideal table, undamped contact, no compensator: any delay above zero
    pumps energy (the 1-D loop's "critical delay zero"): the neutral loop at
    zero delay counts as reached, as in the 1-D search, rather than the delay
    within the first tick where its growth passes round-off (5e-8 s)."""
    from hybridtable.six_dof.contact import DockingContact
    from hybridtable.six_dof.linear import critical_delay_s

    p = docking_params(table_response_hz=math.inf)
    K, C = DockingContact(p.contact).stiffness(p.nominal_pose())
    assert critical_delay_s(p, K, C) == 0.0


def test_the_lead_follows_the_searched_delay_unless_the_scenario_states_it():
    """What the compensator believes unless told, as in the 1-D margins: with
    no lead stated, each delay searched is the rig's own delay, its lead
    told it; a stated lead stays at its value. SDC on a 25 Hz table: told
    its delay, the lead never covers the table's lag (critical delay 0: the
    loop told a 1 ms delay grows); held at 5 ms, it overcovers it at short
    delays, and the loop stays stable until the delay nears the lead."""
    p = docking_params(
        dissipation=1.0, table_response_hz=25.0, sensor_delay_s=0.005, compensator="SDC"
    )
    assert contact_modes(p).critical_delay_s == 0.0
    assert not contact_modes(p.with_(sensor_delay_s=0.001)).stable
    held = p.with_(lead_time_s=0.005)
    critical = contact_modes(held).critical_delay_s
    assert 0.001 < critical < 0.005
    assert contact_modes(held.with_(sensor_delay_s=0.97 * critical)).stable
    assert not contact_modes(held.with_(sensor_delay_s=1.03 * critical)).stable


def _predicted_cor(modes) -> float:
    f, sigma = _axial(modes)
    return math.exp(sigma * math.pi / (2 * math.pi * f))


def _gain(value: float) -> tuple:
    return tuple(tuple(row) for row in value * np.eye(6))


#: (compensator, effect, its values) of a model whose margins are checked
#: against its simulation; "sensor_gain" and "table_gain" are DockingPhysics'
#: own (every axis scaled alike: no coupling of the axial mode to the others).
MODELS = [
    ("SDC", "stiffness_error", {"contact_stiffness_n_per_m": 1.3e5}),
    ("SDC", "extra_delay", {"extra_delay_s": 0.002}),
    ("SDC", "sensor_filter", {"time_constant_s": 0.002}),
    ("SDC", "mount_resonance", {"mount_frequency_hz": 60.0, "mount_damping_ratio": 0.3}),
    ("SDC", "table_response", {"table_response_ratio": 0.8}),
    ("SDC", "lead_time_error", {"lead_error_s": -0.002}),
    ("SDC", "sensor_gain", 1.2),
    ("SDC", "table_gain", 0.9),
    ("SDMDC", "stiffness_error", {"contact_stiffness_n_per_m": 1.3e5}),
    ("SDMDC", "extra_delay", {"extra_delay_s": 0.002}),
    ("SDMDC", "compensator_stiffness_error", {"compensator_stiffness_ratio": 0.7}),
    ("SDMDC", "sensor_gain", 1.05),
]


@pytest.mark.parametrize(("compensator", "effect", "values"), MODELS)
def test_the_margins_of_a_model_are_of_its_rig(compensator, effect, values):
    """The loop linearized with an effect model's physics (its contact,
    delay, table, the sensor's gain, low pass and mount, the computer's lead
    and stiffness) predicts the CoR of the same rig simulated, as the
    nominal loop's does (within 0.5 % of CoR - 1 plus 1e-3), where the
    effect moves the prediction by several times that."""
    from hybridtable.effects.registry import get_effect
    from hybridtable.six_dof.physics6 import DockingPhysics, physics_with, rig_scale

    params = docking_params(
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        compensator=compensator,
        stiffness_model="nominal",
    )
    if effect in ("sensor_gain", "table_gain"):
        physics = DockingPhysics(**{effect: _gain(values)})
    else:
        physics = physics_with([(get_effect(effect), values)], rig_scale(params))
    predicted = _predicted_cor(contact_modes(params, physics=physics))
    simulated = simulate6(params, physics=physics).metrics.cor_normal
    tolerance = 0.005 * abs(simulated - 1) + 1e-3
    assert predicted == pytest.approx(simulated, abs=tolerance)
    assert abs(predicted - _predicted_cor(contact_modes(params))) > 2.0 * tolerance


def test_a_model_and_a_scenario_that_say_the_same_rig_have_the_same_margins():
    """A contact 30 % stiffer than the scenario, which the rig computer does
    not know (a model's stiffness_error), is the scenario of that contact
    whose compensator believes the old stiffness; and a given MDC matrix of
    half the contact's is a compensator believing half the stiffness (the
    given matrix was once ignored)."""
    from hybridtable.effects.registry import get_effect
    from hybridtable.six_dof.contact import DockingContact
    from hybridtable.six_dof.physics6 import physics_with, rig_scale

    params = docking_params(sensor_delay_s=0.005, table_response_hz=25.0, compensator="SDMDC")
    k = params.contact.contact_stiffness_n_per_m
    physics = physics_with(
        [(get_effect("stiffness_error"), {"contact_stiffness_n_per_m": 1.3 * k})], rig_scale(params)
    )
    told = params.with_(
        contact=replace(params.contact, contact_stiffness_n_per_m=1.3 * k),
        compensator_stiffness_n_per_m=k,
    )
    assert contact_modes(params, physics=physics) == contact_modes(told)
    K, _ = DockingContact(params.contact).stiffness(params.nominal_pose())
    given = params.with_(stiffness_model="given", compensator_stiffness_matrix=0.5 * K)
    half = params.with_(compensator_stiffness_n_per_m=0.5 * k)
    a, b = contact_modes(given), contact_modes(half)
    assert a.max_growth_rate_per_s == pytest.approx(b.max_growth_rate_per_s, rel=1e-9)
    assert a.frequencies_hz == pytest.approx(b.frequencies_hz, rel=1e-9)
    assert a.max_growth_rate_per_s > contact_modes(params).max_growth_rate_per_s + 1e-3
