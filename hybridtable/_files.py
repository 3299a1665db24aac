"""Writing files so that nothing is lost or left half-written (the ground floor).

Every output of every command goes through here:

- :func:`write_text_atomic` / :func:`write_bytes_atomic` / :func:`atomic_path`
  write a file through a temporary file in the target's folder and a rename:
  an error or an interruption (Ctrl-C) leaves the old file, if any, in place
  and no temporary file behind;
- :func:`staged_folder` writes a folder of outputs (a report, a set of
  recorded runs) into a hidden staging folder beside it and moves the files
  in only when all are written: an interrupted report leaves the target
  folder as it was;
- :func:`writable_problem` says, before any work, why a path cannot be
  written (a parent that is a file, a read-only folder);
- a write that fails (a full disk) is a :class:`~hybridtable.errors.WriteError`
  naming the output, and leaves nothing of it; without ``--force``
  (:func:`overwrite_policy`) a finished file appears only where none is, in
  one step (two processes writing one output: one of them fails).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from hybridtable.errors import WriteError

__all__ = [
    "overwrite_policy",
    "command_outputs",
    "keep_output",
    "write_text_atomic",
    "write_bytes_atomic",
    "atomic_path",
    "staged_folder",
    "Staging",
    "writable_problem",
    "regular_file_problem",
    "read_user_text",
    "read_user_json",
    "read_user_toml",
    "check_document",
    "MAX_TEXT_BYTES",
    "MAX_TOML_BYTES",
    "MAX_NESTING",
]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: Whether an output may replace an existing file: the command's ``--force``
#: (:func:`overwrite_policy`); a program using the library replaces.
_REPLACE: list[bool] = [True]


@contextlib.contextmanager
def overwrite_policy(replace: bool) -> Iterator[None]:
    """Within the block, :func:`atomic_path` (and every writer on it) replaces
    an existing file only if ``replace``: otherwise the file appears only if
    none is there when it is complete (a hard link: the check and the write
    are one step, so of two processes writing the same new output, one fails
    with a :class:`~hybridtable.errors.WriteError` instead of replacing the
    other's)."""
    _REPLACE.append(bool(replace))
    try:
        yield
    finally:
        _REPLACE.pop()


#: The outputs the running command created (none was there before), innermost
#: :func:`command_outputs` last; None outside one.
_CREATED: list[list[Path] | None] = [None]


def _created(target: Path) -> None:
    if _CREATED[-1] is not None:
        _CREATED[-1].append(target)


def keep_output(path: str | Path) -> None:
    """Keep ``path`` even if its command fails later (a campaign's results, which
    ``--resume`` continues)."""
    if _CREATED[-1] is not None:
        _CREATED[-1][:] = [p for p in _CREATED[-1] if p != Path(path)]


@contextlib.contextmanager
def command_outputs() -> Iterator[None]:
    """One command's outputs are all written or none is new: when the block raises,
    the outputs it created (where none was before) are removed, and the error
    names them. An output that replaced a file (``--force``) stays replaced."""
    _CREATED.append([])
    try:
        yield
    except BaseException as err:
        removed = []
        for path in reversed(_CREATED[-1]):
            try:
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                else:
                    path.unlink()
                removed.append(str(path))
            except OSError:
                pass
        if removed and err.args and isinstance(err.args[0], str):
            err.args = (
                f"{err.args[0]}; the command's other new outputs were removed: "
                f"{', '.join(reversed(removed))}",
                *err.args[1:],
            )
        raise
    finally:
        _CREATED.pop()


def _write_failed(target: Path, err: OSError | WriteError) -> WriteError:
    if isinstance(err, WriteError):  # a file of a staged folder: said as the folder
        why = err.why
    else:
        why = err.strerror or " ".join(str(err).split())
    out = WriteError(f"could not write {target}: {why}; nothing of it was written")
    out.why = why
    return out


def _publish(tmp: str, target: Path, replace: bool) -> None:
    """Move the finished ``tmp`` to ``target``: replacing, or only if no file is there."""
    if replace:
        existed = os.path.lexists(target)
        os.replace(tmp, target)
        if not existed:
            _created(target)
        return
    try:
        os.link(tmp, target)
    except FileExistsError:
        raise WriteError(
            f"{target} exists now (another process wrote it meanwhile?); nothing was "
            "written: give --force to replace it"
        ) from None
    except OSError:  # a file system without hard links: check, then rename
        if os.path.lexists(target):
            raise WriteError(f"{target} exists now; nothing was written") from None
        os.replace(tmp, target)
    _created(target)


@contextlib.contextmanager
def atomic_path(path: str | Path, replace: bool | None = None) -> Iterator[Path]:
    """A temporary path (same folder, same suffix) to write ``path``'s content
    to; moved onto ``path`` when the block ends without error, removed
    otherwise. Creates the folder.

    ``replace``: whether an existing ``path`` is replaced (default: the
    :func:`overwrite_policy`). A write that fails (a full disk) raises a
    :class:`~hybridtable.errors.WriteError` naming ``path``, and leaves
    nothing of it."""
    target = Path(path)
    replace = _REPLACE[-1] if replace is None else replace
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=target.suffix, dir=target.parent
        )
        os.close(fd)
    except OSError as err:
        raise _write_failed(target, err) from None
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # as open() would, not mkstemp's 0600
        _publish(tmp, target, replace)
    except OSError as err:  # a full disk, a quota, a file too large
        raise _write_failed(target, err) from None
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text_atomic(path: str | Path, text: str, replace: bool | None = None) -> None:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically,
    creating its folder (``replace``: as :func:`atomic_path`)."""
    with atomic_path(path, replace) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(text)


def write_bytes_atomic(path: str | Path, data: bytes, replace: bool | None = None) -> None:
    """Write ``data`` to ``path`` atomically, creating its folder (``replace``:
    as :func:`atomic_path`)."""
    with atomic_path(path, replace) as tmp:
        tmp.write_bytes(data)


class Staging:
    """A staging folder (:attr:`path`) of the outputs bound for :attr:`target`."""

    def __init__(self, path: Path, target: Path) -> None:
        self.path = path
        self.target = target

    def final(self, staged: str | Path) -> Path:
        """Where a file written under :attr:`path` ends up under :attr:`target`."""
        return self.target / Path(staged).relative_to(self.path)


@contextlib.contextmanager
def staged_folder(path: str | Path) -> Iterator[Staging]:
    """A :class:`Staging` folder to write the outputs of folder ``path`` into.

    When the block ends without error, a new ``path`` is the staging folder
    renamed; an existing one receives the staged files (same names replaced,
    others kept). On an error or an interruption the staging folder is
    removed and ``path`` is left as it was.
    """
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
    except OSError as err:
        raise _write_failed(target, err) from None
    try:
        yield Staging(stage, target)
        os.chmod(stage, 0o777 & ~_umask())
        if not target.exists():
            os.replace(stage, target)
            _created(target)
            return
        for src in sorted(stage.rglob("*")):
            dst = target / src.relative_to(stage)
            if src.is_dir():
                dst.mkdir(exist_ok=True)
            else:
                dst.parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, dst)
    except (OSError, WriteError) as err:  # a full disk while the outputs were written
        if isinstance(err, WriteError) and not hasattr(err, "why"):
            raise  # another process's output, not a failed write
        raise _write_failed(target, err) from None
    finally:
        if stage.exists():
            shutil.rmtree(stage, ignore_errors=True)


def regular_file_problem(path: str | Path) -> str | None:
    """Why ``path`` is not a regular file to read, in words ("no such file", "a
    FIFO", "a device", "a folder"), or ``None``. Reading a FIFO or a device would
    block or never end, so a reader asks this first."""
    p = Path(path)
    try:
        mode = p.stat().st_mode
    except FileNotFoundError:
        return "no such file" if not p.is_symlink() else "a broken link"
    except OSError as err:
        return f"cannot read it ({err.strerror})"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder, not a file"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe), not a file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device, not a file"
    if stat.S_ISSOCK(mode):
        return "a socket, not a file"
    return "not a regular file"


def _exists(path: Path) -> bool | None:
    """True/False, or None when the system will not say (no permission)."""
    try:
        path.lstat()
    except FileNotFoundError:
        return False
    except NotADirectoryError:
        return False
    except OSError:
        return None
    return True


#: The largest text file a user may give (a run's CSV is read by
#: :mod:`hybridtable.measurement.csv_fast` instead): 64 MiB.
MAX_TEXT_BYTES = 64 * 2**20

#: The largest scenario, sweep spec or other TOML file: 4 MiB (a hundred
#: thousand listed values; a spec draws its values, it does not list millions).
MAX_TOML_BYTES = 4 * 2**20

#: The deepest nesting of tables and arrays a TOML or JSON file may have.
MAX_NESTING = 32


def read_user_text(
    path: str | Path, error: type[Exception] = ValueError, max_bytes: int = MAX_TEXT_BYTES
) -> str:
    """The UTF-8 text (a BOM allowed) of a file a user gave, or ``error`` with
    one line naming it: not a regular file (a FIFO or device would block or
    never end), larger than ``max_bytes`` (checked before reading),
    unreadable, or not UTF-8 (the byte that is not)."""
    path = Path(path)
    problem = regular_file_problem(path)
    if problem:
        raise error(f"{path}: {problem}")
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise error(
                f"{path}: {size / 2**20:.1f} MiB, more than the {max_bytes / 2**20:g} MiB "
                "such a file may have"
            )
        with path.open("rb") as f:  # at most max_bytes, should it grow meanwhile
            data = f.read(max_bytes + 1)
        if len(data) > max_bytes:
            raise error(f"{path}: more than the {max_bytes / 2**20:g} MiB such a file may have")
    except OSError as err:
        raise error(f"{path}: cannot read ({err.strerror})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise error(
            f"{path}: not a UTF-8 text file (byte {err.start}: {data[err.start]:#04x})"
        ) from None


def read_user_json(
    path: str | Path, error: type[Exception] = ValueError, max_bytes: int = MAX_TEXT_BYTES
) -> object:
    """The JSON value of a file a user gave (:func:`read_user_text`), or
    ``error`` with one line: empty, not valid JSON (its line and column), or
    not a document a number can be read from (:func:`check_document`)."""
    text = read_user_text(path, error, max_bytes)
    if not text.strip():
        raise error(f"{path}: empty file")
    try:
        value = json.loads(text)
    except json.JSONDecodeError as err:
        raise error(
            f"{path} line {err.lineno}, column {err.colno}: not valid JSON ({err.msg})"
        ) from None
    except RecursionError:
        raise error(f"{path}: nested more than {MAX_NESTING} deep") from None
    return check_document(value, path, error)


def read_user_toml(
    path: str | Path, error: type[Exception] = ValueError, max_bytes: int = MAX_TOML_BYTES
) -> dict:
    """The parsed TOML of a file a user gave (:func:`read_user_text`, at most
    ``max_bytes``), or ``error`` with one line: not valid TOML, or not a
    document a number can be read from (:func:`check_document`)."""
    import tomllib

    text = read_user_text(path, error, max_bytes)
    try:
        value = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise error(f"{path}: not valid TOML ({err})") from None
    except RecursionError:
        raise error(f"{path}: nested more than {MAX_NESTING} deep") from None
    return check_document(value, path, error)


def check_document(value: object, path: str | Path, error: type[Exception] = ValueError):
    """``value`` (a parsed JSON or TOML document) if it nests at most
    :data:`MAX_NESTING` deep and every integer in it can be a float (a
    ``10**400`` is no quantity); else ``error`` naming the file and the key."""
    stack: list[tuple[object, str, int]] = [(value, "", 0)]
    while stack:
        item, where, depth = stack.pop()
        if isinstance(item, dict | list) and depth + 1 > MAX_NESTING:
            raise error(f"{path}: {where or 'the document'} nests more than {MAX_NESTING} deep")
        if isinstance(item, dict):
            stack += [(v, f"{where}.{k}" if where else str(k), depth + 1) for k, v in item.items()]
        elif isinstance(item, list):
            stack += [(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(item)]
        elif isinstance(item, int) and not isinstance(item, bool) and abs(item) > 2**1023:
            raise error(
                f"{path}: {where or 'the value'} is an integer of {len(str(item))} digits, "
                "too large to be a number"
            )
    return value


def writable_problem(path: str | Path, folder: bool = False) -> str | None:
    """Why ``path`` (a file, or a folder if ``folder``) cannot be written, in
    words, or ``None`` if it can: an ancestor that is a file, a folder that
    cannot be entered or written (tried for real), a read-only file."""
    target = Path(path).absolute()
    probe = target if folder else target.parent
    while True:
        known = _exists(probe)
        if known is None:
            return f"the folder {probe.parent} cannot be entered"
        if known:
            break
        probe = probe.parent
    if probe.is_symlink() and not probe.exists():
        return f"{probe} is a broken link"
    if not probe.is_dir():
        return f"{probe} is a file, not a folder"
    if not os.access(probe, os.W_OK | os.X_OK):
        return f"the folder {probe} is not writable"
    try:  # what the permissions say is not always what the system allows
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as err:
        return f"the folder {probe} is not writable ({err.strerror})"
    if not folder and _exists(target) and not os.access(target, os.W_OK):
        # Replaced by a rename, but a read-only file is the user's "keep this".
        return f"{target} is read-only"
    return None
