"""The audit of a six-axis rig computer's compensation law (six_dof/audit_law6.py):
a lead, an MDC stiffness and a dead band other than the JSON's are solved from
the record (the library's loop with the noise inside it, and the independent
generator's); the scenario's own computer has no finding; a computer that is
not the format's law is named; a log whose readings carry noise the computer
did not see is tested only against the JSON's law; what cannot be audited
says why."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from hybridtable.measurement.audit_fit import NOISE_LEVELS
from hybridtable.six_dof.audit6 import audit_runs6
from hybridtable.six_dof.audit_law6 import audit_compensation6
from hybridtable.six_dof.run6 import read_runs6, run6_csv_text, run6_json, run6_of_docking
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import simulate6
from tests.generators.run6_logs import generate_run6, scenario, write_run6
from tests.six_dof.test_diagnose6 import NOISY


def _told(run_as: dict, told: dict, run_id: str):
    """A run of the loop of ``run_as`` whose JSON says ``told``: a rig computer
    that does something other than what its log's JSON states."""
    return run6_of_docking(simulate6(parse_scenario(run_as)), run_id, told)


def _with(base: dict, **compensator) -> dict:
    out = copy.deepcopy(base)
    out["compensator"] = dict(out["compensator"], **compensator)
    return out


@pytest.fixture(scope="module")
def own():
    return _told(NOISY, NOISY, "own")


def test_the_scenarios_own_computer_is_its_json(own):
    audit = audit_compensation6([own])
    assert audit.findings == [] and not audit.not_audited and audit.ticks > 500
    assert audit.relative_residual < 1e-12
    assert audit.lead_s == pytest.approx(own.params.effective_lead_time_s, abs=1e-12)
    assert audit.factor == pytest.approx(1.0, abs=1e-9)
    assert audit.gain == pytest.approx(1.0, abs=1e-10)
    lower, upper = audit.deadband_n
    assert lower <= own.params.force_deadband_n < upper
    assert audit_runs6([own]).findings == []


def test_a_lead_other_than_the_jsons_is_solved():
    run = _told(_with(NOISY, lead_time_s=0.003), NOISY, "lead")
    audit = audit_compensation6([run])
    assert [f.effect for f in audit.findings] == ["lead_time_error"]
    assert audit.findings[0].values["lead_error_s"] == pytest.approx(-0.002, abs=1e-10)
    assert "its lead is 3" in audit.sentence()


def test_an_mdc_stiffness_other_than_the_jsons_is_solved():
    # the computer's contact model had 1e5 N/m; its JSON says 1.25e5
    run = _told(NOISY, _with(NOISY, stiffness_n_per_m=1.25e5), "stiffness")
    audit = audit_compensation6([run])
    assert [f.effect for f in audit.findings] == ["compensator_stiffness_error"]
    ratio = audit.findings[0].values["compensator_stiffness_ratio"]
    assert ratio == pytest.approx(0.8, abs=1e-9)  # K is linear in the pads' stiffness


def test_a_dead_band_other_than_the_jsons_is_bounded():
    run = _told(NOISY, _with(NOISY, force_deadband_n=40.0), "deadband")
    audit = audit_compensation6([run])
    assert [f.effect for f in audit.findings] == ["deadband_error"]
    lower, upper = audit.deadband_n
    assert lower <= 12.0 < upper  # the dead band the computer used


def test_a_computer_that_is_not_the_formats_law_is_named(own):
    scaled = copy.deepcopy(own)
    for block in ("f_comp", "m_comp"):
        scaled.blocks[block] = 1.01 * own.blocks[block]
    audit = audit_compensation6([scaled])
    # a gain on its output scales every constant of the law
    assert {f.effect for f in audit.findings} == {
        "compensation_law_error",
        "lead_time_error",
        "compensator_stiffness_error",
    }
    assert audit.gain == pytest.approx(1.01, abs=1e-9)
    assert audit.lead_s == pytest.approx(1.01 * own.params.effective_lead_time_s, abs=1e-11)
    assert audit.factor == pytest.approx(1.01, abs=1e-9)
    # a first-order lag on the compensated wrench: no constant of the law makes it
    lagged = copy.deepcopy(own)
    for block in ("f_comp", "m_comp"):
        x = own.blocks[block]
        lagged.blocks[block] = np.where(x != 0.0, 0.5 * (x + np.vstack([x[:1], x[:-1]])), 0.0)
    audit = audit_compensation6([lagged])
    assert [f.effect for f in audit.findings] == ["compensation_law_error"]
    assert audit.relative_residual > 1e-3 and "compensates otherwise" in audit.sentence()


def test_what_cannot_be_audited_says_why(own):
    online = _told(_with(NOISY, name="sdmdc-online"), _with(NOISY, name="sdmdc-online"), "o")
    audit = audit_compensation6([online])
    assert audit.findings == [] and "changes every tick" in audit.not_audited
    damped = copy.deepcopy(NOISY)
    damped["contact"] = dict(damped["contact"], contact_dissipation_s_per_m=0.5)
    audit = audit_compensation6([_told(damped, damped, "damped")])
    assert audit.findings == [] and "rate term" in audit.not_audited
    assert "not audited" in audit.sentence()


