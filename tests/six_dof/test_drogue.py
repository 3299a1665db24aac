"""The probe and drogue: the cone's guiding force against a hand calculation,
its 6x6 K and C in closed form against Drake's own wrench, and a head-on
docking that keeps its energy."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hybridtable.six_dof.drogue as drogue_module
from hybridtable.errors import ParameterError, SpecError
from hybridtable.six_dof.contact import DockingContact, peak_press_m, port_start_z_m
from hybridtable.six_dof.devices import DockingContactParams
from hybridtable.six_dof.drogue import (
    probe_energy_j,
    probe_force_n,
    probe_modulus_pa,
    throat_depth_m,
    wall_depth_m,
)
from hybridtable.six_dof.params import DockingLoopParams, RigidBodyParams
from hybridtable.six_dof.pose import rotation_exp
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import expected_end_s, probe_centres_m, simulate6
from tests.generators.drogue_billiard import Drogue, predict

K_N_PER_M = 1e5


def _cone(**kw) -> DockingContactParams:
    return DockingContactParams(K_N_PER_M, geometry="cone", **kw)


def _on_wall(c: DockingContactParams, rho: float, press: float, theta=(0.0, 0.0, 0.0)):
    """The pose q whose probe head is pressed ``press`` into the cone wall at
    radius ``rho`` (meridian plane y = 0), the port turned by ``theta``."""
    a = c.cone_half_angle_rad
    wall = np.array([rho, 0.0, (c.mouth_radius_m - rho) / math.tan(a)])
    centre = wall + (c.probe_radius_m - press) * np.array([-math.cos(a), 0.0, -math.sin(a)])
    R = rotation_exp(np.array(theta))
    return np.concatenate([centre - R @ c.probe_centre_m, theta])


def test_the_stated_stiffness_is_the_probes_tangent_at_a_tenth_of_its_radius():
    c = _cone()
    x = 0.1 * c.probe_radius_m
    h = 1e-7
    slope = (probe_force_n(c, x + h) - probe_force_n(c, x - h)) / (2 * h)
    assert slope == pytest.approx(K_N_PER_M, rel=1e-6)
    # the work is the force's integral
    xs = np.linspace(0.0, 0.02, 2001)
    work = np.trapezoid(probe_force_n(c, xs), xs)
    assert work == pytest.approx(float(probe_energy_j(c, 0.02)), rel=1e-6)
    # the belief scales the modulus as it scales a pad's k
    assert probe_modulus_pa(_cone().__class__(2 * K_N_PER_M, geometry="cone")) == pytest.approx(
        2 * probe_modulus_pa(c)
    )


@pytest.mark.parametrize("alpha_deg", [20.0, 30.0, 45.0])
@pytest.mark.parametrize("rho", [0.15, 0.25])
def test_the_cone_guides_along_its_normal_as_a_hand_calculation_says(alpha_deg, rho):
    """Frictionless, the wall pushes along its normal: ``cot alpha`` across
    the axis per unit along it; the size is the probe's law on a flat wall,
    ``pi E x^2 (1 - 2x / 3r)``, within 10 %: the wall is concave round the
    axis (more of the head inside it), made of flat facets, and the head's
    pressure field is a tetrahedral mesh (measured: +0.6 to +7 %)."""
    c = _cone(cone_half_angle_rad=math.radians(alpha_deg))
    press = 0.005
    w = DockingContact(c).wrench(_on_wall(c, rho, press))
    F = w[3:]
    a = math.radians(alpha_deg)
    assert F[1] == pytest.approx(0.0, abs=1e-6 * np.linalg.norm(F))
    assert -F[0] / -F[2] == pytest.approx(1.0 / math.tan(a), rel=5e-3)
    assert F[0] < 0.0 and F[2] < 0.0  # toward the axis, and back toward the mouth
    assert np.linalg.norm(F) == pytest.approx(float(probe_force_n(c, press)), rel=0.1)
    assert wall_depth_m(c, _on_wall(c, rho, press)[:3] + c.probe_centre_m) == pytest.approx(press)


def test_the_rim_and_the_floor_push_straight_back():
    """Straight back, and the flat wall's law within 10 % at a 10 mm press:
    Drake's tetrahedral mesh of the head lies inside the sphere (measured:
    -13 % at 5 mm, -6 % at 10 mm)."""
    c = _cone()
    contact = DockingContact(c)
    press = 0.01
    for z_tip, x in ((press, 0.45), (float(drogue_module.profile(c)[-1, 1]) + press, 0.0)):
        F = contact.wrench(np.array([x, 0.0, z_tip, 0.0, 0.0, 0.0]))[3:]
        assert abs(F[0]) + abs(F[1]) < 1e-6 * abs(F[2]) and F[2] < 0.0
        assert -F[2] == pytest.approx(float(probe_force_n(c, press)), rel=0.1)


def _central_differences(contact, q, qd, h=1e-6):
    K, C = np.zeros((6, 6)), np.zeros((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        K[:, j] = -(contact.wrench(q + e, qd) - contact.wrench(q - e, qd)) / (2 * h)
        C[:, j] = -(contact.wrench(q, qd + e) - contact.wrench(q, qd - e)) / (2 * h)
    return K, C


@pytest.mark.parametrize(
    ("rho", "press", "theta", "qd", "dissipation"),
    [
        (0.2, 0.005, (0.0, 0.0, 0.0), None, 0.0),
        (0.15, 0.008, (0.02, -0.03, 0.05), None, 0.0),
        (0.2, 0.005, (0.02, -0.03, 0.05), (0.01, -0.02, 0.05, 0.1, -0.05, 0.2), 0.5),
    ],
)
def test_closed_form_stiffness_matches_drakes_wrench(rho, press, theta, qd, dissipation):
    """``K = -dw/dq`` and ``C = -dw/dqd`` from one evaluation: the derivative of
    the pressure integrated over the contact surface. Drake integrates each
    polygon at its centroid, which the shape's change moves: that is the
    measured 3e-4 of the largest entry."""
    c = _cone(contact_dissipation_s_per_m=dissipation)
    contact = DockingContact(c)
    q = _on_wall(c, rho, press, theta)
    v = None if qd is None else np.array(qd)
    K, C = contact.stiffness(q, v)
    Kn, Cn = _central_differences(contact, q, np.zeros(6) if v is None else v)
    assert np.abs(K - Kn).max() <= 1e-3 * np.abs(Kn).max()
    if dissipation:
        assert np.abs(C - Cn).max() <= 1e-3 * np.abs(Cn).max()
    else:
        assert not C.any() and not Cn.any()
    # the normal stiffness on the wall is the probe's law's slope, ~ f'(x)
    a = c.cone_half_angle_rad
    n = np.array([-math.cos(a), 0.0, -math.sin(a)])
    if theta == (0.0, 0.0, 0.0):
        slope = 2 * math.pi * probe_modulus_pa(c) * press * (1 - press / c.probe_radius_m)
        assert float(n @ K[3:, :3] @ n) == pytest.approx(slope, rel=0.1)


def test_moving_probe_with_friction_has_no_closed_form():
    contact = DockingContact(_cone(friction_coefficient=0.3))
    q = _on_wall(contact.params, 0.2, 0.005)
    contact.stiffness(q)  # at rest friction plays no part
    with pytest.raises(ParameterError, match="friction"):
        contact.stiffness(q, np.array([0.01, 0, 0.05, 0, 0, 0]))


def test_compiled_and_python_face_kernels_agree_bit_for_bit(monkeypatch):
    contact = DockingContact(_cone(contact_dissipation_s_per_m=0.5))
    q = _on_wall(contact.params, 0.2, 0.005, (0.02, -0.03, 0.05))
    qd = np.array([0.01, -0.02, 0.05, 0.1, -0.05, 0.2])
    compiled = contact.stiffness(q, qd)
    drogue_module.hydroelastic_jacobians.cache_clear()
    monkeypatch.setattr(drogue_module, "compiled_available", lambda: False)
    try:
        python = contact.stiffness(q, qd)
    finally:
        drogue_module.hydroelastic_jacobians.cache_clear()
    for a, b in zip(compiled, python, strict=True):
        assert np.array_equal(a, b)


def test_the_cull_before_drakes_query_loses_no_contact(monkeypatch):
    """Poses about the cone's wall, on a facet's edge and across its middle:
    the wrench is the same with the cull (the smooth profile's distance, less
    the facets' sag) and without it."""
    c = _cone()
    contact = DockingContact(c)
    poses = []
    for angle in (0.0, math.pi / 64, 0.3):
        turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        for rho in (0.1, 0.2, 0.28):
            for press in (-2e-3, -3e-4, 0.0, 2e-4, 1e-3):
                q = _on_wall(c, rho, press)
                q[:2] = turn @ q[:2]
                poses.append(q)
    culled = [contact.wrench(q) for q in poses]
    monkeypatch.setattr(drogue_module, "facet_sag_m", lambda _c: math.inf)
    whole = [contact.wrench(q) for q in poses]
    assert any(np.any(w != 0.0) for w in whole)
    for a, b in zip(culled, whole, strict=True):
        assert np.array_equal(a, b)


def test_start_gap_and_peak_press():
    c = _cone()
    R = np.eye(3)
    floor = float(drogue_module.profile(c)[-1, 1])
    # head-on, the first touch is the socket's floor
    assert port_start_z_m(c, R, np.zeros(2), 0.001) == pytest.approx(floor - 0.001, abs=1e-9)
    # on the rim, its plane
    assert port_start_z_m(c, R, np.array([0.45, 0.0]), 0.002) == pytest.approx(-0.002, abs=1e-9)
    with pytest.raises(ParameterError, match="never touches"):
        port_start_z_m(c, R, np.array([0.7, 0.0]), 0.001)
    x = peak_press_m(c, 2000.0, 0.1)
    assert float(probe_energy_j(c, x)) == pytest.approx(0.5 * 2000.0 * 0.01, rel=1e-9)


def test_cone_parameters_and_scenario_keys_are_checked():
    with pytest.raises(ParameterError, match="probe_radius_m"):
        _cone(probe_radius_m=0.1)  # wider than the throat
    with pytest.raises(ParameterError, match="cone_half_angle_rad"):
        _cone(cone_half_angle_rad=1.5)
    with pytest.raises(ParameterError, match="socket_depth_m"):
        _cone(socket_depth_m=0.04)
    with pytest.raises(ParameterError, match="geometry"):
        DockingContactParams(K_N_PER_M, geometry="funnel")
    raw = {
        "spacecraft": {"mass_kg": 2000.0},
        "contact": {"contact_stiffness_n_per_m": 1e5, "geometry": "cone", "pad_count": 6},
    }
    with pytest.raises(SpecError, match="pad_count describes the plate"):
        parse_scenario(raw)
    raw["contact"] = {"contact_stiffness_n_per_m": 1e5, "probe_radius_m": 0.04}
    with pytest.raises(SpecError, match="probe_radius_m describes the cone"):
        parse_scenario(raw)


@pytest.mark.slow
@pytest.mark.parametrize("mass_kg", [2000.0, 30000.0])
def test_head_on_docking_keeps_its_energy(mass_kg):
    """Head-on on the ideal rig: the probe starts 1 mm before the socket's
    floor, its first touch (already past the throat: captured), presses it
    and flies back out. A heavy body's turning point on the floor, still but
    pressed hard, is not a hold."""
    run = simulate6(
        DockingLoopParams(
            spacecraft=RigidBodyParams(mass_kg), contact=_cone(), initial_velocity_m_per_s=0.1
        )
    )
    m = run.metrics
    assert abs(m.energy_ratio - 1.0) < 0.01  # the 1 %; measured 8e-11 (2 t), 2e-10 (30 t)
    assert m.cor_normal == pytest.approx(1.0, abs=0.01)
    assert m.captured
    assert m.lateral_velocity_m_per_s < 1e-9
    assert run.log["table_state"][-1, 2] < 0.0  # back out of the mouth
    # the floor's peak force is the probe's law at the press the energy reaches
    c = run.params.contact
    x = peak_press_m(c, mass_kg, 0.1)
    assert m.peak_force_n == pytest.approx(float(probe_force_n(c, x)), rel=0.08)
    with pytest.raises(ValueError, match="no closed-form potential"):
        _ = run.total_energy_j


def test_a_slow_approach_through_a_deep_drogue_runs_to_the_tick_budget():
    """At 2 cm/s the generous bound (four floors' depths at the approach
    speed) is past the tick budget: the run is not refused, it is capped."""
    params = DockingLoopParams(
        spacecraft=RigidBodyParams(2000.0),
        contact=_cone(contact_dissipation_s_per_m=50.0),
        initial_velocity_m_per_s=0.02,
    )
    assert expected_end_s(params) * params.sample_rate_hz > 100_000
    run = simulate6(params)
    assert run.metrics.captured


# -- capture, as the geometry says ---------------------------------------------
#: A translating probe (the spacecraft's inertia too large to turn), each
#: case's outcome predicted by the independent billiard
#: (tests/generators/drogue_billiard.py) with a clearance of at least 10 mm.
CAPTURE_CASES = [
    (20.0, 0.15),  # four touches on the cone, back out
    (30.0, 0.01),  # straight into the socket, onto its floor
    (20.0, 0.06),  # the cone sends it into the socket: captured
    (30.0, 0.10),  # three touches on the cone, back out
    (40.0, 0.15),  # two touches on the cone, back out
    (30.0, 0.40),  # onto the rim, straight back
]


def _translating(alpha_deg: float, miss_m: float) -> DockingLoopParams:
    return DockingLoopParams(
        spacecraft=RigidBodyParams(500.0, inertia_kg_m2=(1e9, 1e9, 1e9)),
        contact=_cone(cone_half_angle_rad=math.radians(alpha_deg)),
        initial_velocity_m_per_s=0.2,
        lateral_miss_m=(miss_m, 0.0),
    )


@pytest.mark.slow
@pytest.mark.parametrize(("alpha_deg", "miss_m"), CAPTURE_CASES)
def test_offsets_capture_or_not_as_the_geometry_says(alpha_deg, miss_m):
    c = _cone(cone_half_angle_rad=math.radians(alpha_deg))
    oracle = Drogue(
        c.cone_half_angle_rad,
        c.mouth_radius_m,
        c.throat_radius_m,
        c.socket_depth_m,
        c.probe_radius_m,
    )
    expected = predict(oracle, miss_m, 0.2)
    assert expected.closest_call_m >= 0.01  # a clear case
    run = simulate6(_translating(alpha_deg, miss_m))
    assert run.metrics.captured == expected.captured
    assert abs(run.metrics.energy_ratio - 1.0) < 0.01
    # as many touches as the billiard's, the first one specular: on the cone
    # wall the port leaves at v (-sin 2 alpha, cos 2 alpha)
    touching = np.linalg.norm(run.log["contact_wrench"][:, 3:], axis=1) > 0.0
    starts = np.flatnonzero(np.diff(touching.astype(int)) == 1)
    ends = np.flatnonzero(np.diff(touching.astype(int)) == -1)
    if not expected.captured or expected.touches[0].boundary == "floor":
        # touches that end in the socket's corners are not counted: a
        # compliant head there touches wall and floor at once
        assert len(starts) == len(expected.touches)
    after = run.port_velocity_m_per_s[ends[0] + 2]
    vx, vz = expected.touches[0].velocity_after
    assert after[0] == pytest.approx(vx, abs=0.01 * 0.2)
    assert after[2] == pytest.approx(vz, abs=0.01 * 0.2)
    assert abs(after[1]) < 1e-6


def test_a_probe_held_in_the_socket_ends_the_run():
    """The drogue example on the ideal rig: the cone guides the lossy head
    into the socket, where it rattles across without leaving. The run ends
    once, for the sensor delay plus 20 ticks, it has stayed past the throat
    with its axial speed and force nearly nil, long before the record's
    bound. (A head that bounces off the floor and drifts out does not stop
    at its turning point: test_head_on_docking_keeps_its_energy.)"""
    from hybridtable.six_dof.scenario import load_scenario

    example = Path(__file__).resolve().parents[2] / "examples" / "six_dof" / "drogue.toml"
    held = simulate6(load_scenario(example).ideal_rig())
    assert held.metrics.captured
    assert held.time_s[-1] < 0.5 * expected_end_s(held.params)
    last = held.log["table_state"][-20:]  # the window: 0 ticks of delay + 20
    assert np.all(probe_centres_m(held.params, last)[:, 2] > throat_depth_m(held.params.contact))
    assert np.max(np.abs(held.port_velocity_m_per_s[-20:, 2])) <= 0.05 * 0.1
    assert held.metrics.energy_ratio < 0.1  # the head lost most of its energy on the way in
