"""The diagnosed model goes everywhere: record runs with a hidden effect,
diagnose them into a model file, and carry the file into simulate, compare
(and margins); a bad model file gets one line and exit code 2."""

from __future__ import annotations

import json
import math

import pytest

from hybridtable.cli import main

RIG = [
    "--sensor-delay-s",
    "0.004",
    "--table-response-hz",
    "30",
    "--table-damping-ratio",
    "0.7",
    "--contact-stiffness-n-per-m",
    "6e4",
    "--contact-frequency-hz",
    "1.5",
    "--initial-gap-m",
    "0.002",
]
HIDDEN_DAMPING = 300.0


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """Three runs with hidden contact damping, a held-out fourth, and the
    model diagnose saved from the three."""
    root = tmp_path_factory.mktemp("rig")
    hidden = f"contact_damping:damping_n_s_per_m={HIDDEN_DAMPING}"
    runs, held = root / "runs", root / "held_out"
    assert (
        main(
            ["simulate", "--record", str(runs), "--add", hidden, "--runs", "3"]
            + ["--velocities", "0.06,0.08,0.1", "--compensator", "none,SDMDC,SDC", "--seed", "1"]
            + RIG
            + ["--json", str(root / "record.json")]
        )
        == 0
    )
    assert (
        main(
            ["simulate", "--record", str(held), "--add", hidden, "--velocities", "0.09"]
            + ["--compensator", "MDC", "--seed", "7"]
            + RIG
        )
        == 0
    )
    model = root / "model.json"
    diagnosis = root / "diagnosis.json"
    assert (
        main(
            ["diagnose", str(runs), "--save-model", str(model), "--json", str(diagnosis)]
            + ["--no-progress"]
        )
        == 0
    )
    return {
        "root": root,
        "runs": runs,
        "held": held,
        "model": model,
        "truth": json.loads((runs / "truth.json").read_text()),
        "diagnosis": json.loads(diagnosis.read_text()),
    }


def test_the_recording_hides_the_effect_from_the_json(rig):
    truth = rig["truth"]
    assert truth["format"] == "hybridtable-truth/1"
    (effect,) = truth["hidden"]["effects"]
    assert effect["name"] == "contact_damping"
    assert effect["parameters"]["damping_n_s_per_m"]["value"] == HIDDEN_DAMPING
    run_json = json.loads((rig["runs"] / "run1.json").read_text())
    assert "contact_damping" not in json.dumps(run_json) and "300" not in json.dumps(run_json)
    assert set(run_json) == set(truth["nominal"])
    assert run_json["force_deadband_n"] == pytest.approx(5.0 * truth["noise"]["force_std_n"])
    assert [r["compensator"] for r in truth["runs"]] == ["none", "SDMDC", "SDC"]


def test_the_model_file_holds_what_diagnose_found(rig):
    doc = json.loads(rig["model"].read_text())
    assert doc["format"] == "hybridtable-model/1"
    assert doc["source"] == "diagnose"
    assert doc["tool_version"]
    (effect,) = doc["effects"]
    p = effect["parameters"]["damping_n_s_per_m"]
    assert effect["name"] == "contact_damping" and p["fitted"] and p["unit"] == "N s/m"
    # The fitted value is within a few of its standard errors of the truth.
    assert 0.0 < p["std"] < 0.05 * HIDDEN_DAMPING
    assert abs(p["value"] - HIDDEN_DAMPING) < 4.0 * p["std"] + 1.0
    assert [r["run_id"] for r in doc["runs"]] == ["runs-run1", "runs-run2", "runs-run3"]
    assert all(len(r["sha256"]) == 64 for r in doc["runs"])
    assert doc["nominal"]["contact_stiffness_n_per_m"] == 6e4
    assert doc["evidence"]["verdict"] == rig["diagnosis"]["verdict"] == "contact_damping"


