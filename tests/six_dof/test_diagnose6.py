"""diagnose on 6-DoF runs (six_dof/diagnose6.py): nothing missing on a run of
the scenario's own rig, the hidden effect found (alone and in a pair), and an
effect outside the candidates not explained; through the CLI."""

from __future__ import annotations

import json

import pytest

from hybridtable.effects.registry import get_effect
from hybridtable.six_dof.diagnose6 import diagnose_runs6
from hybridtable.six_dof.physics6 import physics_with, rig_scale
from hybridtable.six_dof.run6 import run6_csv_text, run6_json, run6_of_docking
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.test_run6 import SCENARIO

#: The conftest's rig with F/T and encoder noise in the loop and a dead band above it.
NOISY = {
    **SCENARIO,
    "contact": {**SCENARIO["contact"], "friction_coefficient": 0.3},
    "rig": {
        **SCENARIO["rig"],
        "force_noise_n": 2.0,
        "moment_noise_n_m": 0.5,
        "position_noise_m": 2e-6,
        "attitude_noise_rad": 1e-6,
        "seed": 3,
    },
    "compensator": {"name": "SDMDC", "force_deadband_n": 12.0},
}


def _run(hidden: dict, run_id: str):
    params = parse_scenario(NOISY)
    physics = physics_with([(get_effect(n), v) for n, v in hidden.items()], rig_scale(params))
    return run6_of_docking(simulate6(params, physics=physics), run_id, NOISY)


def test_a_run_of_the_scenarios_own_rig_misses_nothing():
    d = diagnose_runs6([_run({}, "null")], workers=2)
    assert d.verdict == "nothing missing" and not d.selected
    assert max(d.nominal_errors.values()) < 1.3
    assert d.sentence().startswith("nothing is missing")


def test_a_stiffer_contact_is_found_with_its_value():
    d = diagnose_runs6(
        [_run({"stiffness_error": {"contact_stiffness_n_per_m": 1.2e5}}, "k")], workers=2
    )
    assert d.verdict == "found" and d.selected == ["stiffness_error"]
    k = d.fit.values["stiffness_error"]["contact_stiffness_n_per_m"]
    std = d.fit.std["stiffness_error"]["contact_stiffness_n_per_m"]
    assert abs(k - 1.2e5) < 4.0 * std
    assert d.nominal_errors["fz_mea"] > 10.0 and d.final_errors["fz_mea"] < 1.3


def test_a_pair_is_found_and_an_effect_outside_the_candidates_is_not_explained(tmp_path):
    hidden = {
        "sensor_misalignment": {
            "sensor_roll_rad": 0.01,
            "sensor_pitch_rad": -0.02,
            "sensor_yaw_rad": 0.0,
        },
        "friction_across_face": {"extra_friction_coefficient": 0.2},
    }
    run = _run(hidden, "pair")
    d = diagnose_runs6([run], workers=2)
    assert d.verdict == "found"
    assert set(d.selected) == {"sensor_misalignment", "friction_across_face"}
    # the same run with the candidates that cannot carry the turned sensor
    outside = diagnose_runs6(
        [run], ["stiffness_error", "extra_delay", "table_response", "friction_across_face"], 2
    )
    assert outside.verdict == "not explained"
    assert outside.sentence().startswith("not explained")
    assert max(outside.final_errors.values()) > 1.3
    # through the CLI: the run's files, diagnose --json
    from hybridtable.cli import main

    folder = tmp_path / "pair"
    folder.mkdir()
    (folder / "run1.csv").write_text(run6_csv_text(run))
    (folder / "run1.json").write_text(json.dumps(run6_json(run)))
    out, report = tmp_path / "d.json", tmp_path / "report"
    args = ["diagnose", str(folder), "--json", str(out), "--no-progress", "--report", str(report)]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "found" and doc["format"] == "hybridtable-run6/1"
    # the report: the diagnosis over the compare report, before and with the effects found
    md = (report / "report.md").read_text()
    assert md.splitlines()[2] == f"**{doc['sentence']}**" and "round 2:" in md
    assert "## With the fitted effects" in md and "sensor_roll_rad" in md
    assert sorted(p.suffix for p in report.iterdir()) == [".md", ".png", ".png"]
    assert doc["report"] == [
        str(report / "report.md"),
        *sorted(str(p) for p in report.glob("*.png")),
    ]
    assert main(args) == 2  # an existing report is replaced only with --force
    assert set(doc["selected"]) == {"sensor_misalignment", "friction_across_face"}
    roll = doc["fit"]["values"]["sensor_misalignment"]["sensor_roll_rad"]
    assert roll == pytest.approx(
        0.01, abs=4.0 * doc["fit"]["std"]["sensor_misalignment"]["sensor_roll_rad"]
    )


