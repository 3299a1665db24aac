"""Faults of a campaign: a diverging run is a row, SIGKILL and --resume give the
file an undisturbed campaign gives, Ctrl-C leaves a valid file."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from hybridtable.cli import main
from hybridtable.studies.paper import table2_rows

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "sweeps"

DIVERGING = """
name = "diverging"
engine = "{engine}"
metrics = ["cor", "peak_force_n"]

[base]
compensator = "MDC"
table_response_hz = 5.0

[grid]
compensator_stiffness_ratio = [1.0, 1000.0]
"""

# Slow enough (the Drake diagram, one worker) to be killed half way.
SLOW = """
name = "slow"
engine = "diagram"
compensators = ["none", "SDMDC"]
metrics = ["cor", "energy_gain_j"]

[grid]
sensor_delay_s = {start = 0.001, stop = 0.01, num = 12}
"""


def _rows(path: Path):
    return pq.read_table(path).drop_columns(["seconds"])


def test_a_diverging_run_is_a_row_and_the_campaign_goes_on(tmp_path, capsys):
    # an MDC that believes the contact 1000 times stiffer than it is, behind a
    # 5 Hz table, pushes with 1000 k times the table's lag: the force passes the
    # divergence bound within the contact; the true stiffness gives a bounce.
    for engine in ("diagram", "auto"):
        spec = tmp_path / f"{engine}.toml"
        spec.write_text(DIVERGING.format(engine=engine))
        out = tmp_path / f"{engine}.parquet"
        assert main(["sweep", str(spec), "--out", str(out), "--workers", "1"]) == 0
        text = capsys.readouterr().out
        assert text.splitlines()[0].startswith("sweep diverging: 1 of 2 runs finished")
        assert "1 diverged" in text.splitlines()[0]
        rows = pq.read_table(out).to_pylist()
        assert [r["status"] for r in rows] == ["ok", "diverged"]
        assert "diverged" in rows[1]["message"]
        assert math.isnan(rows[1]["cor"]) and 0.9 < rows[0]["cor"] < 1.1


def _campaign(spec: Path, out: Path, workers: int, **popen) -> subprocess.Popen:
    """``hybridtable sweep`` in a process of its own, with Ctrl-C's default action
    (a test process started in the background, or one whose earlier tests left
    SIGINT ignored, would pass that on, and Python would not turn it into
    KeyboardInterrupt)."""
    args = ["sweep", str(spec), "--out", str(out), "--workers", str(workers), "--no-progress"]
    return subprocess.Popen(
        [sys.executable, "-m", "hybridtable.cli", *args],
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        **popen,
    )


def _wait_for_rows(path: Path, proc: subprocess.Popen, at_least: int, timeout_s: float) -> int:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and proc.poll() is None:
        if path.exists():
            try:
                n = pq.read_metadata(path).num_rows
            except OSError:
                n = 0
            if n >= at_least:
                return n
        time.sleep(0.1)
    return 0


def test_sigkill_then_resume_gives_the_file_of_an_undisturbed_campaign(tmp_path):
    spec = tmp_path / "slow.toml"
    # 80 runs, about 7 s of them on one worker (2026-11-28): the first checkpoint
    # (every 2 s) comes half way; 24 runs took 2 s and could all be in it
    spec.write_text(SLOW.replace("num = 12", "num = 40"))
    n = 80
    out = tmp_path / "killed.parquet"
    proc = _campaign(
        spec,
        out,
        1,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        written = _wait_for_rows(out, proc, 1, 300)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert 0 < written < n, "the campaign was not caught half way"
    # what SIGKILL left is a valid Parquet file of finished runs
    partial = pq.read_table(out).to_pylist()
    assert 0 < len(partial) < n and all(r["status"] == "ok" for r in partial)
    assert (
        main(["sweep", str(spec), "--out", str(out), "--resume", "--workers", "2", "--no-progress"])
        == 0
    )
    whole = tmp_path / "whole.parquet"
    assert main(["sweep", str(spec), "--out", str(whole), "--workers", "2", "--no-progress"]) == 0
    assert repr(_rows(out).to_pylist()) == repr(_rows(whole).to_pylist())
    assert pq.read_schema(out).metadata == pq.read_schema(whole).metadata
    # the resumed file kept the finished runs as they were, timing included
    kept = {r["run"]: r["seconds"] for r in pq.read_table(out).to_pylist()}
    assert all(kept[r["run"]] == r["seconds"] for r in partial)


def test_ctrl_c_leaves_a_valid_file_of_the_finished_runs(tmp_path):
    """Ctrl-C in a terminal reaches the whole process group, the cluster's
    workers too: one line, exit 130, a valid file of the finished runs."""
    spec = tmp_path / "slow.toml"
    # 800 runs: the first checkpoint comes after a few seconds, far from the end even
    # on an idle machine (120 runs could all finish before the signal landed)
    spec.write_text(SLOW.replace("num = 12", "num = 400"))
    out = tmp_path / "stopped.parquet"
    proc = _campaign(
        spec,
        out,
        2,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        assert _wait_for_rows(out, proc, 1, 300)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert "--resume" in err.strip().splitlines()[-1]
    assert "Traceback" not in err
    table = pq.read_table(out)
    assert 0 < table.num_rows < 800
    assert table.column("run").to_pylist() == sorted(table.column("run").to_pylist())


def test_resume_refuses_another_specs_file(tmp_path, capsys):
    spec = tmp_path / "a.toml"
    spec.write_text(DIVERGING.format(engine="auto"))
    out = tmp_path / "a.parquet"
    assert main(["sweep", str(spec), "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    other = tmp_path / "b.toml"
    other.write_text(DIVERGING.format(engine="auto").replace("1000.0]", "100.0]"))
    capsys.readouterr()
    before = out.read_bytes()
    assert main(["sweep", str(other), "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "another spec" in err and err.count("\n") == 1
    assert out.read_bytes() == before
    # without --resume or --force an existing file is never replaced
    assert main(["sweep", str(spec), "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    # the spec is an input: never written over, even with --force
    text = spec.read_text()
    assert main(["sweep", str(spec), "--out", str(out), "--json", str(spec), "--force"]) == 2
    assert "input" in capsys.readouterr().err and spec.read_text() == text


def test_the_table2_spec_gives_reproduce_s_cors_exactly(tmp_path, table2_run):
    out = tmp_path / "table2.parquet"
    spec = EXAMPLES / "table2.toml"
    assert main(["sweep", str(spec), "--out", str(out), "--workers", "2", "--no-progress"]) == 0
    rows = pq.read_table(out).to_pylist()
    expected = [table2_run(i).metrics.cor for i in range(len(table2_rows()))]
    # bit for bit what `hybridtable reproduce` computes for each row
    assert [r["cor"] for r in rows] == expected
    assert [r["engine"] for r in rows] == ["diagram"] * 15


def test_in_process_gives_the_rows_of_a_cluster(tmp_path):
    import tomllib

    from hybridtable.sweeps.engine import run_campaign
    from hybridtable.sweeps.spec import parse_spec

    spec = parse_spec(tomllib.loads(DIVERGING.format(engine="auto")))
    here = run_campaign(spec, tmp_path / "here.parquet", in_process=True, progress=False)
    there = run_campaign(spec, None, workers=1, progress=False)
    assert there.path is None and not list(tmp_path.glob("there*"))
    # repr: NaN metrics of the diverged run compare equal
    drop = repr([{k: v for k, v in r.items() if k != "seconds"} for r in here.rows])
    assert drop == repr([{k: v for k, v in r.items() if k != "seconds"} for r in there.rows])
    assert repr(_rows(tmp_path / "here.parquet").to_pylist()) == drop