# -- against the independent generator (rig6: plain numpy, its own MDC by finite
# differences, its logger's noise added after the loop) ---------------------------


def _generated(tmp_path, lead_s: float, told_lead_s: float, noise: bool, stem: str):
    sc = scenario(compensator={"name": "SDMDC", "lead_time_s": lead_s})
    levels = (
        dict(
            force_noise_n=2.0, moment_noise_n_m=0.5, position_noise_m=2e-6, attitude_noise_rad=1e-6
        )
        if noise
        else {}
    )
    rows = generate_run6(sc, **levels)
    told = scenario(compensator={"name": "SDMDC", "lead_time_s": told_lead_s})
    write_run6(tmp_path, stem, told, rows)
    return read_runs6([tmp_path / f"{stem}.csv"])[0]


def test_the_generators_computer_is_audited(tmp_path):
    own = audit_compensation6([_generated(tmp_path, 0.005, 0.005, False, "own")])
    assert own.findings == [] and own.relative_residual < 1e-6  # its K by differences
    lead = audit_compensation6([_generated(tmp_path, 0.003, 0.005, False, "lead")])
    assert [f.effect for f in lead.findings] == ["lead_time_error"]
    assert lead.findings[0].values["lead_error_s"] == pytest.approx(-0.002, abs=1e-8)


def test_a_loggers_own_noise_is_not_taken_for_another_law(tmp_path):
    # rig6's logger adds the noise after the loop: the computer never saw it
    own = audit_compensation6([_generated(tmp_path, 0.005, 0.005, True, "own")])
    assert own.findings == [] and own.block > 1
    assert own.noise_levels <= NOISE_LEVELS and "to the noise" in own.sentence()
    # ... and a lead 2 ms off still shows, over means of ticks, without a guess at it
    lead = audit_compensation6([_generated(tmp_path, 0.003, 0.005, True, "lead")])
    assert [f.effect for f in lead.findings] == ["compensation_law_error"]
    assert lead.noise_levels > 3 * NOISE_LEVELS  # 14.8
    assert "cannot be solved" in lead.sentence() and "lead_time_error" not in lead.sentence()


def test_compare_names_the_lead_the_computer_used(tmp_path, capsys):
    from hybridtable.cli import main

    run = _told(_with(NOISY, lead_time_s=0.003), NOISY, "lead")
    (tmp_path / "run1.csv").write_text(run6_csv_text(run))
    (tmp_path / "run1.json").write_text(json.dumps(run6_json(run)))
    assert main(["compare", str(tmp_path / "run1.csv"), "--no-progress", "--json", "-"]) == 0
    audit = json.loads(capsys.readouterr().out)["audit"]
    assert [f["effect"] for f in audit["findings"]] == ["lead_time_error"]
    assert audit["compensation"][0]["solved"]["lead_time_s"] == pytest.approx(0.003, abs=1e-10)


@pytest.mark.parametrize(
    "effect, values, used",
    [
        ("lead_time_error", {"lead_error_s": -0.002}, {"lead_time_s": 0.003}),
        (
            "compensator_stiffness_error",
            {"compensator_stiffness_ratio": 0.8},
            {"stiffness_n_per_m": 0.8e5},
        ),
    ],
)
def test_what_the_audit_finds_runs_the_computer_it_found(effect, values, used):
    # the 6-DoF loop's computer takes the finding (apply6): the JSON's scenario with
    # the effect is the computer that used the other value, to round-off
    from hybridtable.effects.registry import get_effect
    from hybridtable.six_dof.physics6 import physics_with, rig_scale

    params = parse_scenario(NOISY)
    physics = physics_with([(get_effect(effect), values)], rig_scale(params))
    modelled = simulate6(params, physics=physics).log["compensated_wrench"]
    actual = simulate6(parse_scenario(_with(NOISY, **used))).log["compensated_wrench"]
    np.testing.assert_allclose(modelled, actual, rtol=0, atol=1e-9 * np.abs(actual).max())
    assert np.abs(actual).max() > 100.0


def test_a_model_file_carries_the_lead_the_audit_found(tmp_path, capsys):
    from hybridtable.cli import main

    run = _told(_with(NOISY, lead_time_s=0.003), NOISY, "lead")
    (tmp_path / "run1.csv").write_text(run6_csv_text(run))
    (tmp_path / "run1.json").write_text(json.dumps(run6_json(run)))
    model = tmp_path / "model.json"
    args = ["compare", str(tmp_path / "run1.csv"), "--no-progress", "--save-model", str(model)]
    assert main(args) == 0
    saved = json.loads(model.read_text())
    (lead,) = [e for e in saved["effects"] if e["name"] == "lead_time_error"]
    assert lead["parameters"]["lead_error_s"]["value"] == pytest.approx(-0.002, abs=1e-10)
    capsys.readouterr()
    args = ["compare", str(tmp_path / "run1.csv"), "--no-progress", "--model", str(model)]
    assert main([*args, "--json", "-"]) == 0
    out = json.loads(capsys.readouterr().out)
    # the closed loop of the JSON's computer misses the CoR; with the audited lead it does not
    assert abs(out["runs"][0]["cor_error"]) > 0.01
    assert abs(out["model"]["runs"][0]["cor_error"]) < 0.1 * abs(out["runs"][0]["cor_error"])


