"""``hybridtable compensators --model``: every compensator on the rig a model
file describes, ranked against the model's contact on an ideal rig; the
model file's errors and the options that mean nothing there."""

from __future__ import annotations

import json

import pytest

from hybridtable.cli import main
from tests.commands.test_margins_model import PLUGIN
from tests.studies.test_model_compensators import (
    DAMPING,
    damped_oscillator_cor,
    write_damped_model,
)


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return write_damped_model(tmp_path_factory.mktemp("rig"))


def test_the_ranking_against_the_damped_contact(model, tmp_path, capsys):
    out, report = tmp_path / "c.json", tmp_path / "report"
    args = ["compensators", "--model", str(model), "--compensators", "none,SDMDC,smith"]
    args += ["--jobs", "1", "--no-progress", "--report", str(report), "--json", str(out)]
    assert main(args) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("On the modelled rig ") and "comes closest: CoR" in lines[0]
    assert "; no compensation gives 1.0" in lines[0]
    doc = json.loads(out.read_text())
    assert doc["verdict"] == lines[0]
    assert doc["model"]["path"] == str(model)
    assert "contact_damping" in doc["model"]["description"]
    assert len(doc["runs"]) == 6 and all(r["error"] == "" for r in doc["runs"])
    ranking = {e["key"]: e for e in doc["ranking"]}
    assert set(ranking) == {
        f"{c}{g}" for c in ("none", "SDMDC", "smith") for g in ("", " +passivity")
    }
    (point,) = doc["points"]
    assert point["cor_reference"] == pytest.approx(damped_oscillator_cor(DAMPING), abs=0.01)
    assert abs(ranking["SDMDC"]["cor_error"]) < abs(ranking["none"]["cor_error"])
    # The passivity guard stops no compensation from creating energy.
    assert ranking["none"]["max_energy_created"] > 0.1
    assert ranking["none +passivity"]["max_energy_created"] < 1e-3
    assert doc["ranking"][-1]["key"] == "none"
    assert (report / "report.md").is_file() and (report / "model_cor.png").is_file()


def test_model_errors_and_options_that_do_not_apply(model, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "hybridtable-model/2"}')
    assert main(["compensators", "--model", str(bad), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "not supported" in err and "\n" not in err
    doc = json.loads(model.read_text())
    doc["effects"][0]["name"] = "lab_damping"
    doc["effects"][0]["parameters"] = {"c_n_s_per_m": {"value": DAMPING}}
    user = tmp_path / "user.json"
    user.write_text(json.dumps(doc))
    assert main(["compensators", "--model", str(user), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "'lab_damping' is not registered" in err and "--plugin" in err and "\n" not in err
    for extra in (["--quick"], ["--prior-ratios", "1"], ["--sample-rate-hz", "500"]):
        assert main(["compensators", "--model", str(model), "--no-progress", *extra]) == 2
        assert "not with --model" in capsys.readouterr().err
    plugin = tmp_path / "lab.py"
    plugin.write_text(PLUGIN)
    from hybridtable.effects.registry import unregister_effect

    try:
        args = ["compensators", "--model", str(user), "--plugin", f"{plugin}:EFFECT"]
        args += ["--compensators", "SDMDC", "--no-passivity", "--no-progress", "--json", "-"]
        assert main(args) == 0
    finally:
        unregister_effect("lab_damping")
    doc = json.loads(capsys.readouterr().out)
    assert "lab_damping" in doc["model"]["description"]
    (point,) = doc["points"]
    assert point["cor_reference"] == pytest.approx(damped_oscillator_cor(DAMPING), abs=0.01)
