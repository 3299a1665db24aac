"""The 6-DoF run generator ``run6_logs`` against itself and the format document
(no hybridtable code): its columns, quaternions, time grid and twist, its one
contact and the energy it gains or keeps, the files it writes, and that each
corruption breaks the one thing it names (checked by this file's own reading
of ``docs/run6-format.md``'s checks)."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from tests.generators import rig6
from tests.generators import run6_logs as g

H = 1e-3
XYZ, WXYZ = "xyz", "wxyz"
K_N_PER_M = 1e5
MASS = K_N_PER_M / (2.0 * math.pi) ** 2  # contact frequency 1 Hz
INERTIA = np.diag([1689.0, 1689.0, 1689.0])
R_PORT = np.array([0.01, 0.0, 1.5])
SMALL_NOISE = {
    "force_noise_n": 0.5,
    "moment_noise_n_m": 0.1,
    "position_noise_m": 1e-6,
    "attitude_noise_rad": 1e-6,
}
IDEAL = {"table.response_hz": "inf", "rig.sensor_delay_s": 0.0}


def vec(rows, pattern: str, axes: str = XYZ) -> np.ndarray:
    return np.column_stack([rows[pattern.format(a)] for a in axes])


@pytest.fixture(scope="module")
def nominal():
    return g.generate_run6(g.scenario())


@pytest.fixture(scope="module")
def noisy():
    return g.generate_run6(g.scenario(), seed=3, **SMALL_NOISE)


@pytest.fixture(scope="module")
def ideal():
    return g.generate_run6(g.scenario(**IDEAL))


def fed(rows) -> np.ndarray:
    """Rows where the model was fed a wrench."""
    return np.any(vec(rows, "f{}_comp_n") != 0.0, axis=1) | np.any(
        vec(rows, "m{}_comp_n_m") != 0.0, axis=1
    )


def cor_normal(rows) -> float:
    """The port's normal velocity just after the last wrench the model felt over
    the one just before the first."""
    on = np.flatnonzero(fed(rows))
    vz = rows["vz_des_m_per_s"]
    return abs(vz[on[-1]]) / abs(vz[on[0] - 1])


def rotations(rows, which: str) -> list[np.ndarray]:
    theta = g.rotation_vector_of_quaternion(vec(rows, "q{}_" + which, WXYZ))
    return [rig6.exp_so3(t) for t in theta]


# --- columns, quaternions, time -----------------------------------------------


def test_the_record_has_the_documents_33_columns(nominal):
    assert tuple(nominal) == g.COLUMNS
    assert len(g.COLUMNS) == len(set(g.COLUMNS)) == 33
    n = len(nominal["time_s"])
    assert all(len(v) == n and v.dtype == float for v in nominal.values())
    assert all(np.isfinite(v).all() for v in nominal.values())


@pytest.mark.parametrize("which", ["des", "act"])
def test_quaternions_are_unit_and_sign_continuous(nominal, noisy, which):
    for rows in (nominal, noisy):
        q = vec(rows, "q{}_" + which, WXYZ)
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
        assert q[0, 0] >= 0.0
        assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0.0)


def test_quaternion_sign_continuity_survives_a_turn_past_180_degrees():
    theta = np.outer(np.linspace(0.0, 1.9 * math.pi, 50), [0.0, 0.0, 1.0])
    q = g.quaternion_of_rotation_vector(theta)
    q[30:] *= -1.0  # as a logger with w >= 0 beyond 180 deg would not do
    fixed = g._sign_continuous(q)
    assert fixed[0, 0] >= 0.0 and np.all(np.sum(fixed[1:] * fixed[:-1], axis=1) > 0.0)


def test_rotation_vector_round_trip():
    theta = np.array([[0.3, -0.2, 1.1], [1e-9, 0.0, 2e-9], [0.0, 0.0, 0.0]])
    q = g.quaternion_of_rotation_vector(theta)
    np.testing.assert_allclose(g.rotation_vector_of_quaternion(q), theta, atol=1e-15)
    np.testing.assert_allclose(g.rotation_vector_of_quaternion(-2.0 * q), theta, atol=1e-15)
    np.testing.assert_allclose(rig6.exp_so3(theta[0]), _matrix(q[0]), atol=1e-15)


def _matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_time_is_k_over_the_sample_rate(nominal):
    t = nominal["time_s"]
    np.testing.assert_array_equal(t, np.arange(len(t)) / 1000.0)
    fast = g.generate_run6(g.scenario(**{"rig.sample_rate_hz": 2000.0}))["time_s"]
    np.testing.assert_array_equal(fast, np.arange(len(fast)) / 2000.0)


# --- the twist and the poses --------------------------------------------------


def test_p_des_steps_by_v_des_times_h(nominal):
    p, v = vec(nominal, "p{}_des_m"), vec(nominal, "v{}_des_m_per_s")
    step = np.diff(p, axis=0)
    # exact for the centre of mass; the port's lever arm turns by O(h^2 w^2 r) more
    np.testing.assert_allclose(step, H * v[1:], rtol=0, atol=1e-4 * H * 0.1)
    assert np.abs(v[:, :2]).max() > 1e-3  # the offset contact moves the port sideways


def test_w_des_is_the_commanded_attitudes_change(nominal):
    rot = rotations(nominal, "des")
    w = vec(nominal, "w{}_des_rad_per_s")
    turn = np.array([rig6.log_so3(rot[k] @ rot[k - 1].T) for k in range(1, len(rot))])
    np.testing.assert_allclose(turn, H * w[1:], rtol=0, atol=1e-15)
    assert np.abs(w).max() > 0.01  # rad/s: the contact turns the body


def test_the_port_velocity_is_rig6s(nominal):
    out = rig6.simulate_rig6(
        mass_kg=MASS,
        lateral_offset_m=(0.01, 0.0),
        misalignment_rad=(0.0, math.radians(2.0)),
        table_response_hz=25.0,
        sensor_delay_s=0.005,
    )
    np.testing.assert_allclose(
        nominal["vz_des_m_per_s"], out["port_velocity_z_m_per_s"], rtol=0, atol=1e-14
    )
    np.testing.assert_allclose(vec(nominal, "p{}_des_m"), out["q_des"][:, :3], atol=0)
    np.testing.assert_allclose(vec(nominal, "p{}_act_m"), out["q_act"][:, :3], atol=0)
    np.testing.assert_allclose(vec(nominal, "f{}_comp_n"), out["wrench_comp"][:, 3:], atol=0)
    np.testing.assert_allclose(vec(nominal, "m{}_comp_n_m"), out["wrench_comp"][:, :3], atol=0)


def test_the_ideal_table_is_at_the_last_command(ideal):
    np.testing.assert_array_equal(vec(ideal, "p{}_act_m")[1:], vec(ideal, "p{}_des_m")[:-1])
    np.testing.assert_allclose(
        vec(ideal, "q{}_act", WXYZ)[1:], vec(ideal, "q{}_des", WXYZ)[:-1], atol=1e-15
    )


def test_the_measured_wrench_is_the_contacts_at_the_table_pose_a_delay_before(nominal):
    """Force and moment by name, on the spacecraft (fz < 0 pressing), 5 ticks late."""
    pads = rig6.pad_ring(8, 0.3, 0.01)
    q_act = np.column_stack(
        [vec(nominal, "p{}_act_m"), g.rotation_vector_of_quaternion(vec(nominal, "q{}_act", WXYZ))]
    )
    want = np.array([rig6.wrench(q, np.zeros(6), pads, K_N_PER_M / 8, 0.0, 0.01)[0] for q in q_act])
    f, m = vec(nominal, "f{}_mea_n"), vec(nominal, "m{}_mea_n_m")
    np.testing.assert_allclose(f[5:], want[:-5, 3:], atol=1e-6)
    np.testing.assert_allclose(m[5:], want[:-5, :3], atol=1e-6)
    assert not f[:5].any() and not m[:5].any()
    assert f[:, 2].min() < -1000.0 and f[:, 2].max() <= 0.0  # a press pushes the spacecraft back
    # pitched +2 deg about y, the pads at +x touch first: the press turns the body back
    assert m[np.argmin(f[:, 2]), 1] < -10.0
    # no compensator: the model is fed what was measured
    np.testing.assert_array_equal(vec(nominal, "f{}_comp_n"), f)
    np.testing.assert_array_equal(vec(nominal, "m{}_comp_n_m"), m)


def test_a_lateral_miss_moves_the_positions_only(nominal):
    missed = g.generate_run6(g.scenario(**{"approach.lateral_miss_m": [0.02, -0.01]}))
    shift = {"px": 0.02, "py": -0.01}
    for name in g.COLUMNS:
        if name[:2] in shift:
            np.testing.assert_allclose(missed[name], nominal[name] + shift[name[:2]], atol=1e-15)
        else:
            np.testing.assert_array_equal(missed[name], nominal[name], err_msg=name)


# --- the contact and its energy -------------------------------------------------


@pytest.mark.parametrize("which", ["nominal", "ideal"])
def test_one_contact_out_of_contact_at_both_ends(nominal, ideal, which):
    rows = {"nominal": nominal, "ideal": ideal}[which]
    on = fed(rows)
    assert on.any() and not on[:5].any() and not on[-20:].any()
    assert np.count_nonzero(np.diff(on.astype(int)) == 1) == 1  # one block of contact
    measured = np.any(vec(rows, "f{}_mea_n") != 0.0, axis=1)
    assert not measured[0] and not measured[-20:].any()


def test_delay_without_compensation_returns_more_than_it_got(nominal):
    assert cor_normal(nominal) > 1.05


def test_the_ideal_rig_keeps_the_normal_speed_and_the_energy(ideal):
    assert cor_normal(ideal) == pytest.approx(1.0, abs=0.05)
    assert cor_normal(ideal) < 1.0  # a tilted ring turns some of the approach into rotation

    def kinetic(k: int) -> float:
        rot = rotations(ideal, "des")[k]
        w = vec(ideal, "w{}_des_rad_per_s")[k]
        v_com = vec(ideal, "v{}_des_m_per_s")[k] - np.cross(w, rot @ R_PORT)
        return 0.5 * MASS * v_com @ v_com + 0.5 * w @ (rot @ INERTIA @ rot.T) @ w

    assert kinetic(0) == pytest.approx(0.5 * MASS * 0.1**2, rel=1e-12)
    assert kinetic(len(ideal["time_s"]) - 1) / kinetic(0) == pytest.approx(1.0, abs=1e-4)


# --- noise --------------------------------------------------------------------


def test_noise_is_seeded_measurement_noise_of_the_asked_size(nominal, noisy):
    again = g.generate_run6(g.scenario(), seed=3, **SMALL_NOISE)
    other = g.generate_run6(g.scenario(), seed=4, **SMALL_NOISE)
    for name in g.COLUMNS:
        np.testing.assert_array_equal(noisy[name], again[name])
    assert not np.array_equal(noisy["fz_mea_n"], other["fz_mea_n"])
    for name in g.COLUMNS:  # the commands, twist and fed wrench are the loop's
        if not name.endswith(("_mea_n", "_mea_n_m", "_act_m", "_act")):
            np.testing.assert_array_equal(noisy[name], nominal[name], err_msg=name)
    for pattern, size in (("f{}_mea_n", 0.5), ("m{}_mea_n_m", 0.1), ("p{}_act_m", 1e-6)):
        residual = vec(noisy, pattern) - vec(nominal, pattern)
        assert residual.std() == pytest.approx(size, rel=0.1)
    turn = [
        rig6.log_so3(a @ b.T)
        for a, b in zip(rotations(noisy, "act"), rotations(nominal, "act"), strict=True)
    ]
    assert np.std(turn) == pytest.approx(1e-6, rel=0.1)


# --- the scenario and the files -------------------------------------------------


def test_the_nominal_scenario_and_its_overrides():
    s = g.scenario()
    assert list(s) == ["spacecraft", "contact", "approach", "rig", "table", "compensator"]
    assert s["contact"]["geometry"] == "plate" and s["table"]["backend"] == "model"
    assert s["compensator"] == {"name": "none"}
    t = g.scenario(
        **{"approach.initial_gap_m": 0.01, "spacecraft.contact_frequency_hz": None},
        spacecraft={"mass_kg": 2000.0},
    )
    assert t["approach"]["initial_gap_m"] == 0.01
    assert "contact_frequency_hz" not in t["spacecraft"] and t["spacecraft"]["mass_kg"] == 2000.0
    assert g.scenario()["approach"]["initial_gap_m"] == 0.001  # the nominal is not changed
    with pytest.raises(ValueError, match="no section"):
        g.scenario(**{"plant.mass_kg": 1.0})


def test_a_mass_instead_of_the_contact_frequency_is_the_same_run(nominal):
    by_mass = g.generate_run6(
        g.scenario(**{"spacecraft.mass_kg": MASS, "spacecraft.contact_frequency_hz": None})
    )
    np.testing.assert_array_equal(by_mass["fz_mea_n"], nominal["fz_mea_n"])


@pytest.mark.parametrize(
    "override, words",
    [
        ({"contact.friction_coefficient": 0.3}, "friction"),
        ({"contact.geometry": "cone"}, "plate"),
        ({"table.backend": "stewart"}, "backend"),
        ({"approach.angular_rate_rad_per_s": [0.0, 0.1, 0.0]}, "rotation"),
        ({"rig.force_noise_n": 2.0}, "noise"),
        ({"rig.sensor_delay_s": 0.0045}, "whole number of ticks"),
        ({"compensator.stiffness_model": "nominal"}, "linearizes"),
        ({"compensator.name": "sdmdc-online"}, "rig6 runs"),
        ({"contact.probe_radius_m": 0.05}, "cannot run"),
        ({"spacecraft.mass_kg": 2000.0}, "one of mass_kg"),
    ],
)
def test_what_rig6_cannot_run_is_refused(override, words):
    with pytest.raises(ValueError, match=words):
        g.generate_run6(g.scenario(**override))


def test_the_pad_law_keys_are_read_from_the_contact_with_their_defaults():
    kw, _ = g._rig6_arguments(g.scenario())
    assert {key: kw[key] for key in rig6.PAD_LAW_KEYS} == rig6.PAD_LAW_KEYS  # absent: defaults
    law = {
        "contact_exponent": 1.3,
        "reference_press_m": 0.006,
        "contact_damping_n_s_per_m": 250.0,
        "series_compliance_m_per_n": 2e-6,
        "normal_friction_force_n": 15.0,
        "normal_friction_velocity_m_per_s": 0.002,
    }
    scen = g.scenario(contact=law)
    kw, _ = g._rig6_arguments(scen)
    assert {key: kw[key] for key in law} == law
    rows = g.generate_run6(scen)  # the scenario's own contact, in the loop and its record
    out = rig6.simulate_rig6(**kw)
    np.testing.assert_array_equal(rows["fz_mea_n"], out["wrench_mea"][:, 5])
    plain = rig6.simulate_rig6(**(kw | rig6.PAD_LAW_KEYS))
    assert abs(out["peak_force_n"] - plain["peak_force_n"]) > 10.0  # N: the law shows


@pytest.mark.parametrize(
    "contact, words",
    [
        ({"contact_exponent": 1.5}, "reference_press_m"),
        ({"normal_friction_force_n": 5.0}, "normal_friction_velocity_m_per_s"),
        ({"contact_exponent": 0.0, "reference_press_m": 0.01}, "contact_exponent.*above 0"),
        ({"reference_press_m": -0.01}, "reference_press_m.*above 0"),
        ({"contact_damping_n_s_per_m": -1.0}, "contact_damping_n_s_per_m.*at least 0"),
        ({"series_compliance_m_per_n": -1e-6}, "series_compliance_m_per_n.*at least 0"),
        ({"normal_friction_force_n": -1.0}, "normal_friction_force_n.*at least 0"),
        ({"contact_damping_n_s_per_m": "lots"}, "not a number"),
    ],
)
def test_a_pad_law_out_of_its_range_is_refused_by_its_key(contact, words):
    with pytest.raises(ValueError, match=words):
        g._rig6_arguments(g.scenario(contact=contact))


def test_write_run6_writes_the_pair(tmp_path, noisy):
    scen = g.scenario(**IDEAL)
    csv_path, json_path = g.write_run6(tmp_path / "runs", "run1", scen, noisy)
    assert csv_path == tmp_path / "runs" / "run1.csv" and json_path.suffix == ".json"
    with open(csv_path, newline="", encoding="utf-8") as stream:
        table = list(csv.reader(stream))
    assert tuple(table[0]) == g.COLUMNS
    assert len(table) == len(noisy["time_s"]) + 1
    for i, name in enumerate(g.COLUMNS):  # repr round-trips exactly
        np.testing.assert_array_equal([float(row[i]) for row in table[1:]], noisy[name])
    doc = json.loads(json_path.read_text(encoding="utf-8"))
    assert doc["format"] == "hybridtable-run6/1" and doc["run_id"] == "run1"
    assert doc["scenario"]["table"]["response_hz"] == "inf"
    assert doc["scenario"] == json.loads(json.dumps(scen))
    _, other = g.write_run6(tmp_path, "run2", scen, noisy, run_id="offset-1")
    assert json.loads(other.read_text())["run_id"] == "offset-1"


# --- corruptions ----------------------------------------------------------------


def noise_level(x: np.ndarray) -> float:
    """Robust white-noise level from second differences (MAD)."""
    d2 = np.diff(x, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


def _fit(y: np.ndarray, x: np.ndarray) -> float:
    """Least-squares scale of ``y`` against ``x``."""
    return float(np.sum(x * y) / np.sum(x * x))


def defects(rows, rate: float = 1000.0) -> set[str]:
    """This file's reading of the document's checks of a CSV: each defect found."""
    found = set()
    if set(g.COLUMNS) - set(rows):
        return {"missing_column"}
    if not all(np.isfinite(rows[c]).all() for c in g.COLUMNS):
        return {"nan_cell"}
    t = rows["time_s"]
    if np.any(np.diff(t) <= 0.0) or t[0] != 0.0 or np.abs(np.diff(t) * rate - 1).max() > 0.01:
        found.add("time_not_increasing")
    for which in ("des", "act"):
        q = vec(rows, "q{}_" + which, WXYZ)
        if np.abs(np.linalg.norm(q, axis=1) - 1.0).max() > 1e-3:
            found.add("not_unit_quaternion")
        elif q[0, 0] < 0.0 or np.any(np.sum(q[1:] * q[:-1], axis=1) < 0.0):
            found.add("quaternion_sign_flip")
    if "quaternion_sign_flip" not in found:
        rot = rotations(rows, "des")
        turn = np.array([rig6.log_so3(rot[k] @ rot[k - 1].T) for k in range(1, len(rot))])
        w = vec(rows, "w{}_des_rad_per_s")[1:]
        if np.abs(turn).max() > 0.0:
            scale = _fit(w, turn * rate)
            if abs(scale - 180.0 / math.pi) < 0.01 * 57.3:
                found.add("degrees")
            elif abs(scale - 1.0) > 0.01:
                found.add("w_des")
        elif np.abs(w).max() > 0.0:
            found.add("w_des")
    scale = _fit(vec(rows, "v{}_des_m_per_s")[1:], np.diff(vec(rows, "p{}_des_m"), axis=0) * rate)
    if abs(scale - 1.0) > 0.01:
        found.add("sign_flipped_velocity")
    wrench = np.column_stack([vec(rows, "f{}_mea_n"), vec(rows, "m{}_mea_n_m")])
    above = np.abs(wrench) > 5.0 * np.array([noise_level(c) for c in wrench.T])
    if not above.any():
        found.add("no_contact")
    elif above[0].any():
        found.add("starts_in_contact")
    return found


@pytest.mark.parametrize("which", ["nominal", "noisy"])
def test_the_good_records_pass_every_check(nominal, noisy, which):
    rows = {"nominal": nominal, "noisy": noisy}[which]
    assert defects(rows) == set()


@pytest.fixture(scope="module")
def long_approach():
    """A free flight of 50 ms before the touch, for ``no_contact``."""
    return g.generate_run6(g.scenario(**{"approach.initial_gap_m": 0.005}), seed=1, **SMALL_NOISE)


@pytest.mark.parametrize("kind", [k for k in g.CORRUPTIONS if k not in g.JSON_CORRUPTIONS])
def test_each_corruption_breaks_what_it_names(noisy, long_approach, kind):
    rows = long_approach if kind == "no_contact" else noisy
    bad, words = g.corrupt(rows, kind)
    assert defects(bad) == {kind}
    assert words and all(group and all(w == w.lower() for w in group) for group in words)
    assert defects(rows) == set()  # the record given is not changed
    if kind == "degrees":
        rot = rotations(bad, "des")
        turn = np.array([rig6.log_so3(rot[k] @ rot[k - 1].T) for k in range(1, len(rot))])
        w = vec(bad, "w{}_des_rad_per_s")[1:]
        assert _fit(w, turn / H) == pytest.approx(180.0 / math.pi, rel=1e-9)
    if kind == "no_contact":
        assert 20 <= len(bad["time_s"]) < len(rows["time_s"])
        assert not np.any(vec(bad, "f{}_comp_n")) and np.all(vec(bad, "p{}_act_m")[:, 2] < -0.01)


def test_the_corrupt_files_hold_the_defect(tmp_path, noisy):
    scen = g.scenario()
    for kind in g.CORRUPTIONS:
        csv_path, json_path, words = g.write_corrupt_run6(tmp_path, kind, scen, noisy, kind)
        header = csv_path.read_text(encoding="utf-8").splitlines()[0].split(",")
        doc = json.loads(json_path.read_text(encoding="utf-8"))
        assert ("my_mea_n_m" in header) == (kind != "missing_column")
        want = "hybridtable-run6/2" if kind == "bad_format" else "hybridtable-run6/1"
        assert doc["format"] == want
        if kind == "nan_cell":
            assert ",nan" in csv_path.read_text(encoding="utf-8")
        assert words == g.corrupt(noisy, kind)[1]


def test_corrupt_refuses_what_it_cannot_break(nominal, ideal):
    with pytest.raises(ValueError, match="initial_gap_m"):
        g.corrupt(ideal, "no_contact")  # 1 mm of free flight, touching at once: too few rows
    flat = g.generate_run6(
        g.scenario(
            **{"spacecraft.lateral_offset_m": [0.0, 0.0], "approach.misalignment_deg": [0, 0]}
        )
    )
    with pytest.raises(ValueError, match="does not turn"):
        g.corrupt(flat, "degrees")
    with pytest.raises(ValueError, match="unknown corruption"):
        g.corrupt(nominal, "upside_down")


def test_message_names():
    words = [("time",), ("increasing", "order")]
    assert g.message_names("run1.csv line 12: TIME_S not strictly Increasing", words)
    assert not g.message_names("run1.csv line 12: time_s period off", words)
