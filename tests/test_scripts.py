"""The scripts of ``diagrams/`` and ``analysis/`` run as a user runs them.

Each script is executed in its own process with ``--quick`` into a fresh
folder: it exits 0, prints a one-line verdict first, writes its outputs there,
and refuses (exit 2, one line) to run over them again without ``--force``. The
README lists every script.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted([*(ROOT / "diagrams").glob("*.py"), *(ROOT / "analysis").glob("*.py")])


def _run(script: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, str(script), "--quick", "--out", str(out), *extra],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_the_folders_hold_the_scripts_the_card_asks_for():
    """At least five diagram scripts and three analysis scripts, each listed
    in the README."""
    names = {p.parent.name: [] for p in SCRIPTS}
    for p in SCRIPTS:
        names[p.parent.name].append(p)
    assert len(names.get("diagrams", [])) >= 5
    assert len(names.get("analysis", [])) >= 3
    readme = (ROOT / "README.md").read_text()
    missing = [
        f"{p.parent.name}/{p.name}" for p in SCRIPTS if f"{p.parent.name}/{p.name}" not in readme
    ]
    assert not missing, f"the README does not list {missing}"


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_the_script_runs_and_keeps_what_it_wrote(script, tmp_path):
    out = tmp_path / "out"
    first = _run(script, out)
    assert first.returncode == 0, first.stderr[-2000:]
    lines = first.stdout.splitlines()
    assert lines and lines[0].strip(), "the first line is a verdict"
    written = [p for p in out.rglob("*") if p.is_file()]
    assert written, "it writes its outputs into --out"
    before = {p: p.stat().st_mtime_ns for p in written}
    again = _run(script, out)
    assert again.returncode == 2, again.stdout[-500:] + again.stderr[-500:]
    assert len(again.stderr.strip().splitlines()) == 1, again.stderr
    assert {p: p.stat().st_mtime_ns for p in written} == before, "nothing is replaced"
