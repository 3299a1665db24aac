"""Physics facts of the independent 6-DoF generator ``rig6`` (no hybridtable code)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.generators import rig6

M_KG, K_N_PER_M, V0 = 2533.03, 1e5, 0.1
OMEGA = math.sqrt(K_N_PER_M / M_KG)  # rad/s
OFFSET = {  # 10 mm off the axis, 2 deg pitch: a few pads touch first, the body turns
    "lateral_offset_m": (0.01, 0.0),
    "misalignment_rad": (0.0, math.radians(2.0)),
    "inertia_kg_m2": (1689.0, 1689.0, 1689.0),
    "port_distance_m": 1.5,
}
RIG = {  # the reference rig: 25 Hz table, 5 ms delay, 1 kHz computer
    "table_response_hz": 25.0,
    "table_damping_ratio": 0.8,
    "sensor_delay_s": 0.005,
    "sample_rate_hz": 1000.0,
}


def run(**kw) -> dict:
    return rig6.simulate_rig6(mass_kg=M_KG, contact_stiffness_n_per_m=K_N_PER_M, **kw)


def test_on_axis_elastic_contact_lasts_half_a_period_and_restores_the_speed():
    r = run(sample_rate_hz=10000.0)
    assert r["contact_duration_s"] == pytest.approx(math.pi / OMEGA, abs=1e-4)
    assert r["cor_normal"] == pytest.approx(1.0, abs=1e-3)
    assert r["peak_force_n"] == pytest.approx(V0 * math.sqrt(K_N_PER_M * M_KG), rel=1e-3)
    assert r["peak_moment_n_m"] < 1e-9  # the ring presses evenly on axis


@pytest.mark.parametrize("extra", [{}, OFFSET], ids=["on_axis", "offset"])
def test_total_energy_is_conserved_without_delay_or_damping(extra):
    r = run(sample_rate_hz=2000.0, **extra)
    e = r["total_energy_j"]
    assert np.abs(e / (0.5 * M_KG * V0**2) - 1.0).max() < 5e-3
    assert r["energy_ratio"] == pytest.approx(1.0, abs=1e-4)


def test_offset_contact_spins_the_body_and_slows_the_port():
    r = run(**OFFSET)
    spin = np.linalg.norm(r["angular_momentum_n_m_s"][-1])
    assert spin > 1.0  # N m s: the off-centre push leaves the body turning
    assert 0.9 < r["cor_normal"] < 0.99  # part of the energy went into the rotation
    assert r["peak_moment_n_m"] > 10.0


@pytest.mark.parametrize(
    "inertia, tol", [((1689.0, 1689.0, 1689.0), 1e-9), ((1689.0, 2100.0, 2600.0), 2e-3)]
)
def test_linear_and_angular_impulse_balance(inertia, tol):
    r = run(**(OFFSET | {"inertia_kg_m2": inertia}))
    h = r["t_s"][1]
    w, com, q_des = r["wrench_comp"], r["com_position_m"], r["q_des"]
    assert not w[0].any()  # tick 0 is before the contact: its lever arm is not needed
    f = w[1:, 3:]
    # linear: m (v_out - v_in) = h sum f, v of the centre of mass from its positions
    v_out = (com[-1] - com[-2]) / h
    impulse = h * f.sum(axis=0)
    np.testing.assert_allclose(M_KG * (v_out - [0.0, 0.0, V0]), impulse, atol=1e-9 * M_KG * V0)
    # angular, about the centre of mass: lever arms before each tick's update
    lever = q_des[:-1, :3] - com[:-1]
    moment = w[1:, :3] + np.cross(lever, f)
    angular_impulse = h * moment.sum(axis=0)
    gained = r["angular_momentum_n_m_s"][-1]  # it starts at zero
    scale = np.linalg.norm(angular_impulse)
    assert scale > 1.0
    np.testing.assert_allclose(gained, angular_impulse, atol=tol * scale)


def test_delay_without_compensation_adds_energy_like_negative_damping():
    cor = [run(sensor_delay_s=d)["cor_normal"] for d in (0.001, 0.002, 0.005, 0.010)]
    assert np.all(np.diff(cor) > 0.0) and cor[0] > 1.0
    for d, c in zip((0.001, 0.002, 0.005, 0.010), cor, strict=True):
        # delayed spring ~ spring with damping -k T: CoR = exp(pi omega T / 2)
        assert c - 1.0 == pytest.approx(math.expm1(math.pi * OMEGA * d / 2.0), rel=1e-2)


def test_hunt_crossley_dissipation_gives_the_small_damping_cor():
    d = 0.1  # s/m: e = 1 - (2/3) d v for d v << 1
    r = run(sample_rate_hz=10000.0, hunt_crossley_dissipation_s_per_m=d)
    assert r["cor_normal"] == pytest.approx(1.0 - 2.0 / 3.0 * d * V0, abs=2e-4)


def _scalar_loop(compensator: str, n_delay: int, h: float, f_hz: float, zeta: float) -> float:
    """CoR of the 1-D loop (spring on the table's position), written out apart."""
    w = 2.0 * math.pi * f_hz
    phi, gam = rig6._table_update(f_hz, zeta, h)
    x, v = -0.001, V0  # the port's z: the pad tops 1 mm from the plane
    s = np.array([x - 2.0 * zeta / w * V0, V0])  # tracking the approach ramp
    lead = n_delay * h if compensator == "SDC" else 0.0
    f_hist, f_prev = [0.0] * n_delay, 0.0
    for _ in range(3000):
        s = phi @ s + gam * x
        f_hist.append(-K_N_PER_M * s[0] if s[0] > 0.0 else 0.0)
        f_mea = f_hist[-1 - n_delay]
        f_c = f_mea + lead * (f_mea - f_prev) / h if f_mea != 0.0 else 0.0
        f_prev = f_mea
        v += h * f_c / M_KG
        x += h * v
    return abs(v) / V0


@pytest.mark.parametrize("compensator", ["none", "SDC"])
def test_on_axis_the_ring_is_the_one_dimensional_spring(compensator):
    r = run(**RIG, compensator=compensator, duration_s=2.999)
    assert r["cor_normal"] == pytest.approx(_scalar_loop(compensator, 5, 1e-3, 25.0, 0.8), 1e-9)


@pytest.mark.parametrize("extra", [{}, OFFSET], ids=["on_axis", "offset"])
def test_compensators_bring_the_energy_back(extra):
    gain = {c: run(**RIG, **extra, compensator=c)["energy_ratio"] - 1.0 for c in rig6.COMPENSATORS}
    assert gain["none"] > 0.25
    assert gain["none"] > gain["SDC"] > gain["MDC"] > abs(gain["SDMDC"])
    assert abs(gain["SDMDC"]) < 0.01


def test_mdc_on_an_ideal_table_without_delay_changes_nothing():
    damped = OFFSET | {"hunt_crossley_dissipation_s_per_m": 0.2}  # K and C both at work
    plain = run(**damped)
    mdc = run(**damped, compensator="SDMDC")
    np.testing.assert_array_equal(plain["wrench_comp"], mdc["wrench_comp"])


def test_finite_difference_stiffness_on_axis_is_the_closed_form():
    a, r_pad, n, depth = 0.3, 0.01, 8, 0.002
    pads = rig6.pad_ring(n, a, r_pad)
    q = np.array([0.0, 0.0, depth, 0.0, 0.0, 0.0])  # every pad pressed by `depth`
    stiffness, damping = rig6.wrench_jacobians(q, np.zeros(6), pads, K_N_PER_M / n, 0.0, r_pad)
    # rows: w = [moment; force], columns: q = [position; rotation vector]
    expected = np.zeros((6, 6))
    expected[5, 2] = K_N_PER_M  # K_zz = k, K_xx = K_yy = 0
    # tilt: k a^2 / 2, plus the lever arm turning with the body under the total force
    expected[0, 3] = expected[1, 4] = K_N_PER_M * a**2 / 2.0 + K_N_PER_M * depth * r_pad
    np.testing.assert_allclose(stiffness, expected, atol=1e-6 * K_N_PER_M)
    assert not damping.any()


def test_finite_difference_stiffness_against_position_is_the_sum_over_pads_in_contact():
    n, r_pad = 8, 0.01
    pads = rig6.pad_ring(n, 0.3, r_pad)
    q = np.array([0.0, 0.0, 0.004, 0.0, math.radians(2.0), 0.0])  # tilted: some pads touch
    stiffness, _ = rig6.wrench_jacobians(q, np.zeros(6), pads, K_N_PER_M / n, 0.0, r_pad)
    _, delta = rig6.wrench(q, np.zeros(6), pads, K_N_PER_M / n, 0.0, r_pad)
    assert 0 < (delta > 0.0).sum() < n
    b = pads @ rig6.exp_so3(q[3:]).T
    g = np.column_stack([b[:, 1], -b[:, 0], np.zeros(n), np.zeros((n, 2)), np.ones(n)])
    expected = K_N_PER_M / n * g[delta > 0.0].sum(axis=0)  # sum k_i g_i, g_i = [b_i x e_z; e_z]
    np.testing.assert_allclose(stiffness[:, 2], expected, atol=1e-6 * K_N_PER_M)
    np.testing.assert_allclose(stiffness[:, :2], 0.0, atol=1e-6 * K_N_PER_M)


def test_finite_difference_damping_matches_hunt_crossley():
    n, r_pad, d, depth, rate = 8, 0.01, 0.3, 0.002, 0.05
    pads = rig6.pad_ring(n, 0.3, r_pad)
    q = np.array([0.0, 0.0, depth, 0.0, 0.0, 0.0])
    qd = np.array([0.0, 0.0, rate, 0.0, 0.0, 0.0])
    stiffness, damping = rig6.wrench_jacobians(q, qd, pads, K_N_PER_M / n, d, r_pad, damped=True)
    assert damping[5, 2] == pytest.approx(K_N_PER_M * depth * d, rel=1e-6)  # c = k delta d
    assert stiffness[5, 2] == pytest.approx(K_N_PER_M * (1.0 + d * rate), rel=1e-6)


def test_rotation_vector_round_trip():
    theta = np.array([0.3, -0.2, 1.1])
    np.testing.assert_allclose(rig6.log_so3(rig6.exp_so3(theta)), theta, atol=1e-12)
    np.testing.assert_allclose(rig6.log_so3(rig6.exp_so3(1e-9 * theta)), 1e-9 * theta, rtol=1e-9)


def test_a_delay_off_the_tick_grid_is_refused():
    with pytest.raises(ValueError, match="whole number of ticks"):
        run(sensor_delay_s=0.0045)