def test_a_loggers_noise_gives_no_finding_over_seeds_and_a_dead_band_still_shows(tmp_path):
    noise = dict(force_noise_n=2.0, moment_noise_n_m=0.5, position_noise_m=2e-6)
    for seed in range(5):
        rows = generate_run6(scenario(compensator={"name": "SDMDC"}), seed=seed, **noise)
        write_run6(tmp_path, f"s{seed}", scenario(compensator={"name": "SDMDC"}), rows)
        audit = audit_compensation6(read_runs6([tmp_path / f"s{seed}.csv"]))
        assert audit.findings == [] and audit.noise_levels < NOISE_LEVELS, audit.sentence()
        assert audit.lead_s is None and "would not show" in audit.sentence()
    # the computer's dead band 20 N, its JSON's none
    used = scenario(compensator={"name": "SDMDC", "force_deadband_n": 20.0})
    write_run6(
        tmp_path, "db", scenario(compensator={"name": "SDMDC"}), generate_run6(used, **noise)
    )
    audit = audit_compensation6(read_runs6([tmp_path / "db.csv"]))
    assert [f.effect for f in audit.findings] == ["deadband_error"]
    lower, upper = audit.deadband_n
    assert lower <= 20.0 < upper


def test_runs_of_other_delays_are_audited_apart():
    # no lead stated: each run's lead is its own delay
    other = copy.deepcopy(NOISY)
    other["rig"] = dict(other["rig"], sensor_delay_s=0.004)
    audit = audit_runs6([_told(NOISY, NOISY, "d5"), _told(other, other, "d4")])
    assert len(audit.laws) == 2 and audit.findings == []


def test_a_law_the_json_does_not_state_is_not_taken_for_a_constant():
    # an SDC computer under an SDMDC JSON: no MDC term at all, not a softer stiffness
    audit = audit_compensation6([_told(_with(NOISY, name="SDC"), NOISY, "sdc")])
    assert [f.effect for f in audit.findings] == ["compensation_law_error"]
    assert abs(audit.factor) < 1e-6
    # an SDMDC computer under an MDC JSON: a lead the JSON's compensator has not
    audit = audit_compensation6([_told(NOISY, _with(NOISY, name="MDC"), "mdc")])
    assert [f.effect for f in audit.findings] == ["compensation_law_error"]
    assert audit.lead_s == pytest.approx(0.005, abs=1e-9) and "has no lead" in audit.sentence()


def test_a_finding_out_of_its_effects_bounds_stays_in_the_evidence():
    from hybridtable.six_dof.model6 import model6_of_runs

    # the computer led by 5 ms, its JSON says 30 ms: -25 ms, below lead_error_s's -20 ms
    run = _told(NOISY, _with(NOISY, lead_time_s=0.03), "far")
    audit = audit_runs6([run])
    assert audit.effects == ["lead_time_error"]
    model = model6_of_runs([run], [], audit, "compare")
    assert [e.name for e in model.effects] == []
    assert "out of bounds" in model.evidence["audit_not_in_the_model"][0]


def test_a_computer_that_never_compensated_has_a_dead_band_above_its_readings(own):
    silent = copy.deepcopy(own)
    for block in ("f_comp", "m_comp"):
        silent.blocks[block] = np.zeros_like(own.blocks[block])
    audit = audit_compensation6([silent])
    assert [f.effect for f in audit.findings] == ["deadband_error"]
    peak = float(np.max(np.linalg.norm(own.blocks["f_mea"], axis=1)))
    assert audit.deadband_n[0] > 0.5 * peak and "no reading got a compensation" in audit.sentence()


def test_a_model_stepped_by_another_time_step_than_the_jsons_rate_is_named(own):
    # the computer ticks and steps its model at 1 kHz; its JSON says 1250 Hz
    from hybridtable.six_dof.audit_law6 import time_step

    h, se = time_step(own)
    assert h == pytest.approx(own.params.sample_period_s, rel=1e-12)
    told = copy.deepcopy(NOISY)
    told["rig"] = dict(told["rig"], sample_rate_hz=1250.0)
    audit = audit_runs6([_told(NOISY, told, "rate")])
    # read with its own step, neither its mass and inertia nor its lead pass for errors
    assert audit.effects == ["sample_rate_error"]
    assert audit.findings[0].values["sample_rate_hz"] == pytest.approx(1000.0, rel=1e-9)