def test_a_candidate_that_cannot_act_on_the_rig_is_left_out_with_why():
    """The Stewart platform's response is its legs' reference model: the
    table's response effects cannot change it, and diagnose says so instead
    of failing their fits."""
    from types import SimpleNamespace

    from hybridtable.six_dof.diagnose6 import _able
    from hybridtable.six_dof.scenario import load_scenario
    from tests.six_dof.test_run6 import EXAMPLES

    run = SimpleNamespace(params=load_scenario(EXAMPLES / "stewart.toml"))
    able, refused = _able([run], ["stiffness_error", "table_response", "table_damping"])
    assert able == ["stiffness_error"]
    assert set(refused) == {"table_response", "table_damping"}
    assert all("Stewart" in why for why in refused.values())


def test_a_fit_that_ends_at_a_bound_is_said():
    """An effect whose fit ends on its boundary may stand in for another: the
    verdict says which parameter, and the JSON lists it."""
    from hybridtable.effects.spec import RigScale
    from hybridtable.six_dof.verdict6 import Diagnosis6

    scale = RigScale(1e5, 2533.0, 1e-3, 5e-3, 0.1, 25.0)
    effect = get_effect("mount_resonance")
    upper = effect.parameter("mount_damping_ratio").bounds(scale)[1]
    assert effect.at_bounds({"mount_frequency_hz": 30.0, "mount_damping_ratio": upper}, scale) == [
        f"mount_damping_ratio at its bound {upper:.4g}"
    ]
    assert effect.at_bounds({"mount_frequency_hz": 30.0, "mount_damping_ratio": 0.3}, scale) == []

    class _Fit:
        values = {"mount_resonance": {"mount_frequency_hz": 30.0, "mount_damping_ratio": upper}}
        std = {"mount_resonance": {"mount_frequency_hz": 0.1, "mount_damping_ratio": 0.01}}

        def to_dict(self):
            return {"values": self.values, "std": self.std}

    errors = {"fz_mea": 1.0, "fx_mea": 1.0}
    d = Diagnosis6(["r"], ["mount_resonance"], {"fz_mea": 9.0, "fx_mea": 1.0})
    d.selected, d.fit, d.final_errors, d.scale = ["mount_resonance"], _Fit(), errors, scale
    assert d.verdict == "found"
    assert "mount_resonance's mount_damping_ratio at its bound 0.7071: it may stand in" in (
        d.sentence()
    )
    assert d.to_dict()["at_bounds"] == ["mount_resonance's mount_damping_ratio at its bound 0.7071"]


