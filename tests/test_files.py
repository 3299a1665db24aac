"""The atomic write: the whole text or the old file, and the permissions a
plain ``open()`` would give."""

from __future__ import annotations

import os
import stat

from hybridtable._files import write_text_atomic


def test_atomic_write_replaces_whole_and_keeps_umask_permissions(tmp_path):
    target = tmp_path / "sub" / "out.json"
    write_text_atomic(target, "first\n")
    write_text_atomic(target, "second\n")
    assert target.read_text() == "second\n"
    assert [p.name for p in target.parent.iterdir()] == ["out.json"]  # no temporary left
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~mask


def test_an_interrupted_atomic_write_leaves_the_old_file_and_no_temporary(tmp_path):
    import pytest

    from hybridtable._files import atomic_path

    target = tmp_path / "fig.png"
    target.write_bytes(b"old")
    with pytest.raises(KeyboardInterrupt), atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".png"
        tmp.write_bytes(b"half")
        raise KeyboardInterrupt
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["fig.png"]


def test_a_staged_folder_appears_whole_or_not_at_all(tmp_path):
    import pytest

    from hybridtable._files import staged_folder

    # A new folder: nothing until the block ends, then everything.
    with staged_folder(tmp_path / "report") as stage:
        (stage.path / "report.md").write_text("# r\n")
        (stage.path / "figs").mkdir()
        (stage.path / "figs" / "a.png").write_bytes(b"png")
        assert not (tmp_path / "report").exists()
        assert stage.final(stage.path / "figs" / "a.png") == tmp_path / "report" / "figs" / "a.png"
    assert (tmp_path / "report" / "figs" / "a.png").read_bytes() == b"png"
    # An existing folder: same names replaced, the user's other files kept.
    (tmp_path / "report" / "notes.txt").write_text("mine")
    with staged_folder(tmp_path / "report") as stage:
        (stage.path / "report.md").write_text("# new\n")
    assert (tmp_path / "report" / "report.md").read_text() == "# new\n"
    assert (tmp_path / "report" / "notes.txt").read_text() == "mine"
    # Interrupted: the folder as it was, no staging folder left.
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path / "report") as stage:
        (stage.path / "report.md").write_text("# half")
        raise KeyboardInterrupt
    assert (tmp_path / "report" / "report.md").read_text() == "# new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_writable_problem_names_a_parent_that_is_a_file(tmp_path):
    from hybridtable._files import writable_problem

    (tmp_path / "afile").write_text("x")
    assert (
        writable_problem(tmp_path / "afile" / "out.json")
        == f"{tmp_path / 'afile'} is a file, not a folder"
    )
    assert writable_problem(tmp_path / "new" / "deeper" / "out.json") is None
    assert writable_problem(tmp_path / "afile" / "rep", folder=True).endswith(
        "is a file, not a folder"
    )


# -- what a user's file may be, and what a failed write leaves -------------------

import json as _json  # noqa: E402
import resource  # noqa: E402
import signal  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import pytest  # noqa: E402

from hybridtable._files import (  # noqa: E402
    MAX_NESTING,
    atomic_path,
    command_outputs,
    keep_output,
    overwrite_policy,
    read_user_json,
    read_user_toml,
)
from hybridtable.errors import SpecError, WriteError  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def test_a_file_too_large_is_refused_before_it_is_read(tmp_path):
    big = tmp_path / "spec.toml"
    big.write_text("x = [" + "1," * 600_000 + "1]\n")
    with pytest.raises(SpecError, match=r"spec.toml: 1\.\d MiB, more than the 1 MiB"):
        read_user_toml(big, SpecError, max_bytes=2**20)


