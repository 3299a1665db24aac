"""The pads' own normal law (the 1-D contact law per pad): with Drake's law it
is Drake's point contact; on the axis the ring is the 1-D law of the totals;
its 6x6 linearization is the derivative of its wrench; where it cannot act
(a drogue, the Stewart platform's plant) it is refused by name."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.errors import ParameterError
from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.devices import PAD_LAW_FIELDS, DockingContactParams
from hybridtable.six_dof.scenario import load_scenario, parse_scenario
from hybridtable.systems.contact_law import ContactLawParams, contact_law_force
from tests.six_dof.test_contact import central_differences, drakes_point_pairs

K = 1.0e5


def random_poses(seed: int, n: int):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = np.concatenate(
            [rng.normal(0.0, 0.01, 2), [rng.uniform(-0.002, 0.003)], rng.normal(0.0, 0.005, 3)]
        )
        qd = np.concatenate([rng.normal(0.0, 0.05, 3), rng.normal(0.0, 0.05, 3)])
        yield q, qd


def drakes_wrench(contact: DockingContact, q, qd) -> np.ndarray:
    """The pads' wrench summed from Drake's query (its point pairs)."""
    p, pairs = drakes_point_pairs(contact, q, qd)
    w = np.zeros(6)
    for point, force, _, _ in pairs:
        w[:3] += np.cross(point - p, force)
        w[3:] += force
    return w


def test_the_pads_wrench_is_drakes_query_by_either_law():
    """With Drake's law the wrench (the compiled closed form) and the pads'
    own law (the 1-D contact law per pad, with Drake's terms only) are both
    Drake's query of the same pose and twist, to round-off."""
    params = DockingContactParams(K, contact_dissipation_s_per_m=0.4, friction_coefficient=0.5)
    closed = DockingContact(params)
    own = DockingContact(params)
    own._pad_law = params.pad_law  # the pads' own law, with Drake's terms only
    touched = 0
    for q, qd in random_poses(0, 40):
        drake = drakes_wrench(closed, q, qd)
        touched += bool(np.any(drake != 0.0))
        for w in (closed.wrench(q, qd), own.wrench(q, qd)):
            np.testing.assert_allclose(
                w, drake, rtol=1e-12, atol=1e-9 * max(1.0, np.abs(drake).max())
            )
        for x, y in zip(closed.stiffness(q, qd), own.stiffness(q, qd), strict=True):
            np.testing.assert_allclose(y, x, rtol=1e-12, atol=1e-9 * max(1.0, np.abs(x).max()))
    assert touched > 20


@pytest.mark.parametrize(
    "law",
    [
        {"contact_exponent": 1.5, "reference_press_m": 0.002},
        {"contact_damping_n_s_per_m": 800.0},
        {"series_compliance_m_per_n": 3e-6},
        {"contact_exponent": 1.3, "series_compliance_m_per_n": 2e-6},
        {"normal_friction_force_n": 60.0, "normal_friction_velocity_m_per_s": 0.002},
    ],
)
@pytest.mark.parametrize("press_m, rate_m_per_s", [(0.001, 0.05), (0.004, -0.03)])
def test_on_the_axis_the_ring_is_the_one_dimensional_law_of_the_totals(law, press_m, rate_m_per_s):
    params = DockingContactParams(K, contact_dissipation_s_per_m=0.2, **law)
    contact = DockingContact(params)
    # every pad pressed alike: the pads' tops (z = 0 in the port frame) press by p_z
    q = np.array([0.0, 0.0, press_m, 0.0, 0.0, 0.0])
    qd = np.array([0.0, 0.0, rate_m_per_s, 0.0, 0.0, 0.0])
    w = contact.wrench(q, qd)
    one_d = ContactLawParams(
        stiffness_n_per_m=K,
        exponent=params.contact_exponent,
        reference_deflection_m=params.reference_press_m,
        damping_n_s_per_m=params.contact_damping_n_s_per_m,
        hunt_crossley_s_per_m=0.2,
        friction_force_n=params.normal_friction_force_n,
        friction_velocity_m_per_s=params.normal_friction_velocity_m_per_s,
        series_compliance_m_per_n=params.series_compliance_m_per_n,
    )
    f = float(contact_law_force(one_d, press_m, rate_m_per_s)[0])
    assert f > 0.0
    np.testing.assert_allclose(-w[5], f, rtol=1e-12)
    np.testing.assert_allclose(w[:5], 0.0, atol=1e-9 * f)


def test_a_power_law_pad_is_its_secant_stiffness_at_the_reference_press():
    x_ref = 0.003
    params = DockingContactParams(K, contact_exponent=1.5, reference_press_m=x_ref)
    contact = DockingContact(params)
    for press, expected in ((x_ref, K * x_ref), (x_ref / 4.0, K * x_ref / 8.0)):
        fz = contact.wrench(np.array([0.0, 0.0, press, 0.0, 0.0, 0.0]))[5]
        np.testing.assert_allclose(-fz, expected, rtol=1e-12)


def test_series_compliance_is_the_softer_spring_of_the_two_in_series():
    s = 4e-6
    contact = DockingContact(DockingContactParams(K, series_compliance_m_per_n=s))
    press = 0.002
    fz = contact.wrench(np.array([0.0, 0.0, press, 0.01, -0.02, 0.0]))[5]
    softer = DockingContact(DockingContactParams(K / (1.0 + K * s)))
    np.testing.assert_allclose(
        fz, softer.wrench(np.array([0.0, 0.0, press, 0.01, -0.02, 0.0]))[5], rtol=1e-12
    )


def test_a_pad_never_pulls_and_a_damper_lets_go_early():
    # separating faster than the spring pushes: c v > k x on every pad
    params = DockingContactParams(K, contact_damping_n_s_per_m=2.0e4)
    contact = DockingContact(params)
    q = np.array([0.0, 0.0, 0.0005, 0.0, 0.0, 0.0])
    assert np.all(contact.wrench(q, np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0])) == 0.0)
    assert contact.wrench(q, np.array([0.0, 0.0, -0.001, 0.0, 0.0, 0.0]))[5] < 0.0


