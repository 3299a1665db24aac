"""Physics facts of the independent 6-DoF generator ``rig6`` (no hybridtable code)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

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


# --- the pad law (docs/run6-format.md, "The pad law") ---------------------------------


def _ring_force(n_pads, depth, rate, d=0.0, **totals):
    """The ring's wrench on axis, every pad pressed ``depth`` at ``rate``, under the
    pad law of the contact's totals ``totals``."""
    pads = rig6.pad_ring(n_pads, 0.3, 0.01)
    q = np.array([0.0, 0.0, depth, 0.0, 0.0, 0.0])
    qd = np.array([0.0, 0.0, rate, 0.0, 0.0, 0.0])
    law = rig6.pad_law(n_pads, **totals)
    return rig6.wrench(q, qd, pads, K_N_PER_M / n_pads, d, 0.01, law)


ON_AXIS_CASES = {  # name: (pad law's totals, Hunt-Crossley d, depth, rate, the 1-D law's force)
    "power_law_shallow": (
        {"contact_exponent": 1.5, "reference_press_m": 0.003},
        0.0,
        0.001,
        0.0,
        K_N_PER_M * 0.003 * (0.001 / 0.003) ** 1.5,
    ),
    "power_law_deep": (
        {"contact_exponent": 1.5, "reference_press_m": 0.003},
        0.0,
        0.006,
        0.0,
        K_N_PER_M * 0.003 * (0.006 / 0.003) ** 1.5,
    ),
    "power_law_soft": (
        {"contact_exponent": 0.7, "reference_press_m": 0.003},
        0.0,
        0.002,
        0.0,
        K_N_PER_M * 0.003 * (0.002 / 0.003) ** 0.7,
    ),
    "viscous_pressing": (
        {"contact_damping_n_s_per_m": 800.0},
        0.0,
        0.002,
        0.05,
        K_N_PER_M * 0.002 + 800.0 * 0.05,
    ),
    "viscous_releasing": (
        {"contact_damping_n_s_per_m": 800.0},
        0.0,
        0.002,
        -0.02,
        K_N_PER_M * 0.002 - 800.0 * 0.02,
    ),
    "viscous_and_hunt_crossley": (
        {"contact_damping_n_s_per_m": 800.0},
        0.3,
        0.002,
        0.05,
        K_N_PER_M * 0.002 * (1.0 + 0.3 * 0.05) + 800.0 * 0.05,
    ),
    "series_compliance": (
        {"series_compliance_m_per_n": 4e-6},
        0.0,
        0.002,
        0.0,
        K_N_PER_M * 0.002 / (1.0 + K_N_PER_M * 4e-6),
    ),
    "normal_friction_pressing": (
        {"normal_friction_force_n": 30.0, "normal_friction_velocity_m_per_s": 0.002},
        0.0,
        0.002,
        0.001,
        K_N_PER_M * 0.002 + 30.0 * math.tanh(0.5),
    ),
    "normal_friction_releasing": (
        {"normal_friction_force_n": 30.0, "normal_friction_velocity_m_per_s": 0.002},
        0.0,
        0.002,
        -0.01,
        K_N_PER_M * 0.002 - 30.0 * math.tanh(5.0),
    ),
}


@pytest.mark.parametrize("n_pads", [3, 8])
@pytest.mark.parametrize("case", list(ON_AXIS_CASES))
def test_on_axis_the_ring_pushes_with_the_one_dimensional_pad_law(case, n_pads):
    totals, d, depth, rate, force = ON_AXIS_CASES[case]
    w, delta = _ring_force(n_pads, depth, rate, d, **totals)
    np.testing.assert_allclose(delta, depth, rtol=1e-12)
    assert -w[5] == pytest.approx(force, rel=1e-12)  # pushed back out of the plate
    np.testing.assert_allclose(w[:5], 0.0, atol=1e-12 * force)  # evenly: no moment


