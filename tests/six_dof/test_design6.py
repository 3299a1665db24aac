"""The run that would separate two models of a six-axis rig
(six_dof/design6.py) and diagnose's separating step on 6-DoF runs.

Physical facts: a candidate run that changes nothing puts two models as far
apart as the recorded run does (to round-off); on a rig whose contact,
table and compensator are linear and homogeneous, twice the approach speed
puts them twice as far apart; a compliance in series with a linear spring
and the softer spring are one law, so no run separates them; and through
the CLI, diagnose says so with the look-alike's hint.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hybridtable.effects.registry import get_effect
from hybridtable.six_dof.compare6 import replay_residuals
from hybridtable.six_dof.design6 import DESIGNS, design_distance, mean_levels, separating_run6
from hybridtable.six_dof.fit6 import fit_runs6
from hybridtable.six_dof.physics6 import physics_with, rig_scale
from hybridtable.six_dof.run6 import run6_csv_text, run6_json, run6_of_docking
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.test_run6 import SCENARIO

#: On axis, no friction, no dead band: the loop is linear and homogeneous in
#: the approach speed once the pads touch (a unilateral linear contact).
LINEAR = {
    **SCENARIO,
    "spacecraft": {**SCENARIO["spacecraft"], "lateral_offset_m": [0.0, 0.0]},
    "contact": {"contact_stiffness_n_per_m": 1.0e5, "friction_coefficient": 0.0},
    "approach": {**SCENARIO["approach"], "misalignment_deg": [0.0, 0.0]},
}

K = 1.0e5
S = 2.0e-6


def _record(scenario: dict, hidden: dict, run_id: str = "r"):
    params = parse_scenario(scenario)
    physics = physics_with([(get_effect(n), v) for n, v in hidden.items()], rig_scale(params))
    return run6_of_docking(simulate6(params, physics=physics), run_id, scenario)


def _model(runs, values: dict):
    """A model with every value given (nothing fitted): its physics and its
    replay residuals on ``runs``."""
    return fit_runs6(runs, [(get_effect(n), v) for n, v in values.items()])


@pytest.fixture(scope="module")
def linear_runs():
    return [_record(LINEAR, {"contact_damping": {"damping_n_s_per_m": 400.0}})]


def test_a_run_that_changes_nothing_is_the_recorded_distance(linear_runs):
    a = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 400.0}})
    b = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 800.0}})
    recorded = float(np.linalg.norm(b.residuals - a.residuals))
    assert recorded > 1.0
    assert design_distance(linear_runs, a, b, {}) == pytest.approx(recorded, rel=1e-9)
    # the distance is of the two replays, whatever the record's own noise levels
    levels = mean_levels(linear_runs)
    r = linear_runs[0]
    direct = replay_residuals(r, b.physics, levels) - replay_residuals(r, a.physics, levels)
    assert float(np.linalg.norm(direct)) == pytest.approx(recorded, rel=1e-12)


def test_twice_the_approach_speed_is_twice_as_far_on_a_linear_rig(linear_runs):
    a = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 400.0}})
    b = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 800.0}})
    one = design_distance(linear_runs, a, b, {})
    two = design_distance(linear_runs, a, b, {"initial_velocity_m_per_s": 0.2})
    half = design_distance(linear_runs, a, b, {"initial_velocity_m_per_s": 0.05})
    assert two / one == pytest.approx(2.0, rel=5e-3)
    assert half / one == pytest.approx(0.5, rel=5e-3)
    sep = separating_run6(linear_runs, a, b)
    assert sep["run"] == "three times the approach velocity"  # the largest speed
    assert sep["separates"] and sep["runs_needed"] == 1
    assert sep["recorded_distance"] == pytest.approx(one, rel=1e-9)
    assert sep["changes"] == {"initial_velocity_m_per_s": pytest.approx(0.3)}


def test_a_series_compliance_and_the_softer_spring_are_never_separated(linear_runs):
    a = _model(linear_runs, {"series_compliance": {"series_compliance_m_per_n": S}})
    b = _model(linear_runs, {"stiffness_error": {"contact_stiffness_n_per_m": K / (1 + K * S)}})
    c = _model(linear_runs, {"stiffness_error": {"contact_stiffness_n_per_m": 0.8 * K}})
    real = design_distance(linear_runs, a, c, {})
    for _words, changes_of in DESIGNS:
        changes = changes_of(linear_runs)
        if changes is not None:
            assert design_distance(linear_runs, a, b, changes) < 1e-6 * real
    sep = separating_run6(linear_runs, a, b)
    assert not sep["separates"] and sep["distance"] < 1e-6 * real
    assert sep["runs_needed"] is None or sep["runs_needed"] > 1e6


def test_a_design_that_cannot_run_is_passed_over(linear_runs, monkeypatch):
    """A candidate run the rig cannot make (a negative approach speed) is
    left out, and the best of the others is the answer; with none left,
    there is no answer (None), not a made-up one."""
    import hybridtable.six_dof.design6 as design6

    a = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 400.0}})
    b = _model(linear_runs, {"contact_damping": {"damping_n_s_per_m": 800.0}})
    bad = ("a reversed approach", lambda r: {"initial_velocity_m_per_s": -0.1})
    good = ("twice the approach velocity", lambda r: {"initial_velocity_m_per_s": 0.2})
    monkeypatch.setattr(design6, "DESIGNS", (bad, good))
    sep = separating_run6(linear_runs, a, b)
    assert sep["run"] == "twice the approach velocity"
    monkeypatch.setattr(design6, "DESIGNS", (bad,))
    assert separating_run6(linear_runs, a, b) is None


def test_a_model_whose_reading_never_falls_back_still_gets_its_runs(linear_runs):
    """A force bias above the dead band keeps the reading on after the
    release, so the contact never ends by itself: the candidate run is
    simulated for as long as a contact is expected to take instead of being
    dropped."""
    bias = {"force_bias": {"bias_n": 50.0}}
    a, b = _model(linear_runs, bias), _model(linear_runs, {})
    assert design_distance(linear_runs, a, b, {"initial_velocity_m_per_s": 0.2}) > 1.0


def test_diagnose_names_no_run_for_one_law_and_says_why(tmp_path):
    """A hidden series compliance on the noisy rig: diagnose names it or
    the softer spring, the other as its look-alike, and says that no run
    tried separates them, with the look-alike's hint (console and JSON)."""
    from hybridtable.cli import main
    from tests.six_dof.test_diagnose6 import NOISY

    run = _record(NOISY, {"series_compliance": {"series_compliance_m_per_n": S}}, "s")
    folder = tmp_path / "runs"
    folder.mkdir()
    (folder / "run1.csv").write_text(run6_csv_text(run))
    (folder / "run1.json").write_text(json.dumps(run6_json(run)))
    out = tmp_path / "d.json"
    assert main(["diagnose", str(folder), "--json", str(out), "--no-progress"]) == 0
    doc = json.loads(out.read_text())
    (name,) = doc["selected"]
    other = ({"series_compliance", "stiffness_error"} - {name}).pop()
    assert doc["lookalikes"] == [other]
    (sep,) = doc["separating_runs"][name]
    assert sep["effects"] == [name, other] and not sep["separates"]
    assert sep["distance"] < 1e-3 and sep["recorded_distance"] < 1e-3
    assert sep["hint"] == get_effect(other).separation_hint


