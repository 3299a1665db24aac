"""diagnose on runs with a hidden effect (tests/generators/effectsim.py: RK4, exact contact
laws, continuous filter and delay, white or AR(1) noise) and on runs without one.

A representative subset (the full confusion study over every effect, sizes and
seeds is benchmarks/confusion_diagnose.py): two approach velocities, short
records, and for some cases a restricted candidate list, to keep the module
well under a minute on two cores.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hybridtable.cli import main
from hybridtable.diagnosis.diagnose import diagnose
from hybridtable.diagnosis.evaluate import prepare_runs
from hybridtable.diagnosis.fit import fit_effect
from hybridtable.effects.registry import register_effect, unregister_effect
from hybridtable.measurement.noise_model import NoiseModel, estimate_noise, whiten
from hybridtable.measurement.run_format import Run, RunInfo
from tests.diagnosis.support import sensor_gain_effect
from tests.generators.effectsim import make_runs, simulate_hidden
from tests.generators.rigsim import NOMINAL

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

VELOCITIES = (0.06, 0.1)
COMPENSATORS = ("SDMDC", "none")


def _runs(tmp_path, effect, phi=0.0, seed=0, size=None, **kw):
    # Coloured noise needs longer quiet stretches for its noise floor: with
    # AR(1) 0.7 a tick is worth (1 - 0.7) / (1 + 0.7) of a white one.
    return make_runs(
        tmp_path / effect,
        effect,
        size=size,
        velocities=VELOCITIES,
        noise_phi=phi,
        seed=seed,
        compensators=COMPENSATORS,
        duration_s=0.55 if phi == 0.0 else 0.8,
        **kw,
    )


def _named(d, hidden: str) -> bool:
    """The verdict is the hidden effect, or one it reports as indistinguishable."""
    if d.verdict == hidden:
        return True
    top = next(c for c in d.ranking if c.effect == d.verdict)
    return hidden in top.indistinguishable_from


# -- noise model -----------------------------------------------------------------
@pytest.mark.parametrize("phi", [0.0, 0.6])
def test_noise_is_estimated_without_a_model(phi):
    info = dict(NOMINAL, run_id="noise")
    cols = simulate_hidden(info, "none", duration_s=2.0, noise_phi=phi, seed=7)
    run = Run(
        RunInfo(**info),
        *(
            cols[c]
            for c in ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")
        ),
    )
    noise = estimate_noise(run, delay_ticks=4, settle_ticks=40)
    assert noise["f_mea_n"].sigma == pytest.approx(2.0, rel=0.12)
    assert noise["f_mea_n"].phi == pytest.approx(phi, abs=0.08)
    assert noise["p_act_m"].sigma == pytest.approx(2e-6, rel=0.15)
    assert noise["p_act_m"].phi == pytest.approx(phi, abs=0.1)


def test_whitening_gives_unit_white_innovations():
    rng = np.random.default_rng(3)
    phi, sigma = 0.7, 2.0
    e = np.empty(20000)
    e[0] = sigma * rng.standard_normal()
    for k in range(1, len(e)):
        e[k] = phi * e[k - 1] + sigma * math.sqrt(1 - phi * phi) * rng.standard_normal()
    w = whiten(e, NoiseModel(sigma, phi, len(e)))
    assert np.var(w) == pytest.approx(1.0, rel=0.03)
    assert abs(np.corrcoef(w[1:], w[:-1])[0, 1]) < 0.03


# -- verdicts --------------------------------------------------------------------
@pytest.mark.parametrize("phi", [0.0, 0.7], ids=["white", "ar1"])
def test_no_hidden_effect_says_none(tmp_path, phi):
    d = diagnose(_runs(tmp_path, "none", phi=phi, seed=11))
    assert d.verdict == "none" and d.selected == [] and d.explained
    assert not any(c.accepted for c in d.ranking)
    assert d.staircase[-1]["error"] == pytest.approx(1.0, abs=0.1)
    assert d.audit.ok and d.goodness.passed
    doc = d.to_json()
    assert doc["explained"] is True and doc["selected"] == []
    assert doc["remaining"]["heldout_error"] == pytest.approx(1.0, abs=0.1)


@pytest.mark.parametrize(
    "hidden, library, channel",
    [
        ("table_resonance", ["contact_damping", "force_bias", "stiffness_error"], "p_act_m"),
        ("contact_damping", ["force_bias", "table_resonance", "sensor_filter"], "f_mea_n"),
    ],
    ids=["resonance-unknown", "damping-unknown"],
)
def test_an_effect_outside_the_library_is_unexplained(tmp_path, hidden, library, channel):
    d = diagnose(_runs(tmp_path, hidden, seed=5), effects=library)
    assert not d.explained
    assert d.verdict == "unexplained" or d.selected, d.verdict
    doc = d.to_json()
    assert doc["explained"] is False
    where = doc["remaining"]["where"]
    assert where["channel"] == channel and where["error"] > 1.5
    assert doc["remaining"]["p_value"] < 0.01
    # every candidate the library offered says why it was not taken, or it was
    for c in d.ranking:
        assert c.reason


def test_a_significant_effect_that_leaves_the_error_is_rejected(tmp_path):
    # force_bias fits a little of a damped contact's force, significantly, but
    # removes far less than a quarter of the excess error: it must not be named
    d = diagnose(_runs(tmp_path, "contact_damping", seed=5), effects=["force_bias"])
    (bias,) = d.ranking
    assert not bias.accepted
    assert d.verdict == "unexplained" and not d.explained
    if bias.significant:
        assert bias.excess_removed < 0.25 and "excess error" in bias.reason


@pytest.mark.parametrize(
    "hidden, phi, effects",
    [
        ("contact_damping", 0.0, None),
        ("extra_delay", 0.7, None),
        ("coulomb_friction", 0.7, None),
        ("table_resonance", 0.0, ["table_resonance", "contact_damping", "force_bias"]),
        ("nonlinear_stiffness", 0.0, ["nonlinear_stiffness", "stiffness_error", "hunt_crossley"]),
    ],
    ids=["damping-white", "delay-ar1", "friction-ar1", "resonance-white", "power-law-white"],
)
def test_hidden_effect_is_named_and_error_falls_to_the_noise(tmp_path, hidden, phi, effects):
    d = diagnose(_runs(tmp_path, hidden, phi=phi, seed=5), effects=effects)
    assert _named(d, hidden), d.verdict
    before, after = d.staircase[0], d.staircase[-1]
    assert before["error"] > 1.3
    assert after["heldout_error"] < 1.1
    top = next(c for c in d.ranking if c.effect == d.verdict)
    assert top.significant and top.delta_bic > 100 and top.heldout_z > 3


def test_mass_error_is_decided_by_the_audit_not_by_a_fit(tmp_path):
    d = diagnose(
        _runs(tmp_path, "mass_error", seed=2),
        effects=["contact_damping", "force_bias", "mass_error"],
    )
    assert d.verdict == "mass_error" and d.explained
    (finding,) = d.audit.findings
    assert finding.key == "spacecraft_mass_kg"
    # arithmetic on the record: exact up to the CSV's 10 digits, not a fit's 0.2 %
    assert finding.used_value / finding.json_value == pytest.approx(1.05, rel=1e-6)
    assert d.to_json()["parameters"]["mass_error"]["mass_ratio"] == pytest.approx(1.05, rel=1e-6)
    # the replay saw nothing: no physics effect was selected
    assert d.selected == [] and not any(c.accepted for c in d.rounds[0])
    # with the mass the computer used, the closed loop reproduces the record
    before, after = (d.closed_loop[k]["runs"] for k in ("before", "after"))
    for b, a in zip(before, after, strict=True):
        assert a["v_des_rms_error_m_per_s"] < 0.2 * b["v_des_rms_error_m_per_s"]


def test_series_compliance_is_reported_indistinguishable_from_a_softer_contact(tmp_path):
    d = diagnose(
        _runs(tmp_path, "series_compliance", seed=4),
        effects=["stiffness_error", "series_compliance", "contact_damping"],
    )
    assert d.verdict in ("stiffness_error", "series_compliance")
    assert _named(d, "series_compliance")
    top = next(c for c in d.ranking if c.effect == d.verdict)
    # k k_s / (k + k_s) = 60000 / (1 + 60000 * 2e-6) = 53571 N/m either way
    if d.verdict == "stiffness_error":
        assert top.parameters["contact_stiffness_n_per_m"] == pytest.approx(53571, rel=0.01)
    # no run of this rig separates them: their predictions coincide
    assert top.separation is not None and not top.separation["separates"]
    assert top.separation["distance"] < 1.0


def test_forward_selection_staircase_with_two_hidden_effects(tmp_path):
    d = diagnose(
        _runs(tmp_path, "contact_damping+force_bias", seed=8),
        effects=["contact_damping", "force_bias", "sensor_filter", "stiffness_error"],
    )
    assert set(d.selected) == {"contact_damping", "force_bias"}
    errors = [s["error"] for s in d.staircase]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 1.05
    assert d.selected_values["force_bias"]["bias_n"] == pytest.approx(-4.0, abs=0.4)
    assert d.selected_values["contact_damping"]["damping_n_s_per_m"] == pytest.approx(400, rel=0.05)


def test_two_effects_whose_cor_changes_cancel_are_both_named(tmp_path):
    # friction removes energy, an extra sensor delay adds it: the CoR barely
    # moves, the time series does (a damping would not do: a delay d of a
    # spring's reading is, to first order, a damping of -k d)
    d = diagnose(
        _runs(tmp_path, "coulomb_friction+extra_delay", seed=12, size={"F": 10.0, "d": 0.001}),
        effects=["contact_damping", "coulomb_friction", "extra_delay", "force_bias"],
    )
    assert set(d.selected) == {"coulomb_friction", "extra_delay"}, d.verdict
    assert d.explained
    before, after = (d.closed_loop[k]["runs"] for k in ("before", "after"))
    for b in before:
        assert abs(b["cor_error"]) < 0.05  # the CoR alone hides them


def test_a_registered_user_effect_is_diagnosed(tmp_path):
    gain = sensor_gain_effect("sensor_gain", typical_change=0.005)
    register_effect(gain)
    try:
        runs = _runs(tmp_path, "sensor_gain", seed=9)
        d = diagnose(runs, effects=["sensor_gain", "force_bias", "contact_damping"])
        assert d.verdict == "sensor_gain"
        assert d.selected_values["sensor_gain"]["gain"] == pytest.approx(1.06, abs=0.005)
        assert fit_effect(runs, "sensor_gain")["gain"] == pytest.approx(1.06, abs=0.005)
    finally:
        unregister_effect("sensor_gain")


def test_examples_of_the_nominal_rig_say_none():

    from hybridtable.measurement.run_reader import read_runs
    from tests.examples import EXAMPLES as folder

    d = diagnose(
        read_runs([folder]), effects=["contact_damping", "extra_delay", "force_bias", "mass_error"]
    )
    assert d.verdict == "none"


def test_the_count_of_model_runs_does_not_depend_on_the_processes():
    # a job run in this process counted its simulations twice (141 against 75)
    from hybridtable.measurement.run_reader import read_runs
    from tests.examples import EXAMPLES as folder

    runs = read_runs([folder])
    counts = [
        diagnose(runs, effects=["contact_damping", "extra_delay"], workers=w, separate=False)
        for w in (1, 2)
    ]
    assert counts[0].simulations == counts[1].simulations
    same = [json.dumps(d.to_json()["ranking"], sort_keys=True) for d in counts]
    assert same[0] == same[1]  # the same fits either way (NaN for the figures not computed)


# -- command line ----------------------------------------------------------------
def test_diagnose_command_json_report_and_errors(tmp_path, capsys):
    runs = _runs(tmp_path, "force_bias", seed=3)
    folder = runs[0].csv_path.parent
    out = tmp_path / "out.json"
    report = tmp_path / "report"
    rc = main(
        [
            "diagnose",
            str(folder),
            "--effects",
            "force_bias,contact_damping",
            "--json",
            str(out),
            "--report",
            str(report),
            "--no-progress",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "verdict: force_bias" in text
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "force_bias" and doc["selected"] == ["force_bias"]
    first = doc["ranking"][0]
    for key in (
        "effect",
        "parameters",
        "error_before",
        "error_after",
        "heldout_error_after",
        "delta_bic",
        "significant",
        "indistinguishable_from",
    ):
        assert key in first
    assert [s["effects"] for s in doc["staircase"]] == [[], ["force_bias"]]
    assert (report / "report.md").is_file() and (report / "staircase.png").is_file()
    assert len(list(report.glob("*_force_deflection.png"))) == 2
    # bad input: one line, exit 2
    assert main(["diagnose", str(folder), "--effects", "magic"]) == 2
    assert "unknown effect" in capsys.readouterr().err
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "keep.txt").write_text("mine")
    assert main(["diagnose", str(folder), "--report", str(tmp_path / "other")]) == 2
    assert (tmp_path / "other" / "keep.txt").read_text() == "mine"


def test_compare_add_shows_the_error_fall(tmp_path, capsys):
    runs = _runs(tmp_path, "contact_damping", seed=6)
    folder = str(runs[0].csv_path.parent)
    out = tmp_path / "cmp.json"
    assert (
        main(
            [
                "compare",
                folder,
                "--add",
                "contact_damping:damping_n_s_per_m=400",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "error fall with contact_damping" in text
    doc = json.loads(out.read_text())
    assert doc["added_effects"] == [
        {
            "effect": "contact_damping",
            "parameters": {"damping_n_s_per_m": 400.0},
            "std": {"damping_n_s_per_m": None},
            "units": {"damping_n_s_per_m": "N s/m"},
            "fitted": [],
        }
    ]
    for before, after in zip(doc["nominal_runs"], doc["runs"], strict=True):
        assert before["error_to_noise"]["f_mea_n"] > 3.0
        assert after["error_to_noise"]["f_mea_n"] < 1.15
    assert (
        main(
            [
                *("compare", folder, "--add", "contact_damping", "--json", str(out)),
                *("--no-progress", "--force"),
            ]
        )
        == 0
    )
    doc = json.loads(out.read_text())
    (added,) = doc["added_effects"]
    assert added["fitted"] == ["damping_n_s_per_m"]
    assert added["parameters"]["damping_n_s_per_m"] == pytest.approx(400, rel=0.05)
    # The standard error is honest: the truth within a few of them, and small.
    std = added["std"]["damping_n_s_per_m"]
    assert 0.0 < std < 40.0
    assert abs(added["parameters"]["damping_n_s_per_m"] - 400.0) < 5.0 * std + 2.0
    assert main(["compare", folder, "--add", "contact_damping:damping_n_s_per_m=-3"]) == 2
    assert "out of bounds" in capsys.readouterr().err


def test_runs_without_contact_are_refused(tmp_path):
    from hybridtable.errors import MeasurementError

    runs = _runs(tmp_path, "none", seed=1)
    r = runs[0]
    flat = Run(
        r.info,
        r.time_s,
        r.p_des_m,
        np.minimum(r.p_act_m, -1e-3),
        r.f_mea_n,
        r.f_comp_n,
        r.v_des_m_per_s,
    )
    with pytest.raises(MeasurementError, match="no contact"):
        prepare_runs([flat])


def test_noise_free_and_single_runs(tmp_path):
    """A noise-free record gets a numerical noise floor (no spurious effect
    below it); one run is diagnosed by the BIC alone."""
    kw = {"noise_f_n": 0.0, "noise_p_m": 0.0}
    none = diagnose(_runs(tmp_path, "none", **kw), effects=["contact_damping", "force_bias"])
    assert none.verdict == "none"
    assert any("no noise found" in n for n in none.data[0].notes)
    (run,) = _runs(tmp_path / "one", "contact_damping", seed=3)[:1]
    d = diagnose([run], effects=["contact_damping", "force_bias"])
    assert d.verdict == "contact_damping"
    assert math.isnan(d.ranking[0].heldout_z) and d.notes