def test_the_power_law_scales_as_the_depth_to_the_exponent():
    law = {"contact_exponent": 1.37, "reference_press_m": 0.004}
    f1 = -_ring_force(8, 0.001, 0.0, **law)[0][5]
    f2 = -_ring_force(8, 0.0035, 0.0, **law)[0][5]
    assert f2 / f1 == pytest.approx(3.5**1.37, rel=1e-12)
    at_ref = -_ring_force(8, 0.004, 0.0, **law)[0][5]
    assert at_ref == pytest.approx(K_N_PER_M * 0.004, rel=1e-12)  # k x_ref at the reference


@pytest.mark.parametrize("exponent", [0.6, 1.4, 2.5])
@pytest.mark.parametrize("depth", [1e-5, 0.002, 0.01])
def test_series_compliance_of_a_power_law_solves_its_own_equation(exponent, depth):
    s, x_ref = 3e-6, 0.003
    totals = {"contact_exponent": exponent, "reference_press_m": x_ref}
    f = -_ring_force(8, depth, 0.0, **totals, series_compliance_m_per_n=s)[0][5]
    stiff = -_ring_force(8, depth, 0.0, **totals)[0][5]
    assert 0.0 < f < stiff  # a compliance behind the pads only softens them
    # the 1-D law of the totals: f = k x_ref ((x - s f) / x_ref)^n
    assert f == pytest.approx(K_N_PER_M * x_ref * ((depth - s * f) / x_ref) ** exponent, rel=1e-9)
    root = brentq(
        lambda g: g - K_N_PER_M * x_ref * (max(depth - s * g, 0.0) / x_ref) ** exponent,
        0.0,
        min(stiff, depth / s),
        xtol=1e-300,
        rtol=1e-15,
    )
    assert f == pytest.approx(root, rel=1e-12)


def test_a_pad_that_would_pull_pushes_nothing_and_has_no_friction():
    pads = rig6.pad_ring(8, 0.3, 0.01)
    q = np.array([0.0, 0.0, 0.001, 0.0, 0.0, 0.0])
    qd = np.array([0.003, 0.0, -0.2, 0.0, 0.0, 0.0])  # sliding and leaving fast
    law = rig6.pad_law(8, contact_damping_n_s_per_m=1000.0)  # k x = 100 N < c |xdot| = 200 N
    w, delta = rig6.wrench(q, qd, pads, K_N_PER_M / 8, 0.0, 0.01, law)
    assert (delta > 0.0).all() and not w.any()
    w, _ = rig6.contact_wrench(q, qd, pads, K_N_PER_M / 8, 0.0, 0.01, 0.5, law=law)
    assert not w.any()
    qd[2] = -0.05  # leaving slower: 50 N of push, and friction across the face with it
    w, _ = rig6.contact_wrench(q, qd, pads, K_N_PER_M / 8, 0.0, 0.01, 0.5, law=law)
    assert w[5] == pytest.approx(-50.0, rel=1e-12)
    assert w[3] == pytest.approx(-0.5 * 50.0, rel=1e-12)  # mu f_n against the slip


def test_the_mdc_stiffness_and_damping_of_the_pad_law_on_axis():
    n, depth = 8, 0.002
    pads = rig6.pad_ring(n, 0.3, 0.01)
    q = np.array([0.0, 0.0, depth, 0.0, 0.0, 0.0])
    qd = np.zeros(6)

    def kc(**totals):
        law = rig6.pad_law(n, **totals)
        args = (pads, K_N_PER_M / n, 0.0, 0.01, law)
        return rig6.wrench_jacobians(q, qd, *args, damped=True)

    stiffness, _ = kc(series_compliance_m_per_n=2e-6)
    assert stiffness[5, 2] == pytest.approx(K_N_PER_M / (1.0 + K_N_PER_M * 2e-6), rel=1e-6)
    stiffness, _ = kc(contact_exponent=1.5, reference_press_m=0.004)
    assert stiffness[5, 2] == pytest.approx(1.5 * K_N_PER_M * (depth / 0.004) ** 0.5, rel=1e-6)
    _, damping = kc(contact_damping_n_s_per_m=700.0)
    assert damping[5, 2] == pytest.approx(700.0, rel=1e-6)
    # tanh(xdot / v_F) is F / v_F steep at rest (the step: well inside v_F)
    _, damping = kc(normal_friction_force_n=20.0, normal_friction_velocity_m_per_s=0.01)
    assert damping[5, 2] == pytest.approx(20.0 / 0.01, rel=1e-6)


