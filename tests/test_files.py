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
