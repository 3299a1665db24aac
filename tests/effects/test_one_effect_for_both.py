"""One user effect, written once, is a candidate of both ``diagnose`` and ``explain``.

Through the command line (``hybridtable.cli.main`` in-process), with the user's
plug-in ``tests/effects/plugins/table_lag.py`` (the table lags ``r`` times as
long as stated: its response frequency over ``r``; ``default_for`` left at its
default) and the worked example ``examples/plugins/backlash.py`` (a Drake
system wrapped around the table):

- ``effects`` lists ``table_lag`` once, tried by both front ends, its CoR run
  by the fast engine; ``backlash``'s CoR by the Drake diagram;
- ``explain`` (no ``--effects``) fits ``table_lag`` to a CoR table of the
  independent generator ``tests/generators/cortable.py`` whose true table
  responds at 15 Hz where 25 Hz is stated: the lag ratio 25/15, as good as
  the built-in ``table_response`` (the same law under another parameter);
- ``diagnose`` (no ``--effects``) tries ``table_lag`` in its first round on runs
  of ``tests/generators/effectsim.py`` whose table is 1.5 times slower than
  their JSON states, and names it with the ratio 1.5;
- ``explain`` fits ``backlash`` through the Drake diagram: while the devices
  touch the play stays taken up, so its CoRs are the stated loop's.

The registry is reset to the built-ins around every command, so that the
plug-ins' names are free for each.
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.effects import registry
from hybridtable.effects.library import BUILTIN_EFFECTS
from tests.explain.conftest import TWO_FREQUENCIES, generated_table
from tests.generators.effectsim import simulate_hidden
from tests.generators.rigsim import NOMINAL, write_run

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: The user's effect, as a user gives it: ``--plugin path/to/table_lag.py:EFFECT``.
TABLE_LAG = f"{HERE / 'plugins' / 'table_lag.py'}:EFFECT"
#: The worked example of docs/plugins.md.
BACKLASH = f"{ROOT / 'examples' / 'plugins' / 'backlash.py'}:EFFECT"

#: The CoR table's stated table response (the paper's Table 1) and the true one, Hz.
STATED_TABLE_HZ = 25.0
TRUE_TABLE_HZ = 15.0
#: The recorded runs' true table lag over the one their JSON states.
TRUE_LAG_RATIO = 1.5
#: (approach velocity m/s, compensator) of the recorded runs (as tests/diagnosis).
RUN_PLAN = ((0.06, "SDMDC"), (0.10, "none"))


@dataclass
class CliRun:
    code: int
    out: str
    err: str
    doc: dict | list | None


@contextmanager
def _builtins_only() -> Iterator[None]:
    """The registry with the built-ins only, entry points not loaded again."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(registry, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})
        mp.setattr(registry, "_entry_points_loaded", True)
        mp.setattr(registry, "_ENTRY_POINT_FILES", {})
        yield


def _cli(json_path: Path, *argv: str) -> CliRun:
    """``hybridtable argv... --json json_path`` in this process, on the built-ins."""
    out, err = io.StringIO(), io.StringIO()
    with _builtins_only(), redirect_stdout(out), redirect_stderr(err):
        code = main([*argv, "--json", str(json_path)])
    doc = json.loads(json_path.read_text(encoding="utf-8")) if json_path.exists() else None
    return CliRun(code, out.getvalue(), err.getvalue(), doc)


def _model(doc: dict, effects: list[str]) -> dict:
    found = [m for m in doc["models"] if m["effects"] == effects]
    assert found, f"no model {effects} among {[m['name'] for m in doc['models']]}"
    return found[0]


# -- hybridtable effects ----------------------------------------------------------------
@pytest.fixture(scope="module")
def listed(tmp_path_factory) -> CliRun:
    folder = tmp_path_factory.mktemp("effects")
    return _cli(folder / "effects.json", "effects", "--plugin", TABLE_LAG, "--plugin", BACKLASH)


def test_effects_lists_table_lag_once_for_both_front_ends(listed):
    assert listed.code == 0, listed.err
    (item,) = [e for e in listed.doc["effects"] if e["name"] == "table_lag"]
    assert item["source"] == "plug-in"
    assert item["default_for"] == ["diagnose", "explain"]
    assert item["cor_engine"] == "fast engine"  # a change of the loop's parameters
    assert item["stage"] == "replay"
    assert item["touches"] == ["table.lag"]
    (p,) = item["parameters"]
    assert (p["name"], p["unit"], p["lower"], p["upper"]) == ("table_lag_ratio", "1", 0.2, 5.0)
    assert (p["null"], p["typical"]) == (1.0, 0.1)


def test_effects_runs_backlash_through_the_drake_diagram(listed):
    assert listed.code == 0, listed.err
    (item,) = [e for e in listed.doc["effects"] if e["name"] == "backlash"]
    assert item["source"] == "plug-in"
    assert item["cor_engine"] == "Drake diagram"  # a user's wrapped system


# -- explain: a table whose true table responds at 15 Hz, stated 25 Hz ------------------
@pytest.fixture(scope="module")
def slow_table(tmp_path_factory) -> CliRun:
    folder = tmp_path_factory.mktemp("slow_table")
    generated_table(
        folder,
        "slow_table",
        TWO_FREQUENCIES,
        hidden={"table_response": {"table_response_hz": TRUE_TABLE_HZ}},
    )
    table = folder / "slow_table.csv"
    return _cli(
        folder / "explain.json",
        "explain",
        str(table),
        "--plugin",
        TABLE_LAG,
        "--max-effects",
        "1",
        "--no-progress",
    )


