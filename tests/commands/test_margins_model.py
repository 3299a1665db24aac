"""``hybridtable margins --model``: the margins of the rig a model file
describes, its operating point against the nominal model and against a
simulation of the whole model, and the model file's errors."""

from __future__ import annotations

import json
import math

import pytest

from hybridtable.analysis.validation import EXPLAIN_ABOVE
from hybridtable.cli import main
from tests.studies.test_model_compensators import (
    DAMPING,
    RIG,
    damped_oscillator_cor,
    write_damped_model,
)

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")

#: A user's effect (``--plugin FILE.py:EFFECT``): viscous contact damping
#: under another name.
PLUGIN = """
from hybridtable.effects.effect import Effect, EffectParameter, Signature

EFFECT = Effect(
    name="lab_damping",
    description="the lab's contact damping",
    parameters=(EffectParameter("c_n_s_per_m", "N s/m", "c", 0.0, 1e4, 10.0, null=0.0),),
    signature=Signature(("f_mea_n",), ("compression",), "damping"),
    apply=lambda spec, v, s: spec.with_contact(damping_n_s_per_m=v["c_n_s_per_m"]),
)
"""


@pytest.fixture(scope="module")
def margins(tmp_path_factory):
    """``margins --model`` of a rig with 300 N s/m of contact damping, on a
    small grid around its operating point."""
    root = tmp_path_factory.mktemp("margins")
    model = write_damped_model(root / "rig")
    out = root / "margins.json"
    args = ["margins", "--model", str(model), "--sensor-delay-s", "0.002,0.004"]
    args += ["--table-response-hz", "30,60", "--no-progress", "--json", str(out)]
    return {"model": model, "args": args, "out": out}


def test_the_damping_lowers_every_predicted_cor_as_a_damped_oscillator(margins, capsys):
    assert main(margins["args"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("The model lowers the predicted CoR of every compensator")
    assert "stable with" in lines[0]
    doc = json.loads(margins["out"].read_text())
    assert doc["model"]["path"] == str(margins["model"])
    assert "contact_damping" in doc["model"]["description"]
    assert doc["model"]["kind"] == "sampled" and doc["model"]["sample_rate_hz"] == 1000.0
    assert doc["model"]["left_out"] == []
    point = doc["operating_point"]
    assert set(point) == set(COMPENSATORS)
    loss = damped_oscillator_cor(DAMPING)
    for c in COMPENSATORS:
        p = point[c]
        assert p["cor_model"] < p["cor_nominal"]
        # The linear change: the damped oscillator's loss, whatever the compensator.
        assert p["cor_model"] / p["cor_nominal"] == pytest.approx(loss, abs=0.003)
        # The simulated model: the change of CoR the linear models predict,
        # within the margins' validation tolerance.
        linear_change = p["cor_model"] - p["cor_nominal"]
        simulated_change = p["cor_model_simulated"] - p["cor_nominal_simulated"]
        assert abs(linear_change - simulated_change) <= EXPLAIN_ABOVE, c
        shown = f"  {c}: nominal {p['cor_nominal']:.4f} -> model {p['cor_model']:.4f}"
        assert any(line.startswith(shown) for line in lines)
    # Without the rig computer's gating (none, SDC: nothing waits for the
    # measured force) the simulated CoR itself is the linear one.
    for c in ("none", "SDC"):
        assert abs(point[c]["cor_model_simulated"] - point[c]["cor_model"]) <= EXPLAIN_ABOVE
    # MDC and SDMDC wait for the delayed force above the 6 N dead band: a
    # difference the validation finds in the nominal rig too, and names.
    for c in ("MDC", "SDMDC"):
        sim = point[c]["model_simulation"]
        if sim["abs_error"] > EXPLAIN_ABOVE:
            assert sim["cause"] == "gating and separation"
    assert point["SDMDC"]["cor_nominal"] == pytest.approx(1.0, abs=0.001)
    shown = "linear loop: contact_damping_n_s_per_m 0 -> 300; left out: nothing"
    assert any(line.startswith(shown) for line in lines)
    assert doc["model"]["linear_changes"] == {"contact_damping_n_s_per_m": [0.0, DAMPING]}
    # The grid is the model's: contact damping in the loop at every point.
    cor = doc["compensators"]["SDMDC"]["predicted_cor"]
    assert cor[1][0] == pytest.approx(point["SDMDC"]["cor_model"], rel=1e-12)
    assert doc["grid"]["sensor_delay_s"] == [0.002, 0.004]


def test_options_given_override_the_models_rig(margins, capsys):
    args = margins["args"][:-2] + ["--compensator", "SDMDC", "--json", "-"]
    args += ["--table-damping-ratio", "0.8", "--initial-velocity-m-per-s", "0.05"]
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["model"]["table_damping_ratio"] == 0.8
    assert doc["model"]["operating_point_initial_velocity_m_per_s"] == 0.05
    assert doc["model"]["spacecraft_mass_kg"] == RIG["spacecraft_mass_kg"]
    assert doc["model"]["lead_time_s"] == RIG["lead_time_s"]
    assert list(doc["operating_point"]) == ["SDMDC"]


def test_a_bad_or_unregistered_model_gets_one_line_and_exit_2(margins, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["margins", "--model", str(bad), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "not valid JSON" in err and "\n" not in err
    doc = json.loads(margins["model"].read_text())
    doc["effects"][0]["name"] = "lab_damping"
    doc["effects"][0]["parameters"] = {"c_n_s_per_m": {"value": DAMPING}}
    user = tmp_path / "user.json"
    user.write_text(json.dumps(doc))
    assert main(["margins", "--model", str(user), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "'lab_damping' is not registered" in err and "--plugin" in err and "\n" not in err
    # With the user's effect loaded, the model is the damped one under another name.
    plugin = tmp_path / "lab.py"
    plugin.write_text(PLUGIN)
    from hybridtable.effects.registry import unregister_effect

    try:
        args = ["margins", "--model", str(user), "--plugin", f"{plugin}:EFFECT"]
        args += ["--sensor-delay-s", "0.004", "--table-response-hz", "30"]
        assert main([*args, "--compensator", "SDMDC", "--no-progress", "--json", "-"]) == 0
    finally:
        unregister_effect("lab_damping")
    point = json.loads(capsys.readouterr().out)["operating_point"]["SDMDC"]
    assert point["cor_model"] / point["cor_nominal"] == pytest.approx(
        damped_oscillator_cor(), abs=0.003
    )
    assert math.isfinite(point["cor_model_simulated"])
