"""A six-axis rig's model file (``hybridtable-model6/1``, six_dof/model6.py):
``compare --add`` or ``diagnose`` on 6-DoF runs writes it (``--save-model``),
``compare --model`` holds it against other runs of the rig, ``simulate6
--model`` runs it under a scenario; bad files are one line and exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.six_dof.model6 import load_model6

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "six_dof"

HIDDEN = {
    "sensor_misalignment": {
        "sensor_roll_rad": 0.01,
        "sensor_pitch_rad": -0.02,
        "sensor_yaw_rad": 0.0,
    },
    "friction_across_face": {"extra_friction_coefficient": 0.2},
}

#: Whole commands, several fits: make test runs them, make check does not.
pytestmark = pytest.mark.slow


def _record(folder: Path, compensator: str, *extra: str) -> None:
    argv = ["simulate6", str(EXAMPLES / "offset_noisy.toml"), "--compensator", compensator]
    argv += ["--record", str(folder), "--no-reference", "--no-progress", *extra]
    for name, values in HIDDEN.items():
        argv += ["--add", f"{name}:" + ",".join(f"{k}={v}" for k, v in values.items())]
    assert main(argv) == 0


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """Two runs of one rig (SDMDC and SDC) with a turned sensor and friction
    across the face hidden, and the model ``compare --add`` fitted to the first."""
    root = tmp_path_factory.mktemp("model6")
    _record(root / "a", "SDMDC")
    _record(root / "b", "SDC")
    model = root / "model.json"
    argv = ["compare", str(root / "a"), "--no-progress", "--save-model", str(model)]
    argv += ["--add", "sensor_misalignment", "--add", "friction_across_face"]
    argv += ["--json", str(root / "a.json")]
    assert main(argv) == 0
    return root, model


def test_the_saved_model_holds_the_fitted_values_and_reads_back(rig, capsys):
    root, path = rig
    model = load_model6(path)
    assert model.effect_names == ("sensor_misalignment", "friction_across_face")
    for name, values in HIDDEN.items():
        found = next(e for e in model.effects if e.name == name)
        for k, v in values.items():
            assert abs(found.values[k] - v) < 4.0 * found.std[k] + 1e-9, (k, found.std[k])
        assert set(found.fitted) == set(found.values)
    doc = json.loads(path.read_text())
    assert doc["format"] == "hybridtable-model6/1" and doc["source"] == "compare"
    assert doc["evidence"]["explained"] and doc["runs"][0]["sha256"]
    physics = model.physics()
    assert physics.sensor_gain is not None and physics.offsets["friction_coefficient"] == (
        pytest.approx(0.2, abs=1e-3)
    )


def test_the_model_explains_another_run_of_the_rig(rig, capsys):
    root, model = rig
    capsys.readouterr()
    assert main(["compare", str(root / "b"), "--model", str(model), "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert not doc["explained"]  # the scenario's own model misses the other run
    assert doc["model"]["explained"] and doc["model"]["other_rig"] == []
    worst = max(c["error_sigma"] for c in doc["model"]["runs"][0]["components"])
    assert worst < 3.0
    report = root / "report"
    argv = ["compare", str(root / "b"), "--model", str(model), "--report", str(report)]
    assert main([*argv, "--no-progress"]) == 0
    text = (report / "report.md").read_text()
    assert f"the model {model}: sensor_misalignment" in text and "explains the run" in text
    # an effect the model has is not added again, and the model is not written over
    argv = ["compare", str(root / "b"), "--model", str(model)]
    assert main([*argv, "--add", "friction_across_face"]) == 2
    assert "has it already" in capsys.readouterr().err
    assert main([*argv, "--save-model", str(model)]) == 2
    assert "input" in capsys.readouterr().err


def test_simulate6_runs_the_model_under_a_scenario(rig, tmp_path, capsys):
    root, model = rig
    out = tmp_path / "s.json"
    argv = ["simulate6", str(EXAMPLES / "offset_noisy.toml"), "--compensator", "SDC"]
    argv += ["--no-reference", "--no-progress", "--model", str(model), "--json", str(out)]
    assert main(argv) == 0
    hidden = json.loads(out.read_text())["hidden"]
    assert [e["name"] for e in hidden["effects"]] == list(HIDDEN)
    assert hidden["physics"]["offsets"]["friction_coefficient"] == pytest.approx(0.2, abs=1e-3)
    # the recorded run of the model is the other run's rig: the model explains it
    folder = tmp_path / "rec"
    assert main([*argv[:-2], "--record", str(folder)]) == 0
    capsys.readouterr()
    assert main(["compare", str(folder), "--model", str(model), "--json", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["model"]["explained"]


def test_diagnose_saves_the_audits_centre_of_mass_as_an_effect(tmp_path, capsys):
    folder = tmp_path / "com"
    argv = ["simulate6", str(EXAMPLES / "offset_noisy.toml"), "--compensator", "SDMDC"]
    argv += ["--record", str(folder), "--no-reference", "--no-progress"]
    assert main([*argv, "--add", "com_offset:com_x_m=0.05,com_y_m=-0.02,com_z_m=-0.1"]) == 0
    path = tmp_path / "m.json"
    assert main(["diagnose", str(folder), "--save-model", str(path), "--no-progress"]) == 0
    model = load_model6(path)
    com = next(e for e in model.effects if e.name == "com_offset")
    assert com.values == pytest.approx({"com_x_m": 0.05, "com_y_m": -0.02, "com_z_m": -0.1})
    assert model.physics().com_offset_m == pytest.approx((0.05, -0.02, -0.1))
    assert json.loads(path.read_text())["source"] == "diagnose"


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda d: d.update(format="hybridtable-model/1"), "a model of a 1-D rig"),
        (lambda d: d.update(format="other"), "not a 6-DoF model file"),
        (lambda d: d.pop("scenario"), "missing key scenario"),
        (lambda d: d["effects"][0].update(name="series_compliance"), "series_compliance"),
        (
            lambda d: d["effects"][1]["parameters"]["extra_friction_coefficient"].update(value=9),
            "out of bounds",
        ),
        (lambda d: d["scenario"]["rig"].update(sample_rate_hz=-1), "sample_rate_hz"),
    ],
)
def test_a_bad_model_file_is_one_line(rig, tmp_path, capsys, change, words):
    root, model = rig
    doc = json.loads(model.read_text())
    change(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["compare", str(root / "b"), "--model", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


def test_a_6dof_model_is_refused_by_name_on_1d_runs(rig, capsys):
    _, model = rig
    nominal = Path(__file__).resolve().parents[2] / "examples" / "nominal"
    assert main(["compare", str(nominal), "--model", str(model)]) == 2
    assert "a model of a six-axis rig" in capsys.readouterr().err
