"""The audit of a six-axis rig computer's spacecraft (six_dof/audit6.py), and
the two effects it and the sensor's cross-talk add: ``com_offset`` solved to
round-off from the record, nothing found on the scenario's own computer (also
from a log written at six significant digits), a mass the JSON misstates, an
inertia that an on-axis run cannot tell; ``sensor_crosstalk`` found by
diagnose with its values."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from hybridtable.effects.registry import get_effect
from hybridtable.six_dof.audit6 import audit_runs6, audit_spacecraft6
from hybridtable.six_dof.diagnose6 import diagnose_runs6
from hybridtable.six_dof.physics6 import NOMINAL_PHYSICS, physics_with, rig_scale
from hybridtable.six_dof.run6 import run6_csv_text, run6_json, run6_of_docking
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.test_diagnose6 import NOISY

COM = {"com_x_m": 0.05, "com_y_m": -0.02, "com_z_m": -0.1}


def _run(hidden: dict, run_id: str, scenario: dict = NOISY):
    params = parse_scenario(scenario)
    physics = physics_with([(get_effect(n), v) for n, v in hidden.items()], rig_scale(params))
    return run6_of_docking(simulate6(params, physics=physics), run_id, scenario)


@pytest.fixture(scope="module")
def null_run():
    return _run({}, "null")


@pytest.fixture(scope="module")
def com_run():
    return _run({"com_offset": COM}, "com")


def test_the_scenarios_own_computer_has_no_finding(null_run):
    audit = audit_spacecraft6([null_run])
    assert audit.findings == [] and audit.ticks > 100
    assert audit.relative_residual < 1e-10
    body = null_run.params.spacecraft
    assert audit.mass_kg == pytest.approx(body.mass_kg, rel=1e-10)
    np.testing.assert_allclose(audit.port_position_m, body.port_position_m, atol=1e-10)


def test_an_offset_centre_of_mass_is_solved_to_round_off(com_run):
    audit = audit_runs6([com_run])
    assert audit.effects == ["com_offset"]
    found = audit.findings[0]
    for name, value in COM.items():
        assert found.values[name] == pytest.approx(value, abs=1e-9)
        assert found.std[name] < 1e-9
    # the hidden offset moved the commands: the replay of the physical part is unchanged
    d = diagnose_runs6([com_run], workers=1)
    assert d.verdict == "found" and d.found == ["com_offset"] and d.selected == []
    assert d.sentence().startswith("found the rig computer's spacecraft: com_offset")
    assert "com_offset" not in d.candidates  # an effect of the computer is not fitted
    assert json.loads(json.dumps(d.to_dict()))["audit"]["findings"][0]["effect"] == "com_offset"


def test_a_log_at_six_digits_is_not_a_finding_but_the_offset_still_is(null_run, com_run):
    def rounded(run):
        blocks = {k: np.array([[float(f"{x:.6g}") for x in row] for row in v])
                  for k, v in run.blocks.items()}  # fmt: skip
        return replace(run, blocks=blocks)

    assert audit_runs6([rounded(null_run)]).findings == []
    audit = audit_runs6([rounded(com_run)])
    assert audit.effects == ["com_offset"]
    assert audit.findings[0].values["com_x_m"] == pytest.approx(0.05, rel=1e-3)


def test_a_mass_the_json_misstates_is_a_mass_error(null_run):
    params = null_run.params
    wrong = replace(
        null_run, params=params.with_(spacecraft_mass_kg=params.spacecraft.mass_kg * 1.01)
    )
    audit = audit_runs6([wrong])
    assert audit.effects == ["mass_error"]
    assert audit.findings[0].values["mass_ratio"] == pytest.approx(1 / 1.01, rel=1e-9)
    # with a run whose JSON is right: each spacecraft the JSONs state is solved apart
    both = audit_runs6([null_run, replace(wrong, run_id="wrong")])
    assert [g.run_ids for g in both.groups] == [["null"], ["wrong"]]
    assert both.effects == ["mass_error"]
    assert both.to_dict()["findings"][0]["runs"] == ["wrong"]


def test_a_computer_that_steps_otherwise_is_a_model_error(null_run):
    v = null_run.blocks["v_des"].copy()
    v[1:] = v[:-1] + 0.5 * (v[1:] - v[:-1])  # half of every velocity change
    audit = audit_runs6([replace(null_run, blocks={**null_run.blocks, "v_des": v})])
    assert audit.effects == ["spacecraft_model_error"]


def test_an_on_axis_run_cannot_tell_the_inertia():
    on_axis = {
        **NOISY,
        "spacecraft": {**NOISY["spacecraft"], "lateral_offset_m": [0.0, 0.0]},
        "approach": {**NOISY["approach"], "misalignment_deg": [0.0, 0.0]},
    }
    on_axis["contact"] = {**NOISY["contact"], "friction_coefficient": 0.0}
    # no F/T noise either: the noise's moments, fed back, would turn the model and tell it
    on_axis["rig"] = {**NOISY["rig"], "force_noise_n": 0.0, "moment_noise_n_m": 0.0}
    audit = audit_spacecraft6([_run({}, "axis", on_axis)])
    assert audit.findings == []
    assert audit.mass_kg is not None
    assert any(i is None for i in audit.inertia_kg_m2)  # no torque: undetermined, not a guess


def test_crosstalk_reads_the_axial_force_into_four_channels():
    values = {"fz_to_fx": 0.01, "fz_to_fy": -0.02, "fz_to_mx_m": 0.003, "fz_to_my_m": 0.004}
    w = np.array([1.0, 2.0, 3.0, 10.0, 20.0, -1000.0])  # [m; f]
    physics = physics_with(
        [(get_effect("sensor_crosstalk"), values)], rig_scale(parse_scenario(NOISY))
    )
    read = np.array(physics.sensor_gain) @ w
    np.testing.assert_allclose(read, [1.0 - 3.0, 2.0 - 4.0, 3.0, 10.0 - 10.0, 20.0 + 20.0, -1000.0])
    assert NOMINAL_PHYSICS.computer(parse_scenario(NOISY)) == parse_scenario(NOISY)


@pytest.mark.slow
def test_diagnose_finds_crosstalk_with_its_values(tmp_path):
    values = {"fz_to_fx": 0.01, "fz_to_fy": -0.005, "fz_to_mx_m": 0.003, "fz_to_my_m": -0.002}
    run = _run({"sensor_crosstalk": values}, "xt")
    d = diagnose_runs6([run], workers=2)
    assert d.verdict == "found" and d.selected == ["sensor_crosstalk"]
    for name, value in values.items():
        got, std = d.fit.values["sensor_crosstalk"][name], d.fit.std["sensor_crosstalk"][name]
        assert abs(got - value) < 5.0 * std
    # through the CLI
    from hybridtable.cli import main

    (tmp_path / "xt.csv").write_text(run6_csv_text(run))
    (tmp_path / "xt.json").write_text(json.dumps(run6_json(run)))
    out = tmp_path / "d.json"
    assert main(["diagnose", str(tmp_path), "--json", str(out), "--no-progress"]) == 0
    data = json.loads(out.read_text())
    assert data["found"] == ["sensor_crosstalk"] and data["audit"]["findings"] == []
