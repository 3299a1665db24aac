"""The 6-DoF run reader through the command line, on runs the independent
generator ``tests/generators/run6_logs.py`` wrote from ``docs/run6-format.md``.

``hybridtable compare RUN.csv --json -`` (a subprocess, as a user runs it):
every bad run is refused with exit code 2 and one non-empty line on stderr
that names its defect, without a traceback; a good run is compared (exit 0,
a JSON object on stdout); a folder of two runs with one ``run_id`` is refused.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.generators import run6_logs as g

SMALL_NOISE = {
    "force_noise_n": 0.5,
    "moment_noise_n_m": 0.1,
    "position_noise_m": 1e-6,
    "attitude_noise_rad": 1e-6,
}


def compare(cwd: Path, *runs: str) -> subprocess.CompletedProcess:
    """``hybridtable compare RUNS... --json -`` in ``cwd``."""
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-m", "hybridtable.cli", "compare", *runs, "--json", "-"],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


def one_error_line(result: subprocess.CompletedProcess) -> str:
    """The refusal's single line, after checking the exit code and that there
    is no traceback."""
    detail = f"exit {result.returncode}\nstdout:\n{result.stdout[-2000:]}\nstderr:\n{result.stderr}"
    assert "Traceback" not in result.stderr, detail
    assert result.returncode == 2, detail
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, detail
    return lines[0]


@pytest.fixture(scope="module")
def rows():
    """The nominal scenario (10 mm offset, 2 deg pitch, 25 Hz table, 5 ms
    delay, no compensator) with a little measurement noise."""
    return g.generate_run6(g.scenario(), seed=7, **SMALL_NOISE)


@pytest.fixture(scope="module")
def long_approach():
    """The nominal scenario from 20 mm: 200 ms of free flight before the touch."""
    scen = g.scenario(**{"approach.initial_gap_m": 0.02})
    return scen, g.generate_run6(scen, seed=8, **SMALL_NOISE)


@pytest.mark.parametrize("kind", g.CORRUPTIONS)
def test_a_bad_run_is_one_line_naming_its_defect(tmp_path, rows, long_approach, kind):
    scen, data = long_approach if kind == "no_contact" else (g.scenario(), rows)
    _, _, words = g.write_corrupt_run6(tmp_path, "run1", scen, data, kind)
    line = one_error_line(compare(tmp_path, "run1.csv"))
    assert g.message_names(line, words), f"{kind}: {line!r} does not name {words}"


def test_a_good_run_is_compared(tmp_path, rows):
    g.write_run6(tmp_path, "run1", g.scenario(), rows, run_id="offset-1")
    result = compare(tmp_path, "run1.csv")
    detail = f"exit {result.returncode}\nstderr:\n{result.stderr[-4000:]}"
    assert "Traceback" not in result.stderr, detail
    assert result.returncode == 0, detail
    assert isinstance(json.loads(result.stdout), dict)


def test_two_runs_with_one_run_id_are_refused(tmp_path, rows):
    scen = g.scenario()
    g.write_run6(tmp_path / "runs", "run_a", scen, rows, run_id="same")
    g.write_run6(tmp_path / "runs", "run_b", scen, rows, run_id="same")
    line = one_error_line(compare(tmp_path, "runs"))
    assert "run_id" in line.lower()