@pytest.mark.slow
def test_the_swap_step_names_the_simpler_of_two_look_alikes(tmp_path):
    """The independent generator hides a compliance behind the pads and a
    friction force along the normal. Round 1 takes the power law (its exponent
    soaks up the friction's misfit), round 2 the friction; the swap step then
    names the linear stiffness, one parameter fewer and no worse (the power
    law's exponent is back at 1), with the series compliance, the same law on
    one spring, as its look-alike; and the values are the hidden ones."""
    from hybridtable.six_dof.run6 import read_run6
    from tests.generators import run6_logs as g6

    scen = g6.scenario(compensator={"name": "SDC"})
    s, friction = 2.0e-6, 50.0
    hidden = {
        "series_compliance": {"series_compliance_m_per_n": s},
        "coulomb_friction": {"friction_force_n": friction},
    }
    rows = g6.generate_run6(
        scen,
        seed=4,
        force_noise_n=2.0,
        moment_noise_n_m=0.5,
        position_noise_m=2e-6,
        attitude_noise_rad=1e-6,
        hidden=hidden,
        table_start="tick0",
    )
    csv, _ = g6.write_run6(tmp_path, "pair", scen, rows)
    result = diagnose_runs6([read_run6(csv)], workers=2)
    named = set(result.selected)
    assert "coulomb_friction" in named and result.explained
    softer = named - {"coulomb_friction"}
    assert softer <= {"stiffness_error", "series_compliance"} and len(softer) == 1
    other = ({"stiffness_error", "series_compliance"} - softer).pop()
    assert other in result.lookalikes_of[softer.pop()]
    k = float(scen["contact"]["contact_stiffness_n_per_m"])
    values = result.fit.values
    if "stiffness_error" in values:
        assert values["stiffness_error"]["contact_stiffness_n_per_m"] == pytest.approx(
            k / (1.0 + k * s), rel=1e-3
        )
    assert values["coulomb_friction"]["friction_force_n"] == pytest.approx(friction, rel=0.02)
    swap = [step for step in result.steps if step.kind == "swap"]
    assert len(swap) == 1


def test_after_a_swap_each_look_alike_is_paired_with_the_model_it_replaces(monkeypatch):
    """The swap step's bookkeeping with stand-in fits (no simulation): a
    candidate that could replace either selected effect is paired, for the
    separating run, with the model in which it replaces the swapped one, so
    the two models differ in those two effects alone; a look-alike of
    another effect noted in a swap that changed the selection gets no pair
    (its models would hold the effect swapped out)."""
    import hybridtable.six_dof.diagnose6 as d6
    from hybridtable.six_dof.verdict6 import Diagnosis6, Step6

    a, b, x, y = "contact_damping", "sensor_filter", "extra_delay", "table_damping"

    class Fit:
        def __init__(self, names):
            self.names = frozenset(names)
            self.values = {n: {} for n in names}
            self.std = {}
            self.residuals = self.names

    scores = {frozenset({b, y}): 20.0, frozenset({b, x}): 16.0, frozenset({a, x}): 2.0}
    monkeypatch.setattr(d6, "pool_map", lambda fn, jobs, workers, **kw: [Fit(n) for n, _ in jobs])
    monkeypatch.setattr(d6, "blocks", lambda runs, residuals: residuals)
    monkeypatch.setattr(d6, "delta_bic", lambda cur, new, dk, *rest: scores[new])
    monkeypatch.setattr(d6, "component_errors", lambda runs, residuals: {})
    monkeypatch.setattr(d6, "compatible", lambda names: True)
    out = Diagnosis6(run_ids=["r"], candidates=[a, b, x, y], nominal_errors={})
    out.selected, out.fit = [a, b], Fit([a, b])
    round1 = [
        {"effect": a, "delta_bic": 100.0, "values": {a: {}}},
        {"effect": y, "delta_bic": 98.0, "values": {y: {}}},
        {"effect": x, "delta_bic": 60.0, "values": {x: {}}},
    ]
    round2 = [
        {"effect": b, "delta_bic": 50.0, "values": {a: {}, b: {}}},
        {"effect": x, "delta_bic": 30.0, "values": {a: {}, x: {}}},
    ]
    out.steps = [Step6(round1, a, ""), Step6(round2, b, "")]
    out.lookalikes_of = {a: [y], b: []}
    d6._swap_step(["run"], out, 1, False)
    assert out.selected == [y, b]
    assert x in out.lookalikes_of[y] and x in out.lookalikes_of[b]
    for (selected, other), (one, two) in out.pairs.items():
        assert one.names ^ two.names == {selected, other}
    assert (y, x) in out.pairs and (b, x) not in out.pairs