@pytest.mark.slow
def test_explain_fits_the_plugin_by_default_with_the_true_lag_ratio(slow_table):
    assert slow_table.code == 0, slow_table.err
    doc = slow_table.doc
    lag = _model(doc, ["table_lag"])
    assert lag["values"]["table_lag_ratio"] == pytest.approx(
        STATED_TABLE_HZ / TRUE_TABLE_HZ, rel=0.05
    )
    assert doc["models"][0]["name"] == lag["name"] or lag["name"] in doc["lookalikes"], (
        doc["models"][0]["name"],
        doc["lookalikes"],
    )


@pytest.mark.slow
def test_explain_finds_table_lag_and_table_response_the_same_law(slow_table):
    # One law declared twice (lag ratio r, response ratio 1 / r) gives the same CoRs.
    assert slow_table.code == 0, slow_table.err
    lag = _model(slow_table.doc, ["table_lag"])
    response = _model(slow_table.doc, ["table_response"])
    assert abs(lag["bic"] - response["bic"]) <= 0.1, (lag["bic"], response["bic"])
    product = lag["values"]["table_lag_ratio"] * response["values"]["table_response_ratio"]
    assert product == pytest.approx(1.0, rel=1e-3)


# -- diagnose: runs whose table is 1.5 times slower than their JSON states ---------------
@pytest.fixture(scope="module")
def slow_runs(tmp_path_factory) -> CliRun:
    folder = tmp_path_factory.mktemp("slow_runs")
    runs = folder / "runs"
    for i, (v0, compensator) in enumerate(RUN_PLAN):
        stated = dict(
            NOMINAL,
            run_id=f"table-lag-{i}",
            initial_velocity_m_per_s=v0,
            compensator=compensator,
        )
        true = dict(
            stated,
            table_natural_frequency_hz=NOMINAL["table_natural_frequency_hz"] / TRUE_LAG_RATIO,
        )
        cols = simulate_hidden(true, "none", duration_s=0.55, seed=500 + i)
        write_run(runs, stated["run_id"], stated, cols)
    return _cli(
        folder / "diagnosis.json",
        "diagnose",
        str(runs),
        "--plugin",
        TABLE_LAG,
        "--no-progress",
    )


@pytest.mark.slow
def test_diagnose_tries_the_plugin_by_default(slow_runs):
    assert slow_runs.code == 0, slow_runs.err
    first_round = [c["effect"] for c in slow_runs.doc["rounds"][0]]
    assert "table_lag" in first_round, first_round


@pytest.mark.slow
def test_diagnose_names_table_lag_with_the_true_ratio(slow_runs):
    assert slow_runs.code == 0, slow_runs.err
    doc = slow_runs.doc
    assert doc["verdict"] == "table_lag", doc["verdict"]
    assert doc["explained"] is True
    ratio = doc["parameters"]["table_lag"]["table_lag_ratio"]
    assert ratio == pytest.approx(TRUE_LAG_RATIO, rel=0.1)
    assert "table_lag" in slow_runs.out.splitlines()[0]  # the console's opening sentence


# -- explain: backlash, through the Drake diagram -----------------------------------------
@pytest.fixture(scope="module")
def backlash_table(tmp_path_factory) -> CliRun:
    # One stated condition, two compensators, 1 kHz: each CoR of backlash runs the
    # Drake diagram (about 0.1 s a row).
    folder = tmp_path_factory.mktemp("backlash_table")
    generated_table(folder, "nominal", ({},), compensators=("none", "SDC"))
    return _cli(
        folder / "explain.json",
        "explain",
        str(folder / "nominal.csv"),
        "--plugin",
        BACKLASH,
        "--effects",
        "backlash,extra_delay",
        "--max-effects",
        "1",
        "--no-progress",
    )


@pytest.mark.slow
def test_explain_backlash_gives_the_stated_loops_cor(backlash_table):
    # While the devices touch, the play stays taken up and the force is the
    # nominal one: the CoR is the stated loop's.
    assert backlash_table.code == 0, backlash_table.err
    doc = backlash_table.doc
    backlash = _model(doc, ["backlash"])
    stated = _model(doc, [])
    assert len(backlash["predicted_cor"]) == len(stated["predicted_cor"]) == 2
    for got, want in zip(backlash["predicted_cor"], stated["predicted_cor"], strict=True):
        assert math.isfinite(got)
        assert got == pytest.approx(want, abs=1e-4)


def test_a_worker_pool_hands_its_shared_inputs_to_every_job_and_lets_go():
    from hybridtable.effects import workers

    def boom(shared, job):
        if job == 2:
            raise RuntimeError("job 2")
        return shared["k"] * job

    assert workers.pool_map(_scaled, [1, 2, 3], 2, shared={"k": 10}) == [10, 20, 30]
    with pytest.raises(RuntimeError):
        workers.pool_map(boom, [1, 2, 3], 1, shared={"k": 10})
    assert workers._SHARED == []


def _scaled(shared, job):
    return shared["k"] * job