@pytest.mark.slow  # a whole loop at 10 kHz
@pytest.mark.parametrize("zeta", [0.02, 0.05])
def test_a_viscous_damper_gives_the_damped_oscillators_cor(zeta):
    c = 2.0 * zeta * math.sqrt(K_N_PER_M * M_KG)
    r = run(sample_rate_hz=10000.0, contact_damping_n_s_per_m=c)
    # the pad never pulls: it lets go where k x + c xdot = 0, at omega_d t = pi - 2 asin(zeta),
    # and leaves at exactly exp(-zeta omega t) of the speed it came in with
    release = math.exp(-zeta * (math.pi - 2.0 * math.asin(zeta)) / math.sqrt(1.0 - zeta**2))
    assert r["cor_normal"] == pytest.approx(release, abs=1e-4)
    # to first order in the damping, the damped oscillator's half period
    classic = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    assert r["cor_normal"] / classic - 1.0 == pytest.approx(2.0 * zeta**2, rel=0.1)


@pytest.mark.slow  # a whole loop at 10 kHz
def test_a_normal_friction_force_dissipates_two_f_over_the_peak_press():
    force = 0.02 * V0 * math.sqrt(K_N_PER_M * M_KG)  # 2 % of the undamped peak force
    r = run(
        sample_rate_hz=10000.0,
        normal_friction_force_n=force,
        normal_friction_velocity_m_per_s=0.02 * V0,
    )
    x_peak = r["q_act"][:, 2].max()  # on axis every pad is pressed by the port's z
    lost = 0.5 * M_KG * V0**2 - r["kinetic_energy_j"][-1]
    assert lost == pytest.approx(2.0 * force * x_peak, rel=0.01)
    # exactly: F on the way in, F on the way out until k x = F, where the pads let go
    assert lost == pytest.approx(2.0 * force * x_peak - force**2 / (2.0 * K_N_PER_M), rel=1e-4)


@pytest.mark.parametrize("extra", [{}, OFFSET], ids=["on_axis", "offset"])
def test_total_energy_is_conserved_by_a_power_law_behind_a_compliance(extra):
    law = {
        "contact_exponent": 1.4,
        "reference_press_m": V0 * math.sqrt(M_KG / K_N_PER_M),
        "series_compliance_m_per_n": 0.5 / K_N_PER_M,
    }
    r = run(sample_rate_hz=2000.0, **extra, **law)
    e = r["total_energy_j"]
    assert np.abs(e / (0.5 * M_KG * V0**2) - 1.0).max() < 5e-3
    assert r["energy_ratio"] == pytest.approx(1.0, abs=1e-4)
    assert r["peak_force_n"] < 0.9 * V0 * math.sqrt(K_N_PER_M * M_KG)  # softened


DEFAULT_LAW = {
    "contact_exponent": 1.0,
    "reference_press_m": 0.002,  # no matter with a linear spring
    "contact_damping_n_s_per_m": 0.0,
    "series_compliance_m_per_n": 0.0,
    "normal_friction_force_n": 0.0,
    "normal_friction_velocity_m_per_s": 0.001,  # no matter without a force
}


@pytest.mark.slow  # two whole loops with SDMDC
def test_the_pad_law_at_its_defaults_is_the_old_contact_bit_for_bit():
    kw = RIG | OFFSET | {"compensator": "SDMDC", "hunt_crossley_dissipation_s_per_m": 0.2}
    old, new = run(**kw), run(**kw, **DEFAULT_LAW)
    assert old.keys() == new.keys()
    for name, value in old.items():
        np.testing.assert_array_equal(new[name], value, err_msg=name)
    pads = rig6.pad_ring(8, 0.3, 0.01)
    q = np.array([0.001, 0.0, 0.004, 0.01, -0.02, 0.0])
    qd = np.array([0.01, 0.0, 0.05, 0.0, 0.03, 0.0])
    law = rig6.pad_law(8, **DEFAULT_LAW)
    assert law.plain
    for fn, tail in ((rig6.wrench, ()), (rig6.contact_wrench, (0.3,))):
        plain = fn(q, qd, pads, K_N_PER_M / 8, 0.2, 0.01, *tail)
        with_law = fn(q, qd, pads, K_N_PER_M / 8, 0.2, 0.01, *tail, law=law)
        np.testing.assert_array_equal(with_law[0], plain[0])