@pytest.mark.slow
def test_the_suggested_run_tells_the_look_alikes_apart(tmp_path):
    """A set of the independent generator's confusion study (seed 2003)
    hides a slower table and a contact damping; on its three runs diagnose
    names table_damping, table_response its look-alike, and says a run at
    three times the approach speed would separate them. The generator runs
    that approach on the same rig; with it, diagnose names the hidden pair
    and no look-alike is left."""
    import copy

    from hybridtable.six_dof.diagnose6 import diagnose_runs6
    from hybridtable.six_dof.run6 import read_runs6
    from tests.generators import run6_logs as g6

    s6 = g6.draw_set6(2003, "pair")  # the study's draw (benchmarks/study_diagnose6.py)
    assert set(s6.hidden) == {"table_response", "contact_damping"}
    g6.write_set6(tmp_path, s6)
    before = diagnose_runs6(read_runs6(sorted(tmp_path.glob("run*.csv"))), workers=2)
    assert set(before.selected) == {"table_damping", "contact_damping"}
    (sep,) = before.separations["table_damping"]
    assert sep["effects"] == ["table_damping", "table_response"] and sep["separates"]
    assert sep["run"] == "three times the approach velocity"
    scenario = copy.deepcopy(s6.runs[0][0])
    scenario["approach"]["initial_velocity_m_per_s"] = sep["changes"]["initial_velocity_m_per_s"]
    rate = scenario["rig"]["sample_rate_hz"]
    rows = g6.generate_run6(
        scenario,
        seed=991,
        **s6.truth["noise"],
        hidden=s6.hidden,
        table_start="tick0",
        hold_s=100.0 / rate,
    )
    g6.write_run6(tmp_path, f"run{len(s6.runs) + 1}", scenario, rows)
    after = diagnose_runs6(read_runs6(sorted(tmp_path.glob("run*.csv"))), workers=2)
    assert set(after.selected) == {"table_response", "contact_damping"}
    assert not after.lookalikes
