"""Every command in the README and docs runs as written, from a copy of the
repository with nothing beside it.

A fenced block marked ``sh`` is a command to run; synopses and printed output
are marked ``text``. A block marked ``python`` runs too, after the file's
``sh`` blocks (the file's ``python`` blocks in order, as one script, in the
same copy: a block may read what a command above it wrote); a piece of a
larger program that cannot run alone is marked ``python fragment``. The ``sh``
blocks of one file run in order, in one shell
(a variable set in one block is seen by the next), in a fresh copy of the
repository's files (``git ls-files``) whose parent holds nothing else, with the
project's ``.venv/bin`` first on ``PATH`` (in CI the copy is of a fresh clone
and ``.venv`` holds its editable install). ``make`` lines are skipped: the
targets are what CI runs itself. ``pip install`` goes into a folder of the
copy (``PIP_TARGET``, on ``PYTHONPATH``) without dependencies (``PIP_NO_DEPS``:
they are the project's, installed already), so the test environment is left
as it was.

Run with ``make test-docs`` (marker ``docs``; a few minutes).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.M | re.S)
INFO_FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```", re.M | re.S)


def doc_files() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def shell_blocks(path: Path) -> list[str]:
    """The ``sh`` blocks of ``path``, in order."""
    return [m.group(2) for m in FENCE.finditer(path.read_text()) if m.group(1) == "sh"]


def python_blocks(path: Path) -> list[str]:
    """The ``python`` blocks of ``path`` that run (not ``python fragment``), in order."""
    return [
        m.group(3)
        for m in INFO_FENCE.finditer(path.read_text())
        if m.group(1) == "python" and "fragment" not in m.group(2).split()
    ]


def _script(blocks: list[str]) -> str:
    lines = []
    for block in blocks:
        for line in block.splitlines():
            if line.lstrip().startswith("make "):
                continue
            lines.append(line)
    return "set -euo pipefail\nset -x\n" + "\n".join(lines) + "\n"


def _copy_repository(dest: Path) -> Path:
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split()
    repo = dest / "repo"
    for name in files:
        src = ROOT / name
        if src.is_file():
            target = repo / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, target)
    (repo / ".venv").symlink_to(Path(sys.prefix))
    return repo


def test_the_block_convention_is_kept():
    """A ``sh`` block holds commands only: no synopsis brackets, no output."""
    for path in doc_files():
        for block in shell_blocks(path):
            for line in block.splitlines():
                text = line.split("#", 1)[0]
                assert not re.search(r"\[--[a-z]", text), f"{path.name}: synopsis in sh: {line}"
                assert not text.startswith(("hybridtable: error", "wrote ")), (
                    f"{path.name}: output in an sh block: {line}"
                )


def test_no_document_or_file_needs_anything_beside_the_repository():
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split()
    offenders = []
    for name in files:
        path = ROOT / name
        if path.suffix not in {".py", ".md", ".toml", ".json", ".sh", ""} or not path.is_file():
            continue
        if name == "tests/test_docs.py":  # this test names what it looks for
            continue
        text = path.read_text(errors="replace")
        if "../shared" in text or "/work/shared" in text:
            offenders.append(name)
    assert offenders == [], f"files that point outside the repository: {offenders}"


def test_every_python_block_compiles():
    """A ``python`` block is Python (the run itself is ``make test-docs``'s)."""
    for path in doc_files():
        for block in python_blocks(path):
            compile(block, str(path), "exec")


@pytest.mark.docs
@pytest.mark.parametrize("doc", [p.name for p in doc_files()])
def test_every_shell_block_runs(doc, tmp_path):
    path = ROOT / doc if doc == "README.md" else ROOT / "docs" / doc
    blocks = shell_blocks(path)
    code = python_blocks(path)
    if not blocks and not code:
        pytest.skip(f"{doc} has no sh or python block")
    repo = _copy_repository(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["repo"]  # nothing beside it
    site = repo / "out" / "pip-target"
    env = {
        **os.environ,
        "PATH": f"{repo / '.venv' / 'bin'}:{os.environ['PATH']}",
        "MPLBACKEND": "Agg",
        "PIP_TARGET": str(site),
        "PYTHONPATH": str(site),
        "PIP_NO_DEPS": "1",
        "PIP_DISABLE_PIP_VERSION_CHECK": "1",
    }
    runs = [("a command", ["bash", "-c", _script(blocks)])] if blocks else []
    if code:
        script = repo / "out" / "doc_blocks.py"
        script.parent.mkdir(parents=True, exist_ok=True)
        script.write_text("\n".join(code))
        runs.append(("a python block", [str(repo / ".venv" / "bin" / "python"), str(script)]))
    for what, command in runs:
        result = subprocess.run(
            command, cwd=repo, env=env, capture_output=True, text=True, timeout=1800
        )
        assert result.returncode == 0, (
            f"{doc}: {what} failed (exit {result.returncode})\n"
            f"--- stderr (tail) ---\n{result.stderr[-4000:]}\n--- stdout (tail) ---\n"
            f"{result.stdout[-2000:]}"
        )