PAD_LAW_EFFECTS = {  # effect: (hidden parameters, the scenario's keys it amounts to)
    "contact_damping": (
        {"damping_n_s_per_m": 900.0},
        {"contact_damping_n_s_per_m": 300.0 + 900.0},
    ),
    "series_compliance": (
        {"series_compliance_m_per_n": 3e-6},
        {"series_compliance_m_per_n": 1e-6 + 3e-6},
    ),
    "coulomb_friction": (
        {"friction_force_n": 40.0},
        {"normal_friction_force_n": 10.0 + 40.0, "normal_friction_velocity_m_per_s": 0.02 * V0},
    ),
    "nonlinear_stiffness": (
        {"exponent": 1.3, "reference_stiffness_n_per_m": 1.2e5},
        {
            "contact_stiffness_n_per_m": 1.2e5,
            "contact_exponent": 1.3,
            "reference_press_m": V0 * math.sqrt(M_KG / K_N_PER_M),
        },
    ),
}
#: The scenario's own pad law the effects act on (each effect adds to its term).
SCENARIO_LAW = {
    "contact_damping_n_s_per_m": 300.0,
    "series_compliance_m_per_n": 1e-6,
    "normal_friction_force_n": 10.0,
    "normal_friction_velocity_m_per_s": 0.05,
}


@pytest.mark.parametrize("name", list(PAD_LAW_EFFECTS))
def test_a_pad_law_effect_is_the_scenarios_contact_with_its_term_added(name):
    hidden, keys = PAD_LAW_EFFECTS[name]
    own = {k: v for k, v in SCENARIO_LAW.items() if name != "nonlinear_stiffness"}
    kw = RIG | OFFSET | own | {"mass_kg": M_KG, "contact_stiffness_n_per_m": K_N_PER_M}
    out = rig6.simulate_rig6(**kw)
    args = (out["command_initial"], out["command_rate_initial"], out["q_des"], out["qd_des"])
    hid = rig6.replay_rig6(*args, **kw, hidden={name: hidden})
    said = rig6.replay_rig6(*args, **(kw | keys))
    for part in ("q_act", "wrench_act", "wrench_mea"):
        np.testing.assert_array_equal(hid[part], said[part], err_msg=part)
    nominal = rig6.replay_rig6(*args, **kw)
    assert np.abs(hid["wrench_act"] - nominal["wrench_act"]).max() > 10.0  # N: it shows


@pytest.mark.parametrize(
    "name, params, words",
    [
        ("contact_damping", {"damping_n_s_per_m": -1.0}, "at least 0"),
        ("series_compliance", {"series_compliance_m_per_n": -1e-7}, "at least 0"),
        ("coulomb_friction", {"friction_force_n": -2.0}, "at least 0"),
        ("nonlinear_stiffness", {"exponent": 0.0}, "above 0"),
        ("nonlinear_stiffness", {"reference_stiffness_n_per_m": -1e5}, "above 0"),
    ],
)
def test_pad_law_effects_out_of_their_range_are_refused(name, params, words):
    with pytest.raises(ValueError, match=words):
        rig6.normalize_hidden({name: params})
    assert rig6.EFFECT_PARTS[name] == "contact"


# --- table_resonance (docs/run6-format.md, "The effects, as laws") ----------------------


