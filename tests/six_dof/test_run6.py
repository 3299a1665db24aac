"""The 6-DoF run format: written from a simulated run, read back exactly, its
defects refused, replayed exactly, and compared (hybridtable.six_dof.run6,
replay6, compare6). The independent generator's runs are in test_run6_cli.py."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.six_dof.compare6 import EXPLAINED_SIGMA, compare_run6
from hybridtable.six_dof.pose import (
    quaternion_product,
    quaternions_of_rotation_vectors,
    rotation_exp,
    rotation_vectors_of_quaternions,
)
from hybridtable.six_dof.replay6 import replay_run6
from hybridtable.six_dof.run6 import (
    RUN6_COLUMNS,
    read_run6,
    read_runs6,
    run6_csv_text,
    run6_json,
    run6_of_docking,
)
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.conftest import docking_params

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "six_dof"

#: A scenario's document as the run's JSON holds it (the conftest's rig).
SCENARIO = {
    "spacecraft": {
        "contact_frequency_hz": 1.0,
        "inertia_kg_m2": [1689.0, 1689.0, 1689.0],
        "port_distance_m": 1.5,
        "lateral_offset_m": [0.01, 0.0],
    },
    "contact": {"contact_stiffness_n_per_m": 1.0e5},
    "approach": {
        "initial_velocity_m_per_s": 0.1,
        "initial_gap_m": 0.001,
        "misalignment_deg": [0.0, 2.0],
    },
    "rig": {"sample_rate_hz": 1000.0, "sensor_delay_s": 0.005},
    "table": {"response_hz": 25.0, "damping_ratio": 0.8},
    "compensator": {"name": "SDMDC"},
}


def scenario_params(**changes):
    """The loop of :data:`SCENARIO`, with ``changes`` (flat names)."""
    from hybridtable.six_dof.scenario import parse_scenario

    return parse_scenario(SCENARIO).with_(**changes)


@pytest.fixture(scope="module")
def recorded():
    """The scenario's run (SDMDC, offset and tilt), as the format's rows."""
    return run6_of_docking(simulate6(scenario_params()), "offset", SCENARIO)


def _write(folder, run, stem="run1", csv=None, doc=None):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{stem}.csv").write_text(csv if csv is not None else run6_csv_text(run))
    (folder / f"{stem}.json").write_text(json.dumps(doc if doc is not None else run6_json(run)))
    return folder / f"{stem}.csv"


def test_quaternions_are_the_rotation_vectors_rotations():
    rng = np.random.default_rng(3)
    theta = rng.normal(size=(400, 3)) * rng.choice([1e-9, 1e-5, 1e-2, 0.5], size=(400, 1))
    q = quaternions_of_rotation_vectors(theta)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    assert np.all(q[:, 0] >= 0.0)
    back = rotation_vectors_of_quaternions(-q)  # either sign
    assert np.max(np.abs(back - theta) / np.linalg.norm(theta, axis=1)[:, None]) < 1e-14
    # q r q* rotates r as exp([theta]x) does
    r = np.array([0.3, -0.2, 0.9])
    for t, qq in zip(theta[:20], q[:20], strict=True):
        pure = np.array([[0.0, *r]])
        turned = quaternion_product(quaternion_product(qq[None], pure), qq[None] * [1, -1, -1, -1])
        assert np.allclose(turned[0, 1:], rotation_exp(t) @ r, atol=1e-14)


def test_a_run_reads_back_exactly_and_its_rows_are_the_rig_computers_ticks(recorded, tmp_path):
    csv = _write(tmp_path / "a", recorded)
    header = csv.read_text().splitlines()[0].split(",")
    assert header == list(RUN6_COLUMNS) and len(header) == 33
    back = read_run6(csv)
    assert back.run_id == "offset" and back.params.compensator == "SDMDC"
    for name, block in recorded.blocks.items():
        assert np.array_equal(back.blocks[name], block), name
    h = back.params.sample_period_s
    # step 3 of the format: the model's port velocity moves the command by h v
    # (to the lever arm's turn), and the attitude turns by exp(h w) exactly
    step = np.diff(back.blocks["p_des"], axis=0)
    assert np.max(np.abs(step - h * back.blocks["v_des"][1:])) < 1e-4 * h * 0.1
    R = [rotation_exp(t) for t in back.pose("des")[:, 3:]]
    for k in (1, 200, 400):
        assert np.allclose(R[k], rotation_exp(h * back.blocks["w_des"][k]) @ R[k - 1], atol=1e-12)
    # the compensated force is what moved the model: m dv = h f at the centre of mass
    body = back.params.spacecraft
    arm = np.array([r @ body.port_position_m for r in R])
    v_com = back.blocks["v_des"] - np.cross(back.blocks["w_des"], arm)
    dv = np.diff(v_com, axis=0)
    f = back.blocks["f_comp"][1:]
    assert np.max(np.abs(body.mass_kg * dv - h * f)) < 1e-9 * np.max(np.abs(h * f))
    # a head-on press pushes the spacecraft back
    assert back.blocks["f_mea"][:, 2].min() < -1000.0 and back.blocks["f_mea"][:, 2].max() <= 0.0


def test_the_replay_of_a_noise_free_run_is_the_run(recorded):
    replay = replay_run6(recorded)
    # the command is read back through its quaternion: round-off only
    w = recorded.wrench("mea")
    assert np.max(np.abs(replay.measured_wrench - w)) < 1e-9 * np.max(np.abs(w))
    assert np.max(np.abs(replay.table_state[:, :6] - recorded.pose("act"))) < 1e-15


def test_compare_explains_its_own_run_and_names_a_stiffer_contact(recorded, tmp_path):
    c = compare_run6(recorded)
    assert c.explained and c.worst.error_sigma < 1e-9
    assert math.isclose(c.cor_measured, c.cor_model, rel_tol=1e-12)
    # the rig's contact is 30 % stiffer than the scenario says
    stiff = scenario_params(contact_stiffness_n_per_m=1.3e5)
    run = run6_of_docking(simulate6(stiff), "stiff", SCENARIO)
    c = compare_run6(run)
    assert not c.explained
    assert c.worst.name == "fz_mea" and c.worst.worst_phase == "contact"
    assert c.worst.error_sigma > 10 * EXPLAINED_SIGMA
    assert "misses" in c.verdict()


def _broken(recorded, tmp_path, column, change):
    text = run6_csv_text(recorded).splitlines()
    header = text[0].split(",")
    j = header.index(column)
    rows = [line.split(",") for line in text[1:]]
    change(rows, j)
    body = "\n".join([text[0]] + [",".join(r) for r in rows]) + "\n"
    return _write(tmp_path / column, recorded, csv=body)


@pytest.mark.parametrize(
    ("column", "change", "words"),
    [
        (
            "qw_act",
            lambda rows, j: rows[100].__setitem__(j, str(1.2 * float(rows[100][j]))),
            "not a unit quaternion",
        ),
        (
            "qy_des",
            lambda rows, j: [
                r.__setitem__(j + k, repr(-float(r[j + k])))
                for r in rows[300:]
                for k in (-2, -1, 0, 1)
            ],
            "changes sign",
        ),
        (
            "wy_des_rad_per_s",
            lambda rows, j: [
                r.__setitem__(j + k, repr(math.degrees(float(r[j + k]))))
                for r in rows
                for k in (-1, 0, 1)
            ],
            "degrees per second",
        ),
        (
            "vz_des_m_per_s",
            lambda rows, j: [r.__setitem__(j, repr(-float(r[j]))) for r in rows],
            "sign-flipped or mislabelled velocity",
        ),
        ("fx_mea_n", lambda rows, j: rows[50].__setitem__(j, "nan"), "not finite"),
        (
            # a quaternion logged (x, y, z, w): about 180 deg from the target frame
            "qw_act",
            lambda rows, j: [
                r.__setitem__(slice(j, j + 4), [r[j + 1], r[j + 2], r[j + 3], r[j]]) for r in rows
            ],
            "another order",
        ),
        (
            # the command logged a row late against the model's velocity
            "px_des_m",
            lambda rows, j: [
                r.__setitem__(slice(j, j + 3), p)
                for r, p in zip(rows[1:], [x[j : j + 3] for x in rows[:-1]], strict=True)
            ],
            "a row late",
        ),
        (
            # one lateral axis flipped (the other two right)
            "vx_des_m_per_s",
            lambda rows, j: [r.__setitem__(j, repr(-float(r[j]))) for r in rows],
            "vx_des_m_per_s does not follow",
        ),
    ],
)
def test_a_broken_log_is_one_line_naming_it(recorded, tmp_path, column, change, words):
    csv = _broken(recorded, tmp_path, column, change)
    with pytest.raises(MeasurementError, match=words) as err:
        read_run6(csv)
    assert "\n" not in str(err.value)


def test_the_json_and_the_set_are_checked(recorded, tmp_path):
    doc = run6_json(recorded)
    bad = dict(doc, format="hybridtable-run6/2")
    with pytest.raises(MeasurementError, match="format"):
        read_run6(_write(tmp_path / "f", recorded, doc=bad))
    bad = json.loads(json.dumps(doc))
    bad["scenario"]["contact"]["contact_stiffness_n_per_m"] = -1.0
    with pytest.raises(MeasurementError, match="contact_stiffness_n_per_m"):
        read_run6(_write(tmp_path / "k", recorded, doc=bad))
    _write(tmp_path / "two", recorded, "run1")
    _write(tmp_path / "two", recorded, "run2")
    with pytest.raises(MeasurementError, match="run_id 'offset' is also"):
        read_runs6([tmp_path / "two"])
    # a record without a contact
    text = run6_csv_text(recorded).splitlines()
    short = "\n".join(text[:8]) + "\n"
    with pytest.raises(MeasurementError, match="no contact"):
        read_run6(_write(tmp_path / "short", recorded, csv=short))


def test_simulate6_records_a_run_that_compare_reads_through_a_rigs_own_log(tmp_path, capsys):
    from hybridtable.cli import main

    scenario = EXAMPLES / "offset.toml"
    folder = tmp_path / "rec"
    argv = ["simulate6", str(scenario), "--compensator", "SDC", "--no-reference"]
    argv += ["--record", str(folder), "--noise-position-m", "1e-5", "--no-progress"]
    assert main([*argv, "--json", str(tmp_path / "s.json")]) == 0
    record = json.loads((tmp_path / "s.json").read_text())["record"]
    assert record["run_id"] == "offset-SDC" and record["ticks"] > 500
    doc = json.loads((folder / "run1.json").read_text())
    assert doc["format"] == "hybridtable-run6/1" and doc["scenario"]["compensator"]["name"] == "SDC"
    capsys.readouterr()
    assert main([*argv]) == 2  # the run is not written over without --force
    assert "--force" in capsys.readouterr().err
    assert main(["compare", str(folder), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["explained"] and result["runs"][0]["cor_error"] == pytest.approx(0.0, abs=1e-12)
    # the same run as a rig logs it: its own names, ';', time in ms, rates in deg/s
    lines = (folder / "run1.csv").read_text().splitlines()
    header = lines[0].split(",")
    own = tmp_path / "own"
    own.mkdir()
    rows = []
    for line in lines[1:]:
        cells = [float(c) for c in line.split(",")]
        for j, name in enumerate(header):
            if name == "time_s":
                cells[j] *= 1e3
            elif name.startswith("w") and name.endswith("_rad_per_s"):
                cells[j] = math.degrees(cells[j])
        rows.append(";".join(repr(c) for c in cells))
    (own / "a.csv").write_text(";".join(f"log_{n}" for n in header) + "\n" + "\n".join(rows))
    (own / "a.json").write_text((folder / "run1.json").read_text())
    mapping = ['delimiter = ";"', "[columns]"]
    for name in header:
        unit = "ms" if name == "time_s" else "deg/s" if name.endswith("_rad_per_s") else None
        mapping.append(
            f'{name} = {{ column = "log_{name}"' + (f', unit = "{unit}"' if unit else "") + " }"
        )
    (tmp_path / "map.toml").write_text("\n".join(mapping) + "\n")
    assert main(["compare", str(own), "--log-map", str(tmp_path / "map.toml"), "--json", "-"]) == 0
    again = json.loads(capsys.readouterr().out)
    sigmas = [[c["error_sigma"] for c in r["runs"][0]["components"]] for r in (again, result)]
    assert sigmas[0] == pytest.approx(sigmas[1], abs=1e-6)
    assert again["log_map"]["columns"]["time_s"] == {
        "column": "log_time_s",
        "unit": "ms",
        "scale": 1.0,
    }
    # without the rates' unit: one line naming the --unit that reads them
    plain = "\n".join(line for line in mapping if "deg/s" not in line)
    plain += "\n" + "\n".join(f'{n} = "log_{n}"' for n in header if n.endswith("_rad_per_s"))
    (tmp_path / "plain.toml").write_text(plain + "\n")
    assert main(["compare", str(own), "--log-map", str(tmp_path / "plain.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert "degrees per second" in err and "wx_des_rad_per_s=deg/s" in err and "\n" not in err


def test_compare_reports_each_component_with_the_fit(tmp_path, capsys):
    from hybridtable.cli import main

    folder = tmp_path / "rec"
    argv = ["simulate6", str(EXAMPLES / "offset.toml"), "--compensator", "SDMDC"]
    argv += ["--record", str(folder), "--no-reference", "--no-progress"]
    argv += [
        "--add",
        "sensor_misalignment:sensor_roll_rad=0.0,sensor_pitch_rad=0.01,sensor_yaw_rad=0.0",
    ]
    assert main(argv) == 0
    truth = json.loads((folder / "truth.json").read_text())
    assert truth["hidden"]["effects"][0]["values"]["sensor_pitch_rad"] == 0.01
    report = tmp_path / "report"
    out = tmp_path / "c.json"
    args = ["compare", str(folder), "--add", "sensor_misalignment", "--report", str(report)]
    assert main([*args, "--json", str(out), "--no-progress"]) == 0
    doc = json.loads(out.read_text())
    assert not doc["explained"] and doc["added"]["explained"]
    pitch = doc["added"]["fit"]["values"]["sensor_misalignment"]["sensor_pitch_rad"]
    assert pitch == pytest.approx(0.01, abs=1e-6)  # no F/T noise in offset.toml
    names = sorted(p.name for p in report.iterdir())
    assert names == ["00_offset-SDMDC_components.png", "00_offset-SDMDC_residuals.png", "report.md"]
    md = (report / "report.md").read_text()
    assert "| fx_mea |" in md and "with the fit" in md and "mrad" in md
    capsys.readouterr()
    assert main([*args, "--no-progress"]) == 2  # the report is not written over without --force
    assert "--force" in capsys.readouterr().err


def test_an_on_axis_run_is_the_1d_run_it_projects_to(tmp_path, capsys):
    """On axis the 6-DoF loop is the 1-D loop: the 1-D replay of the projected
    run (p = pz, f = -fz, the table's start from the scenario) gives its
    readings and table to round-off; off axis the projection is refused."""
    from hybridtable.cli import main
    from hybridtable.measurement.replay import replay
    from hybridtable.six_dof.axial import axial_run
    from hybridtable.six_dof.scenario import load_scenario

    scenario = EXAMPLES / "on_axis.toml"
    params = load_scenario(scenario, compensator="none")
    from hybridtable.loop.scenario import read_scenario

    raw = read_scenario(scenario)
    raw["compensator"]["name"] = "none"
    run = axial_run(run6_of_docking(simulate6(params), "axis", raw))
    rep = replay(run)
    peak = np.max(np.abs(run.f_mea_n))
    assert np.max(np.abs(rep.f_mea_n - run.f_mea_n)) < 1e-6 * peak
    assert np.max(np.abs(rep.p_act_m - run.p_act_m)) < 1e-9
    # through the CLI: the 1-D compare reads the 6-DoF files with --axial
    folder = tmp_path / "axis"
    folder.mkdir()
    noise = {"force_noise_n": 2.0, "moment_noise_n_m": 0.5, "position_noise_m": 2e-6}
    raw["rig"].update(noise)
    raw["compensator"]["force_deadband_n"] = 12.0
    noisy = params.with_(force_deadband_n=12.0, **noise)
    six = run6_of_docking(simulate6(noisy), "axis", raw)
    (folder / "run1.csv").write_text(run6_csv_text(six))
    (folder / "run1.json").write_text(json.dumps(run6_json(six)))
    assert main(["compare", str(folder), "--axial", "--json", "-", "--no-progress"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # the 1-D CoR of the projection is the 6-DoF normal CoR; its model's is near
    cor6 = six.metrics().cor_normal
    assert doc["runs"][0]["cor_measured"] == pytest.approx(cor6, rel=1e-9)
    assert doc["runs"][0]["cor_model"] == pytest.approx(cor6, abs=0.01)
    assert doc["verdict"].startswith("The model matches"), doc["verdict"]
    # the 6-DoF compare of the same files: the same errors in the same noise levels
    assert main(["compare", str(folder), "--json", "-", "--no-progress"]) == 0
    errors6 = {c["name"]: c for c in json.loads(capsys.readouterr().out)["runs"][0]["components"]}
    one = doc["runs"][0]
    for name6, name1 in (("fz_mea", "f_mea_n"), ("pz_act", "p_act_m")):
        assert errors6[name6]["rms_error"] == pytest.approx(one["rms_error"][name1], rel=1e-6)
        assert errors6[name6]["noise"] == pytest.approx(one["noise_rms"][name1], rel=1e-6)
    off = tmp_path / "off"
    off.mkdir()
    _write(off, run6_of_docking(simulate6(docking_params(offset_m=0.01)), "off", SCENARIO))
    assert main(["compare", str(off), "--axial", "--no-progress"]) == 2
    assert "not on the docking axis (lateral_offset_m, misalignment_deg)" in capsys.readouterr().err


def test_a_6dof_only_effect_is_refused_by_the_1d_commands(tmp_path, capsys):
    from hybridtable.cli import main

    table = tmp_path / "t.csv"
    table.write_text("compensator,sensor_delay_s,cor\nnone,0.005,1.16\nSDC,0.005,1.0\n")
    assert main(["explain", str(table), "--effects", "friction_across_face", "--no-progress"]) == 2
    assert "six-axis rig only" in capsys.readouterr().err
    runs = Path(__file__).resolve().parents[2] / "examples" / "nominal"
    assert main(["compare", str(runs), "--add", "sensor_misalignment", "--no-progress"]) == 2
    assert "six-axis rig only" in capsys.readouterr().err


def test_a_record_writes_its_truth_and_the_scenarios_inf_as_json_can(tmp_path):
    from hybridtable.cli import main

    scenario = tmp_path / "ideal.toml"
    text = (
        (EXAMPLES / "on_axis.toml").read_text().replace("response_hz = 25.0", 'response_hz = "inf"')
    )
    text = text.replace('response_hz = "inf"', "response_hz = inf")
    # the scenario's encoder noise is kept without the flags (they only replace it)
    scenario.write_text(text.replace("[rig]\n", "[rig]\nposition_noise_m = 3e-6\n"))
    folder = tmp_path / "rec"
    argv = ["simulate6", str(scenario), "--record", str(folder), "--no-reference", "--no-progress"]
    assert main([*argv, "--json", str(tmp_path / "s.json")]) == 0
    assert json.loads((tmp_path / "s.json").read_text())["record"]["position_noise_m"] == 3e-6
    doc = json.loads((folder / "run1.json").read_text())  # strict JSON: no Infinity
    assert doc["scenario"]["table"]["response_hz"] == "inf"
    assert doc["scenario"]["rig"]["position_noise_m"] == 3e-6
    truth = json.loads((folder / "truth.json").read_text())
    assert truth["hidden"]["effects"] == []  # written without --add too: never stale
    assert read_run6(folder / "run1.csv").params.table_response_hz == float("inf")


def test_an_ft_bias_far_above_the_noise_is_read_as_a_bias_not_a_contact(tmp_path):
    """An F/T sensor's offset (here 40 N, 20 noise levels) is its level at
    rest: the record is read, its contact starts where the unbiased one's
    does, and a fit of ``force_bias`` finds it."""
    from hybridtable.effects.registry import get_effect
    from hybridtable.six_dof.compare6 import phases
    from hybridtable.six_dof.fit6 import fit_runs6
    from hybridtable.six_dof.physics6 import physics_with, rig_scale

    noise = {"force_noise_n": 2.0, "moment_noise_n_m": 0.5, "duration_s": 0.8}  # no dead band
    scenario = {**SCENARIO, "rig": {**SCENARIO["rig"], **noise}}
    params = scenario_params(**noise)
    bias = get_effect("force_bias")
    hidden = physics_with([(bias, {"bias_n": 40.0})], rig_scale(params))
    plain = read_run6(_write(tmp_path / "plain", run6_of_docking(simulate6(params), "p", scenario)))
    biased = run6_of_docking(simulate6(params, physics=hidden), "b", scenario)
    run = read_run6(_write(tmp_path / "biased", biased))
    assert phases(run)[1][0] == pytest.approx(phases(plain)[1][0], abs=3e-3)  # s
    fit = fit_runs6([run], [(bias, {})])
    found, std = fit.values["force_bias"]["bias_n"], fit.std["force_bias"]["bias_n"]
    assert abs(found - 40.0) < 4.0 * std


def test_a_record_cut_after_the_touch_starts_in_contact_by_its_pose(recorded, tmp_path):
    text = run6_csv_text(recorded).splitlines()
    touch = int(np.argmax(np.linalg.norm(recorded.blocks["f_mea"], axis=1) > 1.0))
    first = touch - recorded.params.delay_ticks + 2  # the pose already pressed, the reading not yet
    cut = [text[0]] + text[1 + first :]
    t0 = float(cut[1].split(",")[0])
    rows = [",".join([repr(float(r.split(",")[0]) - t0), *r.split(",")[1:]]) for r in cut[1:]]
    with pytest.raises(MeasurementError, match="starts in contact .the measured pose"):
        read_run6(_write(tmp_path, recorded, csv="\n".join([cut[0], *rows]) + "\n"))
