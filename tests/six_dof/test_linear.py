"""The 6-DoF loop linearized in contact: modes against closed forms and the simulation."""

from __future__ import annotations

import math

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