@pytest.mark.parametrize("depth", [MAX_NESTING + 1, 5000])
def test_nesting_deeper_than_the_limit_is_one_line(tmp_path, depth):
    toml = tmp_path / "deep.toml"
    toml.write_text("a = " + "[" * depth + "]" * depth + "\n")
    with pytest.raises(SpecError, match="nest"):
        read_user_toml(toml, SpecError)
    doc = tmp_path / "deep.json"
    doc.write_text("[" * depth + "]" * depth)
    with pytest.raises(ValueError, match="nest"):
        read_user_json(doc)
    shallow = tmp_path / "ok.json"
    shallow.write_text("[" * MAX_NESTING + "]" * MAX_NESTING)
    assert read_user_json(shallow) is not None


def test_an_integer_no_float_can_hold_names_its_key(tmp_path):
    doc = tmp_path / "model.json"
    doc.write_text(_json.dumps({"nominal": {"spacecraft_mass_kg": 10**400}}))
    with pytest.raises(ValueError, match=r"nominal\.spacecraft_mass_kg is an integer of 401"):
        read_user_json(doc)


def test_without_force_a_new_output_never_replaces_one_written_meanwhile(tmp_path):
    target = tmp_path / "out.json"
    with overwrite_policy(False):
        with pytest.raises(WriteError, match="exists now"):
            with atomic_path(target) as tmp:
                tmp.write_text("mine")
                target.write_text("the other process's")  # written while we wrote
    assert target.read_text() == "the other process's"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]
    with overwrite_policy(True):  # --force: replaced
        with atomic_path(target) as tmp:
            tmp.write_text("mine")
    assert target.read_text() == "mine"


def _small_disk():
    """In the child: writes beyond 64 kB fail (EFBIG), as on a full disk."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (64_000, 64_000))


def _on_a_small_disk(folder: Path, argv: list[str]) -> str:
    """Run the command in ``folder`` on a 64 kB "disk"; it must fail (exit 1) with
    one line and no traceback: that line."""
    done = subprocess.run(
        [sys.executable, "-m", "hybridtable.cli", *argv],
        cwd=folder,
        capture_output=True,
        text=True,
        preexec_fn=_small_disk,
        timeout=600,
        env={**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"},
    )
    lines = [line for line in done.stderr.splitlines() if "error:" in line]
    assert done.returncode == 1, done.stderr[-2000:]
    assert len(lines) == 1 and "Traceback" not in done.stderr
    return lines[0]


@pytest.mark.slow
@pytest.mark.parametrize(
    "argv, output",
    [
        (["simulate", "--plot", "fig.png"], "fig.png"),
        (["simulate", "--record", "runs", "--sample-rate-hz", "1000"], "runs"),
        (["margins", "--report", "report", "--no-progress"], "report"),
    ],
)
def test_a_full_disk_is_one_line_and_leaves_nothing(tmp_path, argv, output):
    line = _on_a_small_disk(tmp_path, argv)
    assert f"could not write {output}" in line and "nothing of it was written" in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_command_whose_later_output_fails_removes_its_earlier_ones(tmp_path):
    """All of a command's new outputs or none: the JSON written before the plot
    that filled the disk goes too, and the line says so."""
    line = _on_a_small_disk(tmp_path, ["simulate", "--json", "out.json", "--plot", "fig.png"])
    assert "could not write fig.png" in line
    assert "other new outputs were removed: out.json" in line
    assert list(tmp_path.iterdir()) == []


def test_command_outputs_keeps_what_it_replaced_and_what_it_is_told_to_keep(tmp_path):
    old, new, kept = tmp_path / "old.json", tmp_path / "new.json", tmp_path / "rows.parquet"
    old.write_text("before")
    with pytest.raises(RuntimeError, match="new outputs were removed: .*new.json"):
        with overwrite_policy(True), command_outputs():
            write_text_atomic(old, "replaced")
            write_text_atomic(new, "new")
            write_text_atomic(kept, "rows")
            keep_output(kept)
            raise RuntimeError("the next step failed")
    assert old.read_text() == "replaced" and kept.exists() and not new.exists()