def _rk4_servo_and_mode(servo_hz, zeta, f_r, z_r, u, ud, h, substeps=100):
    """One coordinate of the servo and the mode behind it, integrated by RK4 on
    ``substeps`` steps a tick, the command ``u[k], ud[k]`` held over tick k, from
    rest at 0: the device's ``y, y'`` at the end of each tick (written apart from
    rig6: ``x'' = w^2 (u - x) - 2 zeta w x'``, or ``x = u, x' = ud`` for an ideal
    servo; ``y'' = w_r^2 (x - y) + 2 zeta_r w_r (x' - y')``)."""
    ideal = math.isinf(servo_hz)
    w = 0.0 if ideal else 2.0 * math.pi * servo_hz
    wr = 2.0 * math.pi * f_r
    dt = h / substeps
    x = xd = y = yd = 0.0
    ys, yds = [], []
    for uk, udk in zip(u, ud, strict=True):

        def deriv(x, xd, y, yd, uk=uk, udk=udk):
            if ideal:
                x, xd = uk, udk
                xdd = 0.0
            else:
                xdd = w * w * (uk - x) - 2.0 * zeta * w * xd
            return xd, xdd, yd, wr * wr * (x - y) + 2.0 * z_r * wr * (xd - yd)

        for _ in range(substeps):
            k1 = deriv(x, xd, y, yd)
            k2 = deriv(*(s + 0.5 * dt * d for s, d in zip((x, xd, y, yd), k1, strict=True)))
            k3 = deriv(*(s + 0.5 * dt * d for s, d in zip((x, xd, y, yd), k2, strict=True)))
            k4 = deriv(*(s + dt * d for s, d in zip((x, xd, y, yd), k3, strict=True)))
            x, xd, y, yd = (
                s + dt / 6.0 * (a + 2.0 * b + 2.0 * c + e)
                for s, a, b, c, e in zip((x, xd, y, yd), k1, k2, k3, k4, strict=True)
            )
        ys.append(y)
        yds.append(yd)
    return np.array(ys), np.array(yds)


#: A held command of one coordinate: a step, a rate held with it, then a step back.
_N_TICKS = 150
_U = np.where(np.arange(_N_TICKS) < 80, 1.0, -0.5)
_UD = np.where(np.arange(_N_TICKS) < 80, 0.3, -0.2)


@pytest.mark.parametrize(
    "servo_hz, f_r, z_r",
    [(25.0, 40.0, 0.05), (25.0, 12.0, 0.2), (math.inf, 40.0, 0.05), (math.inf, 90.0, 0.7)],
    ids=["servo_40Hz_mode", "servo_12Hz_mode", "ideal_40Hz_mode", "ideal_90Hz_mode"],
)
def test_table_resonance_is_the_servo_and_mode_solved_exactly_over_each_tick(servo_hz, f_r, z_r):
    h, zeta = 1e-3, 0.8
    effects = rig6.normalize_hidden(
        {"table_resonance": {"frequency_hz": f_r, "damping_ratio": z_r}}
    )
    table = rig6._Table(servo_hz, zeta, h, effects, "previous_tick", (0.0, 0.0))
    table.start(np.zeros(6), np.zeros(6))  # at rest at 0: tick 0 reads one tick on
    gains = np.array([1.0, -2.0, 0.5, 0.01, -0.02, 0.03])  # six coordinates, one law
    seen = [table.advance(u * gains, ud * gains) for u, ud in zip(_U, _UD, strict=True)]
    q_act = np.array([s[0] for s in seen])
    qd_act = np.array([s[1] for s in seen])
    y, yd = _rk4_servo_and_mode(servo_hz, zeta, f_r, z_r, _U, _UD, h)
    wr = 2.0 * math.pi * f_r
    np.testing.assert_allclose(q_act, np.outer(y, gains), rtol=0, atol=1e-9)
    np.testing.assert_allclose(qd_act, np.outer(yd, gains), rtol=0, atol=1e-9 * wr)
    assert np.abs(y[:80] - 1.0).max() > 0.05  # the mode rings: a real test of it


def test_table_resonance_starts_unstrained_where_the_table_starts():
    kw = RIG | OFFSET | {"mass_kg": M_KG, "contact_stiffness_n_per_m": K_N_PER_M}
    out = rig6.simulate_rig6(**kw, table_start="tick0")
    args = (out["command_initial"], out["command_rate_initial"], out["q_des"], out["qd_des"])
    mode = {"table_resonance": {"frequency_hz": 30.0, "damping_ratio": 0.05}}
    for response_hz in (25.0, math.inf):
        rig = kw | {"table_response_hz": response_hz}
        plain = rig6.replay_rig6(*args, **rig, table_start="tick0")
        rung = rig6.replay_rig6(*args, **rig, hidden=mode, table_start="tick0")
        np.testing.assert_array_equal(rung["q_act"][0], plain["q_act"][0])
        np.testing.assert_array_equal(rung["qd_act"][0], out["command_rate_initial"])
        assert np.abs(rung["q_act"] - plain["q_act"]).max() > 1e-6  # then it moves its own way


