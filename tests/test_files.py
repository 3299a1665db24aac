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
