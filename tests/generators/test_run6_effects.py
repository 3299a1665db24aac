"""The hidden effects of the independent 6-DoF generator (``rig6``, ``run6_logs``)
against their laws (docs/run6-format.md, "The effects, as laws", and the laws
outside the library in ``rig6.simulate_rig6``'s docstring): no hybridtable code.

Each law is checked on the generator's own arrays: the reading against the
contact's wrench of the same run, the replay of a run's commands through the
physical part with and without the effect, or a closed form (a low pass's step
and ramp, a mount's overshoot and ringing period, a pad's friction).
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from tests.generators import rig6
from tests.generators import run6_logs as g

K_N_PER_M = 1e5
NOISE = {
    "force_noise_n": 2.0,
    "moment_noise_n_m": 0.5,
    "position_noise_m": 2e-6,
    "attitude_noise_rad": 1e-6,
}
#: rig6's arguments of the nominal scenario (10 mm offset, 2 deg pitch, 25 Hz table, 5 ms delay).
RIG, _ = g._rig6_arguments(g.scenario())
DELAY = 5  # ticks


def run(hidden=None, **kw) -> dict:
    return rig6.simulate_rig6(**(RIG | kw), hidden=hidden)


def replay(out: dict, hidden=None, **kw) -> dict:
    return rig6.replay_rig6(
        out["command_initial"],
        out["command_rate_initial"],
        out["q_des"],
        out["qd_des"],
        **(RIG | kw),
        hidden=hidden,
    )


def delayed(w: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros_like(w)
    out[n:] = w[: len(w) - n]
    return out


# --- a null hidden dict is the existing generator ----------------------------------

#: SHA-256 of the 33 columns (float64, little-endian, in COLUMNS order) that
#: generate_run6 wrote before the hidden effects existed.
DIGESTS = {
    "nominal": "77905f847f02e234a5c4b5da95013b264faf8d1575a312dcce2792c08a517992",
    "sdmdc_noisy": "802af7d2f1505c8d41680dbff7f65d004acacf82d7803e38b56bcc4f2bbcb532",
    "mdc_damped": "5bfd9bd8f7d3280f99bffcd6645edf45baa4c0510e4e690bcdb08c673da03051",
    "sdc_ideal": "7d24a8e89bd6b67df007d2b4133a52b7bfd172db7f4e9f1eba43e9714636195a",
}
CASES = {
    "nominal": (g.scenario(), {}),
    "sdmdc_noisy": (
        g.scenario(compensator={"name": "SDMDC"}),
        {"seed": 7, "force_noise_n": 2.0, "moment_noise_n_m": 0.5}
        | {"position_noise_m": 2e-6, "attitude_noise_rad": 1e-6},
    ),
    "mdc_damped": (
        g.scenario(
            compensator={"name": "MDC"},
            **{
                "contact.contact_dissipation_s_per_m": 0.3,
                "approach.lateral_miss_m": [0.01, -0.02],
            },
        ),
        {"seed": 2, "force_noise_n": 1.0},
    ),
    "sdc_ideal": (g.scenario(compensator={"name": "SDC"}, **{"table.response_hz": "inf"}), {}),
}


def digest(rows: dict) -> str:
    h = hashlib.sha256()
    for name in g.COLUMNS:
        h.update(np.ascontiguousarray(rows[name], dtype="<f8").tobytes())
    return h.hexdigest()


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("hidden", [None, {}], ids=["None", "empty"])
def test_a_null_hidden_dict_reproduces_the_existing_record_bit_for_bit(case, hidden):
    scen, kw = CASES[case]
    assert digest(g.generate_run6(scen, **kw, hidden=hidden)) == DIGESTS[case]


def test_every_effect_at_its_null_value_changes_nothing():
    scen = g.scenario(compensator={"name": "SDMDC"})
    plain = g.generate_run6(scen, seed=1, **NOISE)
    null = {name: {} for name in rig6.LIBRARY_EFFECTS if name != "stiffness_error"}
    null |= {name: {} for name in rig6.OUTSIDE_EFFECTS}
    null["stiffness_error"] = {"contact_stiffness_n_per_m": 1e5}  # the scenario's
    ran = g.generate_run6(scen, seed=1, **NOISE, hidden=null)
    for name in g.COLUMNS:
        np.testing.assert_array_equal(ran[name], plain[name], err_msg=name)


def test_unknown_effects_and_parameters_are_refused():
    with pytest.raises(ValueError, match="hidden effect 'backlash'"):
        rig6.normalize_hidden({"backlash": {}})
    with pytest.raises(ValueError, match="not among"):
        rig6.normalize_hidden({"force_bias": {"bias": 1.0}})
    with pytest.raises(ValueError, match="above 0"):
        rig6.normalize_hidden({"table_response": {"table_response_ratio": 0.0}})
    with pytest.raises(ValueError, match="whole number of ticks"):
        run({"extra_delay": {"extra_delay_s": 0.0015}})
    with pytest.raises(ValueError, match="ideal table"):
        run({"lateral_lag": {"lateral_response_ratio": 0.5}}, table_response_hz=math.inf)


# --- the sensor's laws --------------------------------------------------------------


def test_crosstalk_adds_exactly_the_leaks_of_fz():
    c = {"fz_to_fx": 0.01, "fz_to_fy": -0.005, "fz_to_mx_m": 0.003, "fz_to_my_m": -0.002}
    out = run({"sensor_crosstalk": c})
    w = delayed(out["wrench_act"], DELAY)  # [mx, my, mz, fx, fy, fz]
    fz = w[:, 5]
    want = w + np.outer(
        fz, [c["fz_to_mx_m"], c["fz_to_my_m"], 0.0, c["fz_to_fx"], c["fz_to_fy"], 0]
    )
    np.testing.assert_allclose(out["wrench_mea"], want, rtol=0, atol=1e-12 * np.abs(fz).max())
    assert np.abs(fz).max() > 1000.0  # a real press
    np.testing.assert_array_equal(out["wrench_mea"][:, [2, 5]], w[:, [2, 5]])  # mz, fz untouched


def test_a_turned_sensor_keeps_the_norms_and_turns_by_its_rotation():
    angles = np.array([0.01, -0.02, 0.005])
    out = run(
        {
            "sensor_misalignment": dict(
                zip(rig6.LIBRARY_EFFECTS["sensor_misalignment"], angles, strict=True)
            )
        }
    )
    w = delayed(out["wrench_act"], DELAY)
    r = out["wrench_mea"]
    for part in (slice(0, 3), slice(3, 6)):
        np.testing.assert_allclose(
            np.linalg.norm(r[:, part], axis=1), np.linalg.norm(w[:, part], axis=1), rtol=1e-12
        )
    rot = rig6.exp_so3(angles)
    np.testing.assert_allclose(r[:, 3:] @ rot, w[:, 3:], atol=1e-9)  # R^T f_read = f
    k = int(np.argmax(np.abs(w[:, 5])))
    angle = math.acos(r[k, 3:] @ w[k, 3:] / (np.linalg.norm(r[k, 3:]) * np.linalg.norm(w[k, 3:])))
    assert 0.0 < angle <= np.linalg.norm(angles) + 1e-12  # turned, by at most the rotation


def test_force_bias_offsets_fz_at_every_tick():
    out = run({"force_bias": {"bias_n": 7.5}})
    w = delayed(out["wrench_act"], DELAY)
    np.testing.assert_array_equal(out["wrench_mea"][:, :5], w[:, :5])
    np.testing.assert_allclose(out["wrench_mea"][:, 5], w[:, 5] - 7.5, rtol=0, atol=1e-9)
    assert out["wrench_mea"][0, 5] == -7.5  # before the contact too: the compression reads 7.5 N


def test_an_extra_delay_reads_whole_ticks_older_and_the_lead_stays_the_scenarios():
    out = run({"extra_delay": {"extra_delay_s": 0.003}}, compensator="SDC")
    w = out["wrench_mea"]
    np.testing.assert_array_equal(w, delayed(out["wrench_act"], DELAY + 3))
    h = 1e-3
    gate = np.linalg.norm(w[:, 3:], axis=1) > 0.0
    prev = np.vstack([np.zeros(6), w[:-1]])
    lead = 0.005  # the scenario's delay, not the rig's 8 ms
    want = np.where(gate[:, None], w + lead * (w - prev) / h, 0.0)
    np.testing.assert_allclose(out["wrench_comp"], want, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("tau_s", [0.001, 0.004, 0.02])
def test_sensor_filter_step_and_ramp_are_the_first_order_laws(tau_s):
    h = 1e-3
    sensor = rig6._Sensor(
        0, 400, h, rig6.normalize_hidden({"sensor_filter": {"time_constant_s": tau_s}})
    )
    a = math.exp(-h / tau_s)
    c = tau_s * (1.0 - a) / h
    step = np.array([sensor.read(k, np.ones(6))[5] for k in range(400)])
    k = np.arange(400)
    np.testing.assert_allclose(step, 1.0 - c * a**k, rtol=0, atol=1e-12)  # y[k] = 1 - c a^k
    sensor = rig6._Sensor(
        0, 400, h, rig6.normalize_hidden({"sensor_filter": {"time_constant_s": tau_s}})
    )
    ramp = np.array([sensor.read(j, np.full(6, j * h))[0] for j in range(400)])
    t = k * h  # exact for a piecewise-linear input: y = t - tau (1 - exp(-t / tau))
    np.testing.assert_allclose(ramp, t - tau_s * (1.0 - np.exp(-t / tau_s)), rtol=0, atol=1e-12)


def test_sensor_filter_in_the_loop_is_the_difference_equation_before_the_delay():
    tau = 0.004
    out = run({"sensor_filter": {"time_constant_s": tau}})
    a = math.exp(-1e-3 / tau)
    c = tau * (1.0 - a) / 1e-3
    u = out["wrench_act"]
    y = np.zeros_like(u)
    for k in range(len(u)):
        y[k] = (a * y[k - 1] + (c - a) * u[k - 1] if k else 0.0) + (1.0 - c) * u[k]
    np.testing.assert_allclose(out["wrench_mea"], delayed(y, DELAY), rtol=0, atol=1e-9)


@pytest.mark.parametrize("zeta", [0.1, 0.3])
def test_a_mount_resonance_overshoots_and_rings_as_a_second_order_system(zeta):
    f_hz, h, n = 30.0, 1e-4, 12000  # 1.2 s: the ring decays below 1e-9
    effects = rig6.normalize_hidden(
        {"mount_resonance": {"mount_frequency_hz": f_hz, "mount_damping_ratio": zeta}}
    )
    sensor = rig6._Sensor(0, n, h, effects)
    y = np.array([sensor.read(k, np.ones(6))[3] for k in range(n)])
    assert y[-1] == pytest.approx(1.0, abs=1e-6)  # unit gain
    overshoot = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    assert y.max() - 1.0 == pytest.approx(overshoot, rel=0.01)
    peaks = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    period = h * (peaks[1] - peaks[0])
    assert period == pytest.approx(1.0 / (f_hz * math.sqrt(1.0 - zeta**2)), abs=2 * h)


def test_the_quadratic_gain_bends_the_normal_channel_only():
    gain = 2e-5  # 1/N
    out = run({"fz_quadratic_gain": {"gain_per_n": gain}})
    w = delayed(out["wrench_act"], DELAY)
    np.testing.assert_array_equal(out["wrench_mea"][:, :5], w[:, :5])
    fz = w[:, 5]
    np.testing.assert_allclose(out["wrench_mea"][:, 5], fz + gain * fz * np.abs(fz), rtol=1e-12)


# --- the contact's laws ----------------------------------------------------------


def _pressed(tilt_rad=0.0):
    pads = rig6.pad_ring(8, 0.3, 0.01)
    q = np.array([0.0, 0.0, 0.002, 0.0, tilt_rad, 0.0])
    return pads, q


@pytest.mark.parametrize("tilt", [0.0, 0.01])
def test_friction_opposes_the_slip_and_is_bounded_by_mu_fn(tilt):
    pads, q = _pressed(tilt)
    k_pad, mu = K_N_PER_M / 8, 0.3
    rng = np.random.default_rng(4)
    for _ in range(20):
        qd = np.concatenate([rng.normal(0.0, 0.01, 3), rng.normal(0.0, 0.02, 3)])
        w0, delta = rig6.wrench(q, qd, pads, k_pad, 0.0, 0.01)
        w, _ = rig6.contact_wrench(q, qd, pads, k_pad, 0.0, 0.01, mu)
        friction = w - w0
        assert friction[5] == 0.0  # along the face only
        fn = -w0[5]
        assert np.hypot(friction[3], friction[4]) <= mu * fn * (1.0 + 1e-12)
        # each pad's push against the slip of the device's point at its contact point
        b = pads @ rig6.exp_so3(q[3:]).T
        power = 0.0
        for i in np.flatnonzero(delta > 0.0):
            lever = b[i] + [0.0, 0.0, 0.01 - 0.5 * delta[i]]
            slip = (qd[:3] + np.cross(qd[3:], lever))[:2]
            one = rig6.contact_wrench(q, qd, pads[[i]], k_pad, 0.0, 0.01, mu)[0]
            one -= rig6.wrench(q, qd, pads[[i]], k_pad, 0.0, 0.01)[0]
            ft = one[3:5]
            cross = ft[0] * slip[1] - ft[1] * slip[0]
            assert cross == pytest.approx(0.0, abs=1e-9 * mu * fn * np.hypot(*slip))  # parallel
            assert ft @ slip < 0.0  # against it
            np.testing.assert_allclose(one[:3], np.cross(lever, [*ft, 0.0]), atol=1e-12)
            power += ft @ slip
        assert power < 0.0  # friction never pushes the slip on


def test_friction_is_drakes_step5_below_the_stiction_tolerance():
    pads = rig6.pad_ring(8, 0.3, 0.01)
    q = np.array([0.0, 0.0, 0.002, 0.0, 0.0, 0.0])  # all eight pressed 2 mm
    k_pad, mu, vs = K_N_PER_M / 8, 0.3, rig6.STICTION_TOLERANCE_M_PER_S
    fn = K_N_PER_M * 0.002
    for s, factor in (
        (0.5 * vs, 0.5),
        (0.25 * vs, 0.25**3 * (10 - 15 * 0.25 + 6 * 0.0625)),
        (3 * vs, 1.0),
    ):
        qd = np.array([s, 0.0, 0.0, 0.0, 0.0, 0.0])
        w = rig6.contact_wrench(q, qd, pads, k_pad, 0.0, 0.01, mu)[0]
        assert w[3] == pytest.approx(-mu * factor * fn, rel=1e-12)
        assert w[4] == pytest.approx(0.0, abs=1e-9)
    assert rig6.contact_wrench(q, np.zeros(6), pads, k_pad, 0.0, 0.01, mu)[0][3] == 0.0


def test_hunt_crossley_adds_to_the_pads_dissipation():
    pads, q = _pressed()
    qd = np.array([0.0, 0.0, 0.05, 0.0, 0.0, 0.0])
    out = run()
    nominal = replay(out)
    damped = replay(out, {"hunt_crossley": {"damping_factor_s_per_m": 0.4}})
    w0 = rig6.wrench(q, qd, pads, K_N_PER_M / 8, 0.0, 0.01)[0]
    w1 = rig6.wrench(q, qd, pads, K_N_PER_M / 8, 0.4, 0.01)[0]
    assert w1[5] == pytest.approx(w0[5] * (1.0 + 0.4 * 0.05), rel=1e-12)
    on = nominal["in_contact"]
    assert np.any(np.abs(damped["wrench_act"][on, 5] - nominal["wrench_act"][on, 5]) > 10.0)
    np.testing.assert_array_equal(damped["q_act"], nominal["q_act"])  # the table is the same


def test_a_stiffer_contact_scales_the_replayed_wrench():
    out = run()
    nominal = replay(out)
    stiffer = replay(out, {"stiffness_error": {"contact_stiffness_n_per_m": 1.2e5}})
    np.testing.assert_allclose(
        stiffer["wrench_act"], 1.2 * nominal["wrench_act"], rtol=1e-12, atol=1e-9
    )


def test_a_proud_pad_touches_first_and_alone():
    pads = rig6.pad_ring(6, 0.3, 0.01)
    out = rig6.simulate_rig6(
        **(RIG | {"pad_count": 6, "lateral_offset_m": (0.0, 0.0), "misalignment_rad": (0.0, 0.0)}),
        hidden={"pad_proud": {"proud_m": 2e-4, "pad_index": 2}},
    )
    first = int(np.argmax(out["in_contact"]))
    q = out["q_act"][first]
    proud = pads.copy()
    proud[2, 2] += 2e-4
    delta = rig6.wrench(q, np.zeros(6), proud, 1.0, 0.0, 0.01)[1]
    assert np.flatnonzero(delta > 0.0).tolist() == [2]
    assert np.abs(out["wrench_act"][first, :2]).max() > 0.0  # a head-on press with a moment
    plain = rig6.simulate_rig6(
        **(RIG | {"pad_count": 6, "lateral_offset_m": (0.0, 0.0), "misalignment_rad": (0.0, 0.0)})
    )
    assert np.abs(plain["wrench_act"][:, :2]).max() < 1e-9  # the even ring: none


# --- the table's laws ----------------------------------------------------------------


def test_a_turned_table_tracks_the_turned_command_in_w():
    angles = np.array([0.01, -0.02, 0.005])
    scen = g.scenario(**{"table.response_hz": "inf", "approach.lateral_miss_m": [0.02, -0.01]})
    hidden = {
        "table_misalignment": dict(
            zip(rig6.LIBRARY_EFFECTS["table_misalignment"], angles, strict=True)
        )
    }
    rows = g.generate_run6(scen, hidden=hidden)
    rot = rig6.exp_so3(angles)
    p_des = np.column_stack([rows[f"p{a}_des_m"] for a in "xyz"])
    p_act = np.column_stack([rows[f"p{a}_act_m"] for a in "xyz"])
    np.testing.assert_allclose(p_act[1:], p_des[:-1] @ rot.T, rtol=0, atol=1e-15)
    th_des = g.rotation_vector_of_quaternion(np.column_stack([rows[f"q{a}_des"] for a in "wxyz"]))
    th_act = g.rotation_vector_of_quaternion(np.column_stack([rows[f"q{a}_act"] for a in "wxyz"]))
    np.testing.assert_allclose(th_act[1:], th_des[:-1] @ rot.T, rtol=0, atol=1e-14)


def test_table_response_and_damping_change_only_the_table():
    out = run()
    nominal = replay(out, table_start="tick0")
    lag = 2 * 0.8 / (2 * math.pi * 25.0)  # s: the nominal table's ramp lag
    for hidden, own_lag in (
        ({"table_response": {"table_response_ratio": 0.7}}, lag / 0.7),
        ({"table_damping": {"table_damping_factor": 1.3}}, 1.3 * lag),
    ):
        slow = replay(out, hidden, table_start="tick0")
        # tick 0 reads the table tracking the approach with its own ramp lag
        start = out["command_initial"] - own_lag * out["command_rate_initial"]
        np.testing.assert_allclose(slow["q_act"][0], start, rtol=0, atol=1e-15)
        assert nominal["q_act"][0, 2] - slow["q_act"][0, 2] == pytest.approx(
            (own_lag - lag) * 0.1, rel=1e-9
        )
        assert np.abs(slow["q_act"] - nominal["q_act"]).max() > 1e-5
        np.testing.assert_array_equal(slow["in_contact"][:5], False)


def test_lateral_lag_slows_px_py_only():
    out = run()
    nominal = replay(out)
    lagged = replay(out, {"lateral_lag": {"lateral_response_ratio": 0.5}})
    np.testing.assert_array_equal(lagged["q_act"][:, 2:], nominal["q_act"][:, 2:])
    assert np.abs(lagged["q_act"][:, :2] - nominal["q_act"][:, :2]).max() > 1e-6


def test_backlash_holds_the_stage_within_half_the_play_of_the_table():
    width = 2e-4
    out = run(table_response_hz=math.inf)
    played = replay(out, {"lateral_backlash": {"backlash_x_m": width}}, table_response_hz=math.inf)
    ideal = replay(out, table_response_hz=math.inf)
    gap = ideal["q_act"][:, 0] - played["q_act"][:, 0]
    assert np.abs(gap).max() <= 0.5 * width * (1 + 1e-9)
    assert np.abs(gap).max() == pytest.approx(0.5 * width, rel=1e-6)  # the x axis moves enough
    moved = np.flatnonzero(np.diff(played["q_act"][:, 0]) != 0.0) + 1
    np.testing.assert_allclose(np.abs(gap[moved]), 0.5 * width, rtol=1e-6)  # dragged at the edge
    np.testing.assert_array_equal(played["q_act"][:, 1:], ideal["q_act"][:, 1:])


# --- the rig computer: com_offset -----------------------------------------------------


def test_com_offset_changes_the_commands_not_the_contact_laws():
    c = np.array([0.05, -0.02, -0.1])
    scen = g.scenario(compensator={"name": "SDMDC"})
    hidden = {"com_offset": dict(zip(rig6.LIBRARY_EFFECTS["com_offset"], c, strict=True))}
    kw, miss, out = g._closed_loop(scen, hidden, "tick0", None)
    plain = g._closed_loop(scen, None, "tick0", None)[2]
    assert np.abs(out["q_des"] - plain["q_des"][: len(out["q_des"])]).max() > 1e-4
    # the physical part driven by the run's commands is the scenario's own
    rep = rig6.replay_rig6(
        out["command_initial"],
        out["command_rate_initial"],
        out["q_des"],
        out["qd_des"],
        **kw,
        table_start="tick0",
    )
    for name in ("q_act", "wrench_act", "wrench_mea"):
        np.testing.assert_array_equal(rep[name], out[name], err_msg=name)
    np.testing.assert_array_equal(out["command_initial"], plain["command_initial"])  # same start
    # the audit's equation: the computer's centre of mass moves by h f / m, its port at r - c
    rows = g.generate_run6(scen, hidden=hidden, table_start="tick0")
    h, m = 1e-3, RIG["mass_kg"]
    rot = [
        rig6.exp_so3(t)
        for t in g.rotation_vector_of_quaternion(
            np.column_stack([rows[f"q{a}_des"] for a in "wxyz"])
        )
    ]
    om = np.column_stack([rows[f"w{a}_des_rad_per_s"] for a in "xyz"])
    v_port = np.column_stack([rows[f"v{a}_des_m_per_s"] for a in "xyz"])
    f = np.column_stack([rows[f"f{a}_comp_n"] for a in "xyz"])
    r_json = np.array([0.01, 0.0, 1.5])
    residual = {}
    for name, r in (("computer", r_json - c), ("json", r_json)):
        v_com = v_port - np.array([np.cross(o, rr @ r) for o, rr in zip(om, rot, strict=True)])
        residual[name] = np.abs(np.diff(v_com, axis=0) - h * f[1:] / m).max()
    assert residual["computer"] < 1e-12
    assert residual["json"] > 1e-6


# --- sizing and sets -------------------------------------------------------------------


def test_the_replay_error_is_zero_without_an_effect_and_the_bias_over_the_noise_with_one():
    scen = g.scenario()
    assert g.replay_error6(scen, None, NOISE)["ratio"] == 0.0
    err = g.replay_error6(scen, {"force_bias": {"bias_n": 9.0}}, NOISE)
    assert err["worst"] == "fz_mea"
    assert err["ratio"] == pytest.approx(9.0 / NOISE["force_noise_n"], rel=1e-9)
    assert set(err["ratios"]) == set(g.CHANNELS)


@pytest.mark.parametrize("name", ["force_bias", "stiffness_error", "extra_delay"])
def test_sizing_puts_the_nominal_model_at_the_target(name):
    scen = g.scenario(**{"approach.initial_gap_m": 0.004})
    sized = g.size_effect6(scen, name, NOISE, 5.0, np.random.default_rng(1))
    assert sized is not None
    params, report = sized
    err = g.replay_error6(scen, {name: params}, NOISE)
    assert err["ratio"] == pytest.approx(report["ratio"], rel=1e-12)
    if name == "extra_delay":  # whole ticks: the nearest to the target
        assert 3.0 <= err["ratio"]
        assert params["extra_delay_s"] * 1000 == pytest.approx(
            round(params["extra_delay_s"] * 1000)
        )
    else:
        assert err["ratio"] == pytest.approx(5.0, rel=0.2)


@pytest.mark.parametrize(
    "name, seed",
    [
        ("contact_damping", 1),
        ("nonlinear_stiffness", 1),  # the sign drawn: an exponent below 1
        ("nonlinear_stiffness", 2),  # and above 1
        ("series_compliance", 1),
        ("coulomb_friction", 1),
    ],
)
def test_sizing_grows_a_pad_law_effect_to_the_target(name, seed):
    scen = g.scenario(**{"approach.initial_gap_m": 0.004})
    sized = g.size_effect6(scen, name, NOISE, 5.0, np.random.default_rng(seed))
    assert sized is not None
    params, report = sized
    assert report["ratio"] == pytest.approx(5.0, rel=0.2)
    assert g.replay_error6(scen, {name: params}, NOISE)["ratio"] == report["ratio"]
    k, mass, v0 = RIG["contact_stiffness_n_per_m"], RIG["mass_kg"], 0.1
    scale = {  # the family's scale s, within its range
        "contact_damping": params.get("damping_n_s_per_m", 0.0) / (2.0 * math.sqrt(k * mass)),
        "series_compliance": params.get("series_compliance_m_per_n", 0.0) * k,
        "coulomb_friction": params.get("friction_force_n", 0.0) / (v0 * math.sqrt(k * mass)),
        "nonlinear_stiffness": abs(params.get("exponent", 1.0) - 1.0),
    }[name]
    assert 0.0 < scale < 0.5
    if name == "nonlinear_stiffness":
        assert params["reference_stiffness_n_per_m"] == k  # the scenario's stiffness
        assert (params["exponent"] < 1.0) == (seed == 1)


def test_the_library_cannot_explain_an_outside_effect_it_is_sized_by():
    scen = g.scenario(**{"approach.initial_gap_m": 0.004})
    sized = g.size_effect6(scen, "pad_proud", NOISE, 4.0, np.random.default_rng(2))
    assert sized is not None
    params, report = sized
    assert report["ratio"] == pytest.approx(4.0, rel=0.2)
    assert report["nominal_ratio"] >= report["ratio"]  # the projection only takes away
    # a library effect alone, sized the same way, is taken by the projection
    err = g.replay_error6(
        scen, {"stiffness_error": {"contact_stiffness_n_per_m": 1.05e5}}, NOISE, project=True
    )
    assert err["ratio"] > 3.0 and err["residual_ratio"] < 0.05 * err["ratio"]


def test_a_drawn_set_is_written_and_says_what_it_hid(tmp_path):
    s6 = g.draw_set6(5, "single", ["force_bias"], n_runs=2)
    assert s6.effects == ["force_bias"] and list(s6.hidden) == ["force_bias"]
    assert s6.truth["library"] == ["force_bias"] and s6.truth["outside"] == []
    assert 3.0 <= s6.truth["sizing"]["force_bias"]["ratio"] <= 8.0
    paths = g.write_set6(tmp_path / "set", s6, truth=True)
    assert [p.name for p in paths] == ["run1.csv", "run2.csv"]
    assert (tmp_path / "set" / "run2.json").exists() and (tmp_path / "set" / "truth.json").exists()
    speeds = {s["approach"]["initial_velocity_m_per_s"] for s, _ in s6.runs}
    assert len(speeds) == 2  # different approaches, one rig
    rigs = [{k: v for k, v in s.items() if k != "approach"} for s, _ in s6.runs]
    assert rigs[0] == rigs[1]
    null = g.draw_set6(5, "null", n_runs=1)
    assert null.hidden == {} and null.truth["hidden"] == {}
    with pytest.raises(ValueError, match="two parts"):
        g.draw_set6(5, "pair", ["stiffness_error", "hunt_crossley"])


@pytest.mark.parametrize("seed", [1, 11])
def test_a_drawn_delay_is_at_its_target_in_the_sets_noise(seed):
    s6 = g.draw_set6(seed, "single", ["extra_delay"], n_runs=1)
    report, target = s6.truth["sizing"]["extra_delay"], s6.truth["targets"]["extra_delay"]
    assert 3.0 <= report["ratio"] <= 1.2 * target  # a noisier rig when one tick is more
    scen = s6.runs[0][0]
    hold_s = 100.0 / scen["rig"]["sample_rate_hz"]
    err = g.replay_error6(scen, s6.hidden, s6.truth["noise"], hold_s=hold_s)
    assert err["ratio"] == pytest.approx(report["ratio"], rel=1e-9)
    assert s6.truth["run_errors"][0]["ratio"] == pytest.approx(report["ratio"], rel=1e-9)


@pytest.mark.parametrize("seed", [1, 2])
def test_sizing_grows_a_table_resonance_to_the_target(seed):
    scen = g.scenario(**{"approach.initial_gap_m": 0.004})
    sized = g.size_effect6(scen, "table_resonance", NOISE, 5.0, np.random.default_rng(seed))
    assert sized is not None
    params, report = sized
    assert report["ratio"] == pytest.approx(5.0, rel=0.2)
    assert g.replay_error6(scen, {"table_resonance": params}, NOISE)["ratio"] == report["ratio"]
    assert 15.0 <= params["frequency_hz"] <= 450.0  # the family's periods, 1/450 to 1/15 s
    assert 0.03 <= params["damping_ratio"] <= 0.2
