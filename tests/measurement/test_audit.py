"""The audit of the rig computer: values solved from the record, exact up to the CSV.

Records come from ``tests/generators/rigsim.py`` (an independent rig
computer and RK4 table); its computer is given other values than the JSON it
writes, as a misconfigured rig would be.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hybridtable.measurement.audit import audit_run, audit_runs
from hybridtable.measurement.rig import RigPhysics, simulate_rig
from hybridtable.measurement.run_reader import read_run
from tests.generators.rigsim import NOMINAL, simulate_record, write_run


def _run(tmp_path, used: dict, said: dict | None = None, seed: int = 1, **kw):
    """A run whose computer used ``used`` while its JSON says ``said``."""
    info_used = dict(NOMINAL, **used)
    info_said = dict(NOMINAL, run_id=f"r{seed}", **(said or {}))
    cols = simulate_record(info_used, seed=seed, duration_s=0.5, **kw)
    return read_run(write_run(tmp_path, info_said["run_id"], info_said, cols))


def test_a_computer_that_did_what_its_json_says_passes(tmp_path):
    runs = [_run(tmp_path, {}, seed=s) for s in (1, 2)]
    audit = audit_runs(runs)
    assert audit.ok, [f.text for f in audit.findings]
    est = audit.estimates[0]
    assert est.mass_kg == pytest.approx(NOMINAL["spacecraft_mass_kg"], rel=1e-6)
    assert est.lead_time_s == pytest.approx(NOMINAL["lead_time_s"], rel=1e-6)
    assert est.stiffness_n_per_m == pytest.approx(NOMINAL["contact_stiffness_n_per_m"], rel=1e-6)
    assert est.gain == pytest.approx(1.0, abs=1e-6)
    lo, hi = est.deadband_n
    assert lo <= NOMINAL["force_deadband_n"] < hi


@pytest.mark.parametrize(
    "key, used",
    [
        ("spacecraft_mass_kg", 700.0),
        ("spacecraft_mass_kg", 675.475 * 0.9995),  # 0.05 %: still named, to 0.1 %
        ("lead_time_s", 0.005),
        ("contact_stiffness_n_per_m", 66000.0),
    ],
)
def test_a_wrong_json_value_is_found_to_within_0_1_percent(tmp_path, key, used):
    said = {key: NOMINAL[key]}
    # (for the stiffness, rigsim's contact uses the computer's value too: the
    # audit reads only the computer's arithmetic, never the physics)
    run = _run(tmp_path, {key: used}, said)
    audit = audit_runs([run])
    found = {f.key: f for f in audit.findings}
    assert key in found, [f.text for f in audit.findings]
    assert found[key].used_value == pytest.approx(used, rel=1e-3)
    assert found[key].json_value == NOMINAL[key]
    # nothing else is reported
    assert set(found) == {key}


def test_lead_time_message_says_used_and_json(tmp_path):
    run = _run(tmp_path, {"lead_time_s": 0.004}, {"lead_time_s": 0.005})
    (f,) = audit_runs([run]).findings
    assert f.text == "lead_time_s used 4 ms, JSON says 5 ms"
    assert f.effect == "lead_time_error"
    assert f.relative_error == pytest.approx(-0.2, abs=1e-6)


def test_another_compensator_and_deadband_are_named(tmp_path):
    run = _run(tmp_path, {"compensator": "MDC", "force_deadband_n": 2.0}, {"compensator": "SDC"})
    audit = audit_runs([run])
    found = {f.key: f for f in audit.findings}
    assert set(found) == {"lead_time_s", "contact_stiffness_n_per_m", "force_deadband_n"}
    assert found["lead_time_s"].used_value == pytest.approx(0.0, abs=1e-7)
    assert found["contact_stiffness_n_per_m"].used_value == pytest.approx(60000.0, rel=1e-6)
    lo, hi = audit.estimates[0].deadband_n
    assert lo <= 2.0 < hi and not lo <= 6.0 < hi
    changes = audit.computer_changes(run.run_id)
    assert changes["compensator"] == "MDC"
    assert changes["compensator_stiffness_n_per_m"] == pytest.approx(60000.0, rel=1e-6)


def test_the_audited_computer_reproduces_the_record_in_the_closed_loop(tmp_path):
    used = {"spacecraft_mass_kg": 720.0, "lead_time_s": 0.003, "force_deadband_n": 2.0}
    run = _run(tmp_path, used, noise_f_n=0.0, noise_p_m=0.0)
    audit = audit_runs([run])
    assert {f.key for f in audit.findings} == set(used)
    nominal = simulate_rig(run, RigPhysics(), accuracy=1e-9)
    audited = simulate_rig(
        run, RigPhysics(computer=audit.computer_changes(run.run_id)), accuracy=1e-9
    )
    err = {
        name: float(np.max(np.abs(sim.v_des_m_per_s - run.v_des_m_per_s)))
        for name, sim in (("nominal", nominal), ("audited", audited))
    }
    # noise-free: the audited loop is the record up to the integrators (RK4 vs RK3)
    assert err["audited"] < 1e-3 * err["nominal"]
    assert err["audited"] < 1e-6


def test_a_gain_an_unclamped_force_and_a_forced_spacecraft_are_named(tmp_path):
    run = _run(tmp_path, {})
    scaled = dataclasses.replace(run, f_comp_n=1.02 * run.f_comp_n)
    _, found = audit_run(scaled)
    assert "compensation_gain" in {f.key for f in found}
    f_comp = run.f_comp_n.copy()
    on = np.flatnonzero(f_comp > 0)
    f_comp[on[-1] + 1] = -5.0
    _, found = audit_run(dataclasses.replace(run, f_comp_n=f_comp))
    assert "clamp" in {f.key for f in found}
    v = run.v_des_m_per_s.copy()
    v[-20:] += 1e-3
    _, found = audit_run(dataclasses.replace(run, v_des_m_per_s=v))
    assert "spacecraft_model" in {f.key for f in found}


def test_runs_that_agree_are_merged_into_one_finding(tmp_path):
    runs = [_run(tmp_path, {"spacecraft_mass_kg": 700.0}, seed=s) for s in (1, 2, 3)]
    audit = audit_runs(runs)
    (f,) = audit.findings
    assert f.runs == ("r1", "r2", "r3")
    assert f.used_value == pytest.approx(700.0, rel=1e-6)
    assert audit.effects == ["mass_error"]


def _logged_with_noise(tmp_path, used: dict, seed: int):
    """A run whose logger adds its own noise to the readings (2 N, 2 um): the
    computer compensated the readings without it."""
    info_used = dict(NOMINAL, **used)
    info_said = dict(NOMINAL, run_id=f"logger{seed}")
    cols = simulate_record(info_used, seed=seed, duration_s=0.5, noise_f_n=0.0, noise_p_m=0.0)
    rng = np.random.default_rng(seed)
    cols["f_mea_n"] = cols["f_mea_n"] + 2.0 * rng.standard_normal(len(cols["f_mea_n"]))
    cols["p_act_m"] = cols["p_act_m"] + 2e-6 * rng.standard_normal(len(cols["p_act_m"]))
    return read_run(write_run(tmp_path, info_said["run_id"], info_said, cols))


def test_a_loggers_own_noise_is_not_taken_for_another_compensation(tmp_path):
    from hybridtable.measurement.audit_fit import NOISE_LEVELS

    own = audit_runs([_logged_with_noise(tmp_path, {}, seed=3)])
    assert own.ok, [f.text for f in own.findings]
    assert own.estimates[0].compensation_noise_levels <= NOISE_LEVELS
    # a lead 1 ms off still shows over means of ticks, as the law, not as a guess
    lead = audit_runs([_logged_with_noise(tmp_path, {"lead_time_s": 0.003}, seed=4)])
    assert [f.key for f in lead.findings] == ["compensation_law"]
    assert lead.estimates[0].compensation_noise_levels > NOISE_LEVELS


def test_a_loggers_noise_leaves_no_finding_over_seeds_and_a_dead_band_still_shows(tmp_path):
    for seed in range(5, 10):
        audit = audit_runs([_logged_with_noise(tmp_path, {}, seed=seed)])
        assert audit.ok, [f.text for f in audit.findings]
        assert np.isnan(audit.estimates[0].lead_time_s)  # not solved from such readings
        assert "not solved" in audit.notes[0]
    audit = audit_runs([_logged_with_noise(tmp_path, {"force_deadband_n": 30.0}, seed=11)])
    assert [f.key for f in audit.findings] == ["force_deadband_n"]
    lower, upper = audit.estimates[0].deadband_n
    assert lower <= 30.0 < upper