@pytest.mark.parametrize(
    "law",
    [
        {"contact_exponent": 1.4, "reference_press_m": 0.002, "contact_damping_n_s_per_m": 500.0},
        {"series_compliance_m_per_n": 2e-6, "normal_friction_force_n": 40.0},
    ],
)
def test_the_closed_form_linearization_is_the_derivative_of_the_wrench(law):
    params = DockingContactParams(
        K, contact_dissipation_s_per_m=0.3, friction_coefficient=0.4, **law
    )
    contact = DockingContact(params)
    checked = 0
    for q, qd in random_poses(3, 30):
        qd[:2] += 0.01  # slipping well above the stiction tolerance: friction is smooth
        if not np.any(contact.wrench(q, qd)):
            continue
        Kc, Cc = contact.stiffness(q, qd)
        Kn, Cn = central_differences(contact, q, qd, 1e-8)
        scale = max(np.abs(Kc).max(), 1.0)
        assert np.abs(Kc - Kn).max() <= 1e-4 * scale
        assert np.abs(Cc - Cn).max() <= 1e-4 * max(np.abs(Cc).max(), 1.0)
        checked += 1
    assert checked >= 10


def test_the_law_is_refused_where_it_cannot_act():
    with pytest.raises(ParameterError, match="contact_exponent is a term of the pads' law"):
        DockingContactParams(K, geometry="cone", contact_exponent=1.5)
    stewart = load_scenario("examples/six_dof/stewart.toml")
    with pytest.raises(ParameterError, match="normal_friction_force_n: the Stewart platform"):
        stewart.with_(normal_friction_force_n=10.0)
    with pytest.raises(ParameterError, match="contact_damping_n_s_per_m"):
        DockingContactParams(K, contact_damping_n_s_per_m=-1.0)


def test_a_scenario_states_the_pads_law_in_its_contact_section():
    raw = {
        "spacecraft": {"contact_frequency_hz": 1.0, "inertia_kg_m2": [1689.0] * 3},
        "contact": {"contact_stiffness_n_per_m": K, "contact_exponent": 1.5},
        "approach": {"initial_velocity_m_per_s": 0.1},
    }
    params = parse_scenario(raw)
    assert params.contact.contact_exponent == 1.5 and not params.contact.drake_law
    assert set(PAD_LAW_FIELDS) <= set(params.to_dict()["contact"])
    cone = {**raw, "contact": {"contact_stiffness_n_per_m": K, "geometry": "cone"}}
    cone["contact"]["contact_damping_n_s_per_m"] = 10.0
    with pytest.raises(Exception, match="contact_damping_n_s_per_m describes the plate"):
        parse_scenario(cone)


def test_the_pad_law_at_defaults_is_drakes():
    params = DockingContactParams(K)
    assert params.drake_law and params.pad_law_terms == []
    law = params.pad_law
    assert law.stiffness_n_per_m == K / params.pad_count and law.exponent == 1.0
    assert math.isclose(
        DockingContactParams(K, series_compliance_m_per_n=1e-6).pad_law.series_compliance_m_per_n,
        1e-6 * params.pad_count,
    )


def test_a_table_mode_is_refused_on_the_stewart_platform():
    from hybridtable.six_dof.physics6 import NOMINAL_PHYSICS

    stewart = load_scenario("examples/six_dof/stewart.toml")
    with pytest.raises(ParameterError, match="structural mode of the table"):
        NOMINAL_PHYSICS.resonant(60.0, 0.05).apply(stewart)
