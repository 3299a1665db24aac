"""The 6-DoF loop (Drake) against an independent numpy rig (tests/generators/rig6.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.params import DockingContactParams
from hybridtable.six_dof.simulation import simulate6
from tests.generators.rig6 import pad_ring, simulate_rig6, wrench, wrench_jacobians
from tests.six_dof.conftest import MASS_KG, docking_params

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

INERTIA = (1689.0, 2100.0, 2600.0)


def test_drake_contact_wrench_and_stiffness_are_the_pads_on_a_plane():
    """Drake's point contact of the pad ring on the plate gives the wrench of
    linear springs on the pads, and its linearization their K, at random
    tilted, offset, moving poses (damped contact); the closed-form K and C
    equal the generator's central differences to 1e-6 of their largest entry."""
    params = DockingContactParams(1e5, contact_dissipation_s_per_m=0.4)
    contact = DockingContact(params)
    pads = pad_ring(8, 0.3, 0.01)
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = np.concatenate(
            [rng.uniform(-0.05, 0.05, 2), [rng.uniform(-0.01, 0.02)], rng.uniform(-0.05, 0.05, 3)]
        )
        qd = rng.uniform(-0.1, 0.1, 6)
        expected, _ = wrench(q, qd, pads, 1e5 / 8, 0.4, 0.01)
        np.testing.assert_allclose(contact.wrench(q, qd), expected, atol=1e-6 * 1e5 * 0.03)
        K, C = contact.stiffness(q, qd)
        K_ref, C_ref = wrench_jacobians(q, qd, pads, 1e5 / 8, 0.4, 0.01, damped=True)
        # The closed form against the generator's central differences: 1e-6.
        np.testing.assert_allclose(K, K_ref, atol=1e-6 * np.abs(K_ref).max())
        np.testing.assert_allclose(C, C_ref, atol=1e-6 * np.abs(C_ref).max())


@pytest.mark.parametrize("compensator", ["none", "SDC", "MDC", "SDMDC"])
def test_offset_tilted_contact_matches_the_independent_rig(compensator):
    """10 mm lateral offset, 2 deg pitch, anisotropic inertia, 25 Hz table,
    5 ms delay: CoR along the normal, energy ratio, peak force and moment
    agree with the independent rig."""
    params = docking_params(
        0.01,
        2.0,
        inertia=INERTIA,
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        compensator=compensator,
    )
    run = simulate6(params).metrics
    ref = simulate_rig6(
        mass_kg=MASS_KG,
        inertia_kg_m2=INERTIA,
        lateral_offset_m=(0.01, 0.0),
        misalignment_rad=(0.0, np.radians(2.0)),
        table_response_hz=25.0,
        sensor_delay_s=0.005,
        compensator=compensator,
    )
    assert run.cor_normal == pytest.approx(ref["cor_normal"], abs=1e-4)
    assert run.energy_ratio == pytest.approx(ref["energy_ratio"], abs=1e-4)
    assert run.peak_force_n == pytest.approx(ref["peak_force_n"], rel=1e-3)
    assert run.peak_moment_n_m == pytest.approx(ref["peak_moment_n_m"], rel=1e-3)


def test_damped_contact_matches_the_independent_rig():
    """A Hunt–Crossley contact (d = 0.5 s/m) with SDMDC and its 6x6 damping."""
    params = docking_params(0.02, 1.0, dissipation=0.5, sensor_delay_s=0.003, compensator="SDMDC")
    run = simulate6(params).metrics
    ref = simulate_rig6(
        mass_kg=MASS_KG,
        lateral_offset_m=(0.02, 0.0),
        misalignment_rad=(0.0, np.radians(1.0)),
        hunt_crossley_dissipation_s_per_m=0.5,
        sensor_delay_s=0.003,
        compensator="SDMDC",
    )
    assert run.cor_normal == pytest.approx(ref["cor_normal"], abs=1e-4)
    assert run.energy_ratio == pytest.approx(ref["energy_ratio"], abs=1e-4)