@pytest.mark.parametrize("response_hz", [25.0, math.inf], ids=["model", "ideal"])
def test_table_resonance_at_an_infinite_frequency_is_the_old_run_bit_for_bit(response_hz):
    kw = RIG | OFFSET | {"compensator": "SDC", "hunt_crossley_dissipation_s_per_m": 0.2}
    kw["table_response_hz"] = response_hz
    old = run(**kw)
    for params in ({}, {"frequency_hz": math.inf, "damping_ratio": 0.3}):
        new = run(**kw, hidden={"table_resonance": params})
        assert old.keys() == new.keys()
        for name, value in old.items():
            np.testing.assert_array_equal(new[name], value, err_msg=name)


@pytest.mark.parametrize("response_hz", [25.0, math.inf], ids=["model", "ideal"])
def test_a_very_stiff_table_resonance_is_nearly_the_old_run(response_hz):
    kw = RIG | {"table_response_hz": response_hz}
    stiff = {"table_resonance": {"frequency_hz": 5000.0, "damping_ratio": 0.7}}
    old, new = run(**kw), run(**kw, hidden=stiff)
    assert new["cor_normal"] == pytest.approx(old["cor_normal"], abs=1e-3)
    assert new["peak_force_n"] == pytest.approx(old["peak_force_n"], rel=1e-3)


def test_a_40_hz_table_resonance_changes_the_on_axis_cor():
    mode = {"table_resonance": {"frequency_hz": 40.0, "damping_ratio": 0.05}}
    old, new = run(**RIG), run(**RIG, hidden=mode)
    assert abs(new["cor_normal"] - old["cor_normal"]) > 1e-4
    assert np.abs(new["q_act"][:, 2] - old["q_act"][:, 2]).max() > 1e-6  # m: the device rings
    np.testing.assert_allclose(new["q_act"][:, :2], 0.0, atol=1e-15)  # on axis it stays there


def test_table_resonance_acts_on_each_coordinate_behind_its_own_servo():
    kw = RIG | OFFSET | {"mass_kg": M_KG, "contact_stiffness_n_per_m": K_N_PER_M}
    out = rig6.simulate_rig6(**kw)
    args = (out["command_initial"], out["command_rate_initial"], out["q_des"], out["qd_des"])
    mode = {"table_resonance": {"frequency_hz": 30.0, "damping_ratio": 0.05}}
    alone = rig6.replay_rig6(*args, **kw, hidden=mode)
    lagged = rig6.replay_rig6(*args, **kw, hidden=mode | {"lateral_lag": {}})
    np.testing.assert_array_equal(lagged["q_act"], alone["q_act"])  # a null lag: the same
    slow = rig6.replay_rig6(
        *args, **kw, hidden=mode | {"lateral_lag": {"lateral_response_ratio": 0.5}}
    )
    np.testing.assert_allclose(slow["q_act"][:, 2:], alone["q_act"][:, 2:], rtol=0, atol=1e-15)
    assert np.abs(slow["q_act"][:, :2] - alone["q_act"][:, :2]).max() > 1e-7


@pytest.mark.parametrize(
    "params, words",
    [
        ({"frequency_hz": 0.0}, "above 0"),
        ({"frequency_hz": -40.0}, "above 0"),
        ({"damping_ratio": 0.0}, "above 0"),
        ({"damping_ratio": -0.1}, "above 0"),
        ({"damping_ratio": math.inf}, "not finite"),
        ({"frequency_hz": math.nan}, "not finite"),
    ],
)
def test_table_resonance_out_of_its_range_is_refused(params, words):
    with pytest.raises(ValueError, match=words):
        rig6.normalize_hidden({"table_resonance": params})
    assert rig6.EFFECT_PARTS["table_resonance"] == "table"
    assert list(rig6.LIBRARY_EFFECTS)[-1] == "table_resonance"  # appended: the draws keep
