"""One run of a campaign (hybridtable.sweeps.runner): the engines agree, and
effects, a model file and the Stewart table reach the loop."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.loop.simulation import simulate
from hybridtable.sweeps.inputs import loop_params
from hybridtable.sweeps.runner import run_one
from hybridtable.sweeps.spec import parse_spec

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _spec(text: str, **kw):
    return parse_spec(tomllib.loads(text), **kw)


def test_auto_runs_the_paper_four_fast_and_the_plug_ins_on_the_diagram():
    spec = _spec(
        """
        compensators = ["none", "SDC", "MDC", "SDMDC", "polynomial"]
        metrics = ["cor", "energy_created"]
        """
    )
    rows = [run_one(spec, i) for i in range(spec.n_runs)]
    assert [r["engine"] for r in rows] == ["fast"] * 4 + ["diagram"]
    for r in rows:
        m = simulate(loop_params({"compensator": r["compensator"]})).metrics
        assert r["cor"] == pytest.approx(m.cor, abs=1e-6)
        assert r["energy_created"] == pytest.approx(m.energy_created, abs=1e-4)
    # without compensation the delay creates energy; SDMDC nearly none
    assert rows[0]["energy_created"] > 0.3 and rows[3]["energy_created"] < 0.02


def test_coulomb_friction_takes_energy_out_and_zero_friction_is_the_nominal_rig():
    spec = _spec(
        """
        metrics = ["cor"]
        [base]
        sample_rate_hz = 1000.0
        compensator = "SDMDC"
        [grid]
        "coulomb_friction.friction_force_n" = [0.0, 20.0, 50.0]
        """
    )
    rows = [run_one(spec, i) for i in range(3)]
    assert [r["status"] for r in rows] == ["ok"] * 3
    assert all(r["engine"] == "diagram" for r in rows)
    nominal = simulate(loop_params({"sample_rate_hz": 1000.0, "compensator": "SDMDC"})).metrics
    assert rows[0]["cor"] == pytest.approx(nominal.cor, abs=1e-6)
    # friction dissipates F times the path (in and out, ~2 peak deflections)
    assert rows[0]["cor"] > rows[1]["cor"] > rows[2]["cor"]
    p = loop_params({})
    d = p.initial_velocity_m_per_s * math.sqrt(p.spacecraft_mass_kg / p.contact_stiffness_n_per_m)
    ke = 0.5 * p.spacecraft_mass_kg * p.initial_velocity_m_per_s**2
    lost = 1.0 - (rows[2]["cor"] / rows[0]["cor"]) ** 2
    assert lost == pytest.approx(50.0 * 2 * d / ke, rel=0.3)


def test_an_effect_out_of_its_bounds_makes_its_run_invalid_not_the_campaign():
    spec = _spec(
        """
        [base]
        sample_rate_hz = 1000.0
        [grid]
        "coulomb_friction.friction_force_n" = [10.0, 1e6]
        """
    )
    ok, bad = run_one(spec, 0), run_one(spec, 1)
    assert ok["status"] == "ok" and bad["status"] == "invalid"
    assert "friction_force_n" in bad["message"]


@pytest.mark.parametrize(
    "text, words",
    [
        ('[base]\n"coulomb_friction.friction_force_n" = -1e400', "finite"),
        ('[base]\n"table_resonance.frequency_hz" = 40.0', "table_resonance.damping_ratio"),
        ('[base]\n"no_such_effect.x" = 1.0', "unknown parameter"),
        (
            '[base]\n"coulomb_friction.friction_force_n" = 5.0\ntable_backend = "stewart"',
            "stewart",
        ),
        ('engine = "fast"\n[base]\n"force_bias.bias_n" = 5.0', "fast"),
        ('metrics = ["stable"]\n[base]\n"force_bias.bias_n" = 5.0', "margin"),
        (
            '[base]\nsample_rate_hz = 1e3\nforce_noise_n = 1.0\n"force_bias.bias_n" = 5.0',
            "nominal rig only",
        ),
    ],
)
def test_effect_specs_that_cannot_run_are_refused(text, words):
    from hybridtable.errors import SpecError

    with pytest.raises(SpecError, match=words):
        _spec(text)


def test_the_stewart_table_gives_nearly_the_second_order_tables_cor():
    spec = _spec(
        """
        metrics = ["cor", "peak_force_n"]
        [base]
        compensator = "none"
        [grid]
        table_backend = ["second_order", "stewart"]
        """
    )
    second, stewart = run_one(spec, 0), run_one(spec, 1)
    assert stewart["status"] == "ok", stewart["message"]
    assert (second["engine"], stewart["engine"]) == ("fast", "diagram")
    # the platform is tuned to the same 25 Hz / 0.8 response
    assert stewart["cor"] == pytest.approx(second["cor"], abs=0.01)


def test_a_model_file_reaches_every_run(tmp_path):
    from hybridtable.effects.model_reader import load_model
    from hybridtable.studies.model_compensators import simulate_model

    model = tmp_path / "model.json"
    runs = EXAMPLES / "nominal"
    code = main(
        ["compare", str(runs), "--add", "contact_damping:damping_n_s_per_m=400"]
        + ["--save-model", str(model), "--json", str(tmp_path / "c.json")]
    )
    assert code in (0, 1) and model.exists()
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(
        'model = "model.json"\nmetrics = ["cor"]\ncompensators = ["none", "SDMDC"]\n'
        "[base]\nsample_rate_hz = 1000.0\n"
    )
    from hybridtable.sweeps.spec import load_spec

    spec = load_spec(spec_file)
    rows = [run_one(spec, i) for i in range(2)]
    rig = load_model(model)
    for r in rows:
        assert r["engine"] == "diagram"
        params = loop_params({"sample_rate_hz": 1000.0, "compensator": r["compensator"]})
        assert r["cor"] == simulate_model(rig, params).metrics.cor
    # the model's contact damping takes energy out of SDMDC's bounce
    nominal = simulate(loop_params({"sample_rate_hz": 1000.0, "compensator": "SDMDC"}))
    assert rows[1]["cor"] < nominal.metrics.cor - 0.01


def test_the_shipped_specs_hold_what_they_say():
    from hybridtable.compensators.registry import compensator_names
    from hybridtable.sweeps.spec import load_spec

    table2 = load_spec(EXAMPLES / "sweeps" / "table2.toml")
    assert table2.n_runs == 15 and table2.engine == "diagram"
    mc = load_spec(EXAMPLES / "sweeps" / "monte_carlo.toml")
    assert mc.n_runs == 5000 and mc.samples * len(compensator_names()) == 5000
    assert set(mc.swept) == {
        "compensator",
        "contact_stiffness_n_per_m",
        "sensor_delay_s",
        "initial_velocity_m_per_s",
    }
    # the first draw, with every compensator: each runs, on its engine
    rows = [run_one(mc, i) for i in range(len(compensator_names()))]
    assert [r["status"] for r in rows] == ["ok"] * len(rows), [r["message"] for r in rows]
    engines = {r["compensator"]: r["engine"] for r in rows}
    assert {c for c, e in engines.items() if e == "fast"} == {"none", "SDC", "MDC", "SDMDC"}
    assert len({r["contact_stiffness_n_per_m"] for r in rows}) == 1  # the same draw