def test_simulate_with_the_model_reproduces_each_runs_cor(rig):
    out = rig["root"] / "simulate.json"
    assert main(["simulate", "--model", str(rig["model"]), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert len(doc["runs"]) == 3
    measured = {r["run_id"]: r["cor"] for r in rig["truth"]["runs"]}
    for r in doc["runs"]:
        assert abs(r["cor"] - r["cor_measured"]) <= 0.005
        assert r["cor_measured"] == pytest.approx(measured[r["run_id"]], abs=1e-12)
        # The nominal model misses by the damping's loss, about ten times more.
        assert abs(r["cor_error_nominal"]) > 0.05
    assert doc["max_abs_cor_error"] <= 0.005


def test_simulate_with_the_model_at_new_conditions(rig, capsys):
    args = ["simulate", "--model", str(rig["model"]), "--initial-velocity-m-per-s", "0.05"]
    assert main(args + ["--compensator", "MDC", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    (r,) = doc["runs"]
    assert r["compensator"] == "MDC" and r["initial_velocity_m_per_s"] == 0.05
    # Damping lowers the CoR against the nominal rig's by about its own loss.
    zeta = HIDDEN_DAMPING / (2.0 * math.sqrt(6e4 * 6e4 / (2 * math.pi * 1.5) ** 2))
    loss = math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    assert r["cor"] / r["cor_nominal"] == pytest.approx(loss, abs=0.01)


def test_compare_with_the_model_on_a_held_out_run(rig):
    out = rig["root"] / "compare.json"
    assert (
        main(["compare", str(rig["held"]), "--model", str(rig["model"]), "--json", str(out)]) == 0
    )
    doc = json.loads(out.read_text())
    (run,) = doc["runs"]
    (nominal,) = doc["nominal_runs"]
    for channel in ("f_mea_n", "p_act_m"):
        assert run["error_to_noise"][channel] <= 1.1
    assert nominal["error_to_noise"]["f_mea_n"] > 3.0
    assert doc["model"]["effects"][0]["name"] == "contact_damping"


def test_compare_saves_a_model_of_several_added_effects(rig, tmp_path):
    out, model = tmp_path / "c.json", tmp_path / "m.json"
    args = ["compare", str(rig["runs"]), "--no-progress", "--json", str(out)]
    args += ["--add", "contact_damping", "--add", "force_bias:bias_n=0", "--save-model", str(model)]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    names = [a["effect"] for a in doc["added_effects"]]
    assert names == ["contact_damping", "force_bias"]
    damping, bias = doc["added_effects"]
    assert damping["fitted"] == ["damping_n_s_per_m"] and bias["fitted"] == []
    assert damping["parameters"]["damping_n_s_per_m"] == pytest.approx(HIDDEN_DAMPING, rel=0.03)
    saved = json.loads(model.read_text())
    assert [e["name"] for e in saved["effects"]] == names
    assert saved["source"] == "compare --add"
    # The model file is not replaced without --force.
    assert main(args) == 2
    assert main([*args, "--force"]) == 0


@pytest.mark.parametrize(
    "text, words",
    [
        ("{not json", "not valid JSON"),
        ('{"format": "hybridtable-model/2"}', "not supported"),
        ('{"format": "hybridtable-run/1"}', "not a model file"),
        ("[]", "not a model file"),
    ],
)
def test_a_bad_model_file_gets_one_line_and_exit_2(tmp_path, capsys, text, words):
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    for command in (["simulate"], ["compare", str(tmp_path)]):
        assert main([*command, "--model", str(bad)]) == 2
        err = capsys.readouterr().err.strip()
        assert words in err and "\n" not in err


def test_a_model_naming_an_unregistered_effect_is_refused(rig, tmp_path, capsys):
    doc = json.loads(rig["model"].read_text())
    doc["effects"][0]["name"] = "backlash"
    bad = tmp_path / "m.json"
    bad.write_text(json.dumps(doc))
    assert main(["simulate", "--model", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "'backlash' is not registered" in err and "--plugin" in err
    doc = json.loads(rig["model"].read_text())
    doc["effects"][0]["parameters"]["damping_n_s_per_m"]["value"] = -5.0
    bad.write_text(json.dumps(doc))
    assert main(["simulate", "--model", str(bad)]) == 2
    assert "out of bounds" in capsys.readouterr().err


def test_repeated_add_in_simulate_and_its_errors(capsys):
    args = ["simulate", "--sample-rate-hz", "1000", "--json", "-"]
    assert main(args) == 0
    base = json.loads(capsys.readouterr().out)["cor"]
    both = args + ["--add", "contact_damping:damping_n_s_per_m=800"]
    both += ["--add", "extra_delay:extra_delay_s=0.002"]
    assert main(both) == 0
    cor = json.loads(capsys.readouterr().out)["cor"]
    assert main(args[:-2] + ["--add", "contact_damping:damping_n_s_per_m=800", "--json", "-"]) == 0
    damped = json.loads(capsys.readouterr().out)["cor"]
    # Both effects act: the damping lowers the CoR, the extra delay raises it.
    assert damped < base and cor > damped
    for extra, words in [
        (["--add", "contact_damping"], "give damping_n_s_per_m=..."),
        (["--add", "contact_damping:damping_n_s_per_m=1", "--add", "contact_damping"], "twice"),
        (["--add", "hunt_crossley:damping_factor_s_per_m=1", "--add", "no_such"], "unknown effect"),
    ]:
        assert main(["simulate", *extra]) == 2
        assert words in capsys.readouterr().err


def test_margins_with_the_model_shows_the_damping(rig, capsys):
    args = ["margins", "--model", str(rig["model"]), "--sensor-delay-s", "0.004"]
    assert main([*args, "--table-response-hz", "30", "--json", "-", "--no-progress"]) == 0
    doc = json.loads(capsys.readouterr().out)
    point = doc["operating_point"]
    zeta = HIDDEN_DAMPING / (2.0 * math.sqrt(6e4 * 6e4 / (2 * math.pi * 1.5) ** 2))
    loss = math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    assert set(point) == {"none", "SDC", "MDC", "SDMDC"}
    for c, p in point.items():
        # The damping lowers every compensator's predicted CoR by its loss.
        assert p["cor_model"] < p["cor_nominal"], c
        assert p["cor_model"] / p["cor_nominal"] == pytest.approx(loss, abs=0.003), c
