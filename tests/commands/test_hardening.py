"""The newer surfaces on hostile input, through the command line: every
failure one line and a non-zero exit, or a sound result (issue 34's list)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from hybridtable.cli import main

ROOT = Path(__file__).resolve().parents[2]
TABLE2 = ROOT / "examples" / "sweeps" / "table2.toml"
OFFSET = ROOT / "examples" / "six_dof" / "offset.toml"


def _error(capsys, argv: list[str], code: int = 2) -> str:
    assert main(argv) == code
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0].split("error: ", 1)[1]


@pytest.fixture(scope="module")
def fast_spec(tmp_path_factory) -> Path:
    """Table 2 on the fast engine (15 runs, a few seconds)."""
    path = tmp_path_factory.mktemp("spec") / "table2.toml"
    path.write_text(TABLE2.read_text().replace('engine = "diagram"', 'engine = "fast"'))
    return path


def test_resume_runs_again_the_rows_it_cannot_trust(fast_spec, tmp_path, capsys):
    out = tmp_path / "t2.parquet"
    argv = ["sweep", str(fast_spec), "--out", str(out), "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    table = pq.read_table(out)
    rows = table.to_pylist()
    truth = {r["run"]: r["cor"] for r in rows}
    rows[3]["cor"] = math.nan  # "ok" with no number
    rows[5]["sensor_delay_s"] = 0.0123  # not the spec's draw
    rows[7]["status"] = "diverged"  # a failed run with numbers
    pq.write_table(pa.Table.from_pylist(rows, schema=table.schema), out)
    capsys.readouterr()
    assert main([*argv, "--resume", "--json", str(tmp_path / "r.json")]) == 0
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["resumed"] == 12
    assert sorted(r["run"] for r in doc["rerun"]) == [3, 5, 7]
    again = {r["run"]: r for r in pq.read_table(out).to_pylist()}
    assert all(again[i]["status"] == "ok" for i in (3, 5, 7))
    assert {i: again[i]["cor"] for i in truth} == truth  # the same numbers, re-run
    assert "ran 3 run(s) of the file again" in capsys.readouterr().out


def test_a_spec_too_large_or_too_deep_is_refused_before_parsing(tmp_path, capsys):
    big = tmp_path / "big.toml"
    big.write_text('name = "x"\n[grid]\nsensor_delay_s = [' + "0.001," * 900_000 + "0.001]\n")
    text = _error(capsys, ["sweep", str(big), "--out", str(tmp_path / "o.parquet")])
    assert "MiB, more than the 4 MiB" in text
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    assert "nested more than 32 deep" in _error(
        capsys, ["sweep", str(deep), "--out", str(tmp_path / "o.parquet")]
    )


def test_explain_refuses_more_distinct_rows_than_it_can_fit(tmp_path, capsys):
    table = tmp_path / "big.csv"
    rows = [f"none,{1.1 + 1e-5 * i:.5f},0.003,{0.05 + 1e-5 * i:.5f}" for i in range(1000)]
    table.write_text("compensator,cor,sensor_delay_s,initial_velocity_m_per_s\n" + "\n".join(rows))
    text = _error(capsys, ["explain", str(table)])
    assert "1000 rows of distinct conditions, more than the 200" in text


@pytest.mark.slow
def test_a_model_file_whose_computer_runs_no_compensator_is_refused(tmp_path, capsys):
    model = tmp_path / "m.json"
    nominal = str(ROOT / "examples" / "nominal")
    assert main(["diagnose", nominal, "--save-model", str(model), "--no-progress"]) == 0
    capsys.readouterr()
    doc = json.loads(model.read_text())
    doc["computer"] = {"compensator": "PID"}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    text = _error(capsys, ["margins", "--model", str(bad)])
    assert "computer.compensator must be one of none, SDC" in text and "'PID'" in text
    doc["computer"] = {}
    doc["nominal"]["spacecraft_mass_kg"] = 10**400
    bad.write_text(json.dumps(doc))
    text = _error(capsys, ["simulate", "--model", str(bad)])
    assert "nominal.spacecraft_mass_kg is an integer of 401 digits" in text
    doc = json.loads(model.read_text())
    doc["runs"][0]["cor_measured"] = -1.0
    bad.write_text(json.dumps(doc))
    text = _error(capsys, ["simulate", "--model", str(bad)])
    assert "runs[0]: cor_measured must be a number between 0 and 100" in text


def test_a_six_dof_misalignment_is_said_in_the_files_degrees(tmp_path, capsys):
    for value, words in (("[nan, 2.0]", "2 finite numbers"), ("[0.0, 100.0]", "within +-28.6 deg")):
        scenario = tmp_path / "s.toml"
        scenario.write_text(
            OFFSET.read_text().replace(
                "misalignment_deg = [0.0, 2.0]", f"misalignment_deg = {value}"
            )
        )
        text = _error(capsys, ["simulate6", str(scenario)])
        assert "[approach] misalignment_deg must be" in text and words in text
        assert "misalignment_rad" not in text


@pytest.mark.slow
def test_a_spinning_port_is_not_passed_off_as_a_bounce(tmp_path, capsys):
    """A body too light for its rig computer's tick: the loop in contact has a
    growing mode, and the CoR along the normal (the port's swing) says so."""
    scenario = tmp_path / "light.toml"
    scenario.write_text(
        OFFSET.read_text().replace(
            "inertia_kg_m2 = [1689.0, 1689.0, 1689.0]", "inertia_kg_m2 = [0.01, 0.01, 0.01]"
        )
    )
    out = tmp_path / "o.json"
    assert main(["simulate6", str(scenario), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["margins"]["stable"] is False
    assert doc["cor_normal"] > 10 and "the body's spin" in doc["note"]
    assert "note: cor_normal" in capsys.readouterr().out


def test_a_six_dof_given_stiffness_beyond_any_contact_is_refused(tmp_path, capsys):
    scenario = tmp_path / "stiff.toml"
    rows = ", ".join(
        "[" + ", ".join("1e30" if i == j else "0.0" for j in range(6)) + "]" for i in range(6)
    )
    scenario.write_text(
        OFFSET.read_text().replace(
            'stiffness_model = "linearized"',
            f'stiffness_model = "given"\nstiffness_matrix = [{rows}]',
        )
    )
    text = _error(capsys, ["simulate6", str(scenario)])
    assert "stiffness_matrix" in text and "at most 1e+10" in text and "got 1e+30" in text


def test_explain_runs_repeated_rows_once_and_reads_them_as_one_point(monkeypatch):
    from hybridtable.effects.registry import get_effect
    from hybridtable.explain import patterns
    from hybridtable.explain.model import CorModel, EffectAt, table_scale
    from hybridtable.explain.table import read_cor_table

    table = read_cor_table(ROOT / "examples" / "explain" / "table4_experiment_sdmdc.csv")
    cases = [(r.compensator, r.conditions) for r in table.rows]
    repeated = [c for c in cases for _ in range(50)]  # 400 rows, 8 conditions
    calls = []
    model = CorModel(())
    real = model._ln_cor
    monkeypatch.setattr(model, "_ln_cor", lambda c, v: calls.append(c) or real(c, v))
    once = model.predict_values(repeated, {})
    assert len(calls) == len(cases)
    np.testing.assert_array_equal(once, np.repeat(model.predict_values(cases, {}), 50))
    # the trends of the repeated table are the table's, its pairs naming first rows
    y = np.log([r.cor for r in table.rows])
    sigma = np.full(len(y), 0.01)
    effects = [EffectAt(get_effect("lead_time_error"), table_scale(cases))]
    alone = patterns.trends(cases, y, sigma, once[::50], effects)
    many = patterns.trends(
        repeated, np.repeat(y, 50), np.repeat(sigma, 50) * math.sqrt(50), once, effects
    )
    assert len(alone) == len(many) > 0
    for a, b in zip(alone, many, strict=True):
        np.testing.assert_allclose(a["measured_change"], b["measured_change"], rtol=1e-12)
        assert a["miss_sigma"] == pytest.approx(b["miss_sigma"], rel=1e-9)
    assert [t["pairs"] for t in many] == [[[50 * a, 50 * b] for a, b in t["pairs"]] for t in alone]
