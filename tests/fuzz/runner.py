"""Run hostile cases under a time bound and judge what the user would see.

``hybridtable.cli`` (and the heavy modules the commands import) is imported
once in this process; each case runs in a ``fork`` of it: the child makes its
own process group, enters the case's folder, sends fd 0 to ``/dev/null`` and fd 1/2
to files, calls ``hybridtable.cli.main(argv)`` and leaves with ``os._exit``.
The parent kills the child's whole process group (SIGKILL) when its time is up.

Each result gets one outcome:

``hang``
    killed at its time bound;
``traceback``
    stderr holds ``Traceback``, or the exit code is not 0, 1 or 2, or a signal ended
    it, or exit 1 without exactly one ``... error: ...`` line (exit 1 with one such
    line is the documented "simulation failed": right for an ``either`` case);
``unclear_refusal``
    exit 2, but stderr is not exactly one non-empty line (progress bars aside),
    or that line is longer than :data:`MAX_LINE_CHARS`;
``missing_output``
    exit 0, but the ``--json`` file is missing or not JSON;
``bad_stdout``
    exit 0 with ``--json -``, but stdout is not JSON alone;
``silent_nonfinite``
    exit 0 and the JSON holds NaN/Infinity/null, a number beyond 1e12, or a
    CoR outside [0, 100], where the dict that holds it has no ``note``/``notes``
    saying why (nulls and infinities where the case's valid reference has
    them too, unless ``strict``, and numbers the case gave as input, are not counted);
``bad_output``
    what the case's ``post_check`` finds in its folder after the command
    (a partial output left behind, a results file holding a bad row);
``wrong_refusal`` / ``wrong_accept``
    refused a case that expects ``ok`` / accepted one that expects ``refuse``
    or ``fail``;
``ok``
    none of the above.

Optional attributes of a case (a subclass of :class:`~tests.fuzz.corpus.Case`,
e.g. ``tests.fuzz.surfaces.SurfaceCase``; a plain ``Case`` has none of them and
is judged as before):

``expect = "fail"``
    the command cannot give a result: a clear refusal (exit 2, one line) or the
    documented failed run (exit 1, one ``error:`` line); exit 0 is ``wrong_accept``;
``baseline``
    the valid case whose JSON shows where the command writes null or infinity
    by design (instead of :func:`~tests.fuzz.corpus.nominal_case` of the command);
``file_size_limit_bytes``
    ``RLIMIT_FSIZE`` of the child with ``SIGXFSZ`` ignored: a write past it fails
    with ``OSError`` (``EFBIG``), as on a full disk;
``must_mention``
    words the one line of a refusal or failure must hold (the file, the key);
``ignore_lines``
    regular expressions of documented informational stderr lines (not counted);
``post_check``
    ``post_check(folder, exit_code) -> str | None``, run on the case's folder
    after the command; a string is the ``bad_output`` found;
``gives_nonfinite``
    the case's files give ``inf`` as a valid value (an ideal table): its echo,
    as a string or null, is no finding (as for ``inf`` on the command line).
"""

from __future__ import annotations

import contextlib
import importlib
import json
import math
import os
import re
import resource
import shutil
import signal
import stat
import sys
import tempfile
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from tests.fuzz.corpus import Case, Fifo, Folder, Symlink, Unreadable, nominal_case

__all__ = [
    "OUTCOMES",
    "Result",
    "default_timeout_s",
    "full_argv",
    "run_case",
    "run_cases",
    "json_findings",
    "refusal_lines",
    "warm_up",
    "MAX_LINE_CHARS",
]

os.environ.setdefault("MPLBACKEND", "Agg")

#: Every outcome, the good one last.
OUTCOMES = (
    "hang",
    "traceback",
    "unclear_refusal",
    "missing_output",
    "bad_stdout",
    "silent_nonfinite",
    "bad_output",
    "wrong_refusal",
    "wrong_accept",
    "ok",
)

#: Commands with ``--no-progress``.
NO_PROGRESS = frozenset(
    {
        "reproduce",
        "margins",
        "compare",
        "diagnose",
        "compensators",
        "simulate6",
        "explain",
        "sweep",
    }
)
#: Commands with ``--json FILE``.
WITH_JSON = frozenset(
    {
        "simulate",
        "reproduce",
        "margins",
        "compare",
        "diagnose",
        "effects",
        "compensators",
        "diagram",
        "simulate6",
        "explain",
        "sweep",
    }
)
#: Address space a case may take [bytes]: a runaway allocation fails in the case,
#: not in the machine.
MEMORY_LIMIT_BYTES = 6 * 2**30
#: Longest refusal a rig engineer reads as one line [characters].
MAX_LINE_CHARS = 1000
#: Modules the commands import inside ``run``: imported once here, not in every fork.
_WARM = (
    "hybridtable.cli",
    "numpy",
    "scipy.signal",
    "matplotlib.pyplot",
    "hybridtable.measurement.run_reader",
    "hybridtable.measurement.comparison",
    "hybridtable.reports.compare",
    "hybridtable.loop.simulation",
    "hybridtable.diagnosis.diagnose",
    "hybridtable.reports.diagnose",
    "hybridtable.analysis.sweep",
    "hybridtable.reports.margins",
    "hybridtable.studies.compensator_sweep",
    "hybridtable.reports.compensators",
)
_NOBODY = 65534
_TQDM = re.compile(r"\d+%\||\|\s*\d+/\d+|\[\d+:\d+<|\d+(\.\d+)?(it|s)/(s|it)\]")
_COR_OFF = {
    "error",
    "limit",
    "limited",
    "hz",
    "s",
    "delta",
    "std",
    "change",
    "diff",
    # a residual or a log of CoRs may be negative; a count of runs above/below 1 exceed 100
    "residual",
    "residuals",
    "ln",
    "above",
    "below",
}


def default_timeout_s(command: str) -> float:
    """The time bound of a case of ``command`` [s]: 120 for diagnose, else 60."""
    return 120.0 if command == "diagnose" else 60.0


def warm_up() -> None:
    """Import the package and the commands' heavy modules in this process (errors ignored)."""
    for name in _WARM:
        with contextlib.suppress(Exception):
            importlib.import_module(name)


def full_argv(case: Case) -> list[str]:
    """The case's command line with ``--json out.json`` and ``--no-progress`` where the
    command has them and the case did not choose its own ``--json``."""
    argv = list(case.argv)
    if case.command in WITH_JSON and not any(
        a == "--json" or a.startswith("--json=") for a in argv
    ):
        argv += ["--json", "out.json"]
    if case.command in NO_PROGRESS and "--no-progress" not in argv:
        argv.append("--no-progress")
    return argv


@dataclass
class Result:
    """What one case did.

    Attributes
    ----------
    case
        The case.
    outcome
        One of :data:`OUTCOMES`.
    detail
        The first line of stderr, the exception, or the JSON path of the offending number.
    exit_code
        The exit code, None when a signal ended the child.
    signal
        The signal that ended it (SIGKILL at the time bound), else None.
    seconds
        Wall time [s].
    stdout, stderr
        What the command printed (the first megabyte).
    argv
        The command line it ran.
    """

    case: Case
    outcome: str
    detail: str
    exit_code: int | None
    signal: int | None
    seconds: float
    stdout: str
    stderr: str
    argv: list[str]


# --- the case's folder ------------------------------------------------------------------------


def _materialize(case: Case, folder: Path) -> bool:
    """Write the case's files into ``folder``; True if it holds an unreadable entry."""
    unreadable = []
    for rel, spec in case.files.items():
        path = folder / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(spec, bytes):
            path.write_bytes(spec)
        elif isinstance(spec, Symlink):
            os.symlink(spec.target, path)
        elif isinstance(spec, Fifo):
            os.mkfifo(path)
        elif isinstance(spec, Folder):
            path.mkdir(exist_ok=True)
        elif isinstance(spec, Unreadable):
            if spec.data is None:
                path.mkdir(exist_ok=True)
            else:
                path.write_bytes(spec.data)
            unreadable.append(path)
        else:
            raise TypeError(f"{case.name}: unknown file spec {spec!r}")
    for path in unreadable:
        path.chmod(0)
    return bool(unreadable)


def _remove(folder: Path) -> None:
    for dirpath, dirnames, filenames in os.walk(folder):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            if not os.path.islink(p):
                with contextlib.suppress(OSError):
                    os.chmod(p, stat.S_IRWXU)
    shutil.rmtree(folder, ignore_errors=True)


# --- the child --------------------------------------------------------------------------------


def _exit_code(code) -> int:
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def _drop_file_override() -> None:
    """Drop CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH from this (root) process, so
    that file modes bind it as they bind a user; if that fails, become nobody."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    header = (ctypes.c_uint32 * 2)(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3, this process
    data = (ctypes.c_uint32 * 6)()  # (effective, permitted, inheritable) x 2
    if libc.capget(header, data) == 0:
        dac = (1 << 1) | (1 << 2)
        data[0] &= ~dac
        data[1] &= ~dac
        if libc.capset(header, data) == 0:
            return
    os.environ["HOME"] = os.getcwd()
    os.environ["MPLCONFIGDIR"] = os.path.join(os.getcwd(), ".mpl")
    os.setgroups([])
    os.setgid(_NOBODY)
    os.setuid(_NOBODY)


def _child(
    folder: Path, argv: list[str], unprivileged: bool, file_size_limit: int | None = None
) -> None:
    """Run ``argv`` in this forked process and leave; never returns.

    ``file_size_limit`` [bytes]: no file may grow past it (a full disk)."""
    code = 1
    try:
        os.setpgid(0, 0)
        os.chdir(folder)
        null = os.open(os.devnull, os.O_RDONLY)
        out = os.open(folder / ".stdout", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        err = os.open(folder / ".stderr", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        for fd, target in ((null, 0), (out, 1), (err, 2)):
            os.dup2(fd, target)
            os.close(fd)
        sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115
        sys.stdout = open(1, "w", encoding="utf-8", errors="surrogateescape", closefd=False)  # noqa: SIM115
        sys.stderr = open(  # noqa: SIM115
            2, "w", encoding="utf-8", errors="backslashreplace", closefd=False, buffering=1
        )
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))
        if file_size_limit is not None:  # a full disk: writes past it fail with EFBIG
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size_limit, file_size_limit))
        if unprivileged:  # root reads a mode-000 file: give up that power so the mode holds
            _drop_file_override()
        sys.argv = ["hybridtable", *argv]
        from hybridtable.cli import main

        code = _exit_code(main(argv))
    except SystemExit as exc:
        code = _exit_code(exc.code)
    except BaseException:
        with contextlib.suppress(BaseException):
            sys.excepthook(*sys.exc_info())
        code = 1
    finally:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(BaseException):
                stream.flush()
        os._exit(code if 0 <= code < 256 else 1)


# --- judging ----------------------------------------------------------------------------------


def refusal_lines(stderr: str) -> list[str]:
    """The non-empty lines of ``stderr`` without progress bars (tqdm's ``\\r`` lines)."""
    lines = []
    for line in stderr.split("\n"):
        if "\r" in line:
            line = line.rsplit("\r", 1)[-1]
        if not line.strip() or (len(line) < 400 and _TQDM.search(line)):
            continue
        lines.append(line.strip())
    return lines


class _Constant:
    """``NaN``/``Infinity`` literals in a JSON text."""

    def __init__(self, text: str) -> None:
        self.text = text


def _is_cor_key(key: str | None) -> bool:
    if not key:
        return False
    words = key.lower().split("_")
    return "cor" in words and not (_COR_OFF & set(words))


def _explained(holder: dict | None) -> bool:
    if not isinstance(holder, dict):
        return False
    for key in ("note", "notes"):
        value = holder.get(key)
        if isinstance(value, str) and value.strip():
            return True
        if isinstance(value, list) and any(isinstance(v, str) and v.strip() for v in value):
            return True
    return False


def _shape(path: str) -> str:
    return re.sub(r"\[\d+\]", "[*]", path)


def _nonfinite(value) -> bool:
    if value is None or isinstance(value, _Constant):
        return True
    return isinstance(value, str) and value.strip().lower() in {
        "inf",
        "-inf",
        "+inf",
        "nan",
        "infinity",
        "-infinity",
    }


def _walk(obj, path="", key=None, holder=None):
    """(path, key, value, holder dict) of every leaf."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _walk(v, f"{path}.{k}", str(k), obj)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _walk(v, f"{path}[{i}]", key, holder)
    else:
        yield path or ".", key, obj, holder


def json_findings(
    data, inputs: Iterable[float] = (), allowed: Iterable[str] = (), nonfinite_inputs: bool = False
) -> list[str]:
    """The unexplained non-finite, absurd and impossible numbers of a command's JSON.

    Parameters
    ----------
    data
        The parsed JSON (``NaN``/``Infinity`` literals as :class:`_Constant`).
    inputs
        Numbers the case gave (a value equal to one is an echo, not a finding).
    allowed
        Path shapes (``.a[*].b``) where the valid base case holds null or infinity too.
    nonfinite_inputs
        The case gave ``inf`` or ``nan`` itself (its echo is no finding).

    Returns
    -------
    list of str
        ``path = value`` of each finding, in document order.
    """
    inputs = [abs(x) for x in inputs if math.isfinite(x)]
    allowed = set(allowed)
    out = []
    for path, key, value, holder in _walk(data):
        if _explained(holder):
            continue
        if _nonfinite(value):
            if _shape(path) in allowed or (nonfinite_inputs and not isinstance(value, _Constant)):
                continue
            shown = value.text if isinstance(value, _Constant) else json.dumps(value)
            out.append(f"{path} = {shown}")
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            continue
        x = abs(float(value)) if abs(value) < 1e308 else math.inf
        echo = any(abs(x - u) <= 1e-9 * u for u in inputs)
        if x > 1e12 and not echo:
            out.append(f"{path} = {value:.6g} (beyond 1e12)")
        elif _is_cor_key(key) and not 0.0 <= float(value) <= 100.0 and not echo:
            out.append(f"{path} = {value:.6g} (a CoR outside [0, 100])")
    return out


def _nonfinite_paths(data) -> set[str]:
    return {_shape(p) for p, _, v, _ in _walk(data) if _nonfinite(v)}


def _argv_numbers(argv: list[str]) -> tuple[list[float], bool]:
    numbers, nonfinite = [], False
    for token in argv:
        for part in re.split(r"[=,:]", token):
            try:
                x = float(part)
            except ValueError:
                continue
            if math.isfinite(x):
                numbers.append(x)
            else:
                nonfinite = True
    return numbers, nonfinite


def _load_json(text: str):
    return json.loads(text, parse_constant=_Constant)


@dataclass
class _Raw:
    case: Case
    argv: list[str]
    exit_code: int | None
    signal: int | None
    seconds: float
    stdout: str
    stderr: str
    json_text: str | None
    hung: bool
    post_problem: str | None = None


def _first(lines: list[str]) -> str:
    return lines[0][:240] if lines else ""


def _unnamed(case: Case, line: str) -> str | None:
    """The first of the case's ``must_mention`` words that ``line`` lacks."""
    for word in getattr(case, "must_mention", ()):
        if word.lower() not in line.lower():
            return word
    return None


def _judge(raw: _Raw, allowed: set[str]) -> tuple[str, str]:
    outcome, detail = _judge_run(raw, allowed)
    if outcome == "ok" and raw.post_problem:
        return "bad_output", raw.post_problem[:240]
    return outcome, detail


def _judge_run(raw: _Raw, allowed: set[str]) -> tuple[str, str]:
    case, argv = raw.case, raw.argv
    lines = refusal_lines(raw.stderr)
    ignore = [re.compile(p) for p in getattr(case, "ignore_lines", ())]
    if ignore:
        lines = [line for line in lines if not any(p.search(line) for p in ignore)]
    if raw.hung:
        return "hang", f"killed after {raw.seconds:.0f} s; " + _first(lines)
    if "Traceback (most recent call last)" in raw.stderr:
        return "traceback", (lines[-1][:240] if lines else "")
    if raw.signal is not None:
        return "traceback", f"signal {raw.signal}; " + _first(lines)
    if raw.exit_code == 1 and len(lines) == 1 and ": error: " in lines[0]:
        # A simulation that diverged, could not be simulated or never made a
        # contact: the documented exit 1, one line. Right where a clean result
        # or a refusal are both right; not a refusal of certainly invalid input.
        if case.expect in ("either", "fail"):
            missing = _unnamed(case, lines[0])
            if missing is not None:
                return "unclear_refusal", f"does not name {missing!r}: " + lines[0][:200]
            return "ok", lines[0][:240]
        if case.expect == "refuse":
            return "wrong_accept", "exit 1 (simulation failed), not refused: " + lines[0][:200]
        return "wrong_refusal", lines[0][:240]
    if raw.exit_code not in (0, 2):
        return "traceback", f"exit {raw.exit_code}: " + _first(lines)
    if raw.exit_code == 2:
        if len(lines) != 1:
            return "unclear_refusal", f"{len(lines)} lines: " + " | ".join(lines[:3])[:240]
        if len(lines[0]) > MAX_LINE_CHARS:
            return "unclear_refusal", f"a line of {len(lines[0])} characters: {lines[0][:160]}"
        if case.expect == "ok":
            return "wrong_refusal", lines[0][:240]
        missing = _unnamed(case, lines[0])
        if missing is not None:
            return "unclear_refusal", f"does not name {missing!r}: " + lines[0][:200]
        return "ok", lines[0][:240]
    # exit 0
    to_stdout = (
        any(a == "--json" and i + 1 < len(argv) and argv[i + 1] == "-" for i, a in enumerate(argv))
        or "--json=-" in argv
    )
    if to_stdout:
        try:
            data = _load_json(raw.stdout)
        except ValueError as exc:
            return "bad_stdout", f"stdout is not JSON alone: {exc}"[:240]
    elif raw.json_text is None:
        if case.command in WITH_JSON and "out.json" in argv:
            return "missing_output", "exit 0 but no out.json"
        data = None
    else:
        try:
            data = _load_json(raw.json_text)
        except ValueError as exc:
            return "missing_output", f"out.json is not JSON: {exc}"[:240]
    if data is not None:
        numbers, nonfinite = _argv_numbers(argv)
        nonfinite = nonfinite or getattr(case, "gives_nonfinite", False)
        findings = json_findings(data, [*case.inputs, *numbers], allowed, nonfinite)
        if findings:
            more = f" (+{len(findings) - 1} more)" if len(findings) > 1 else ""
            return "silent_nonfinite", findings[0][:200] + more
    if case.expect in ("refuse", "fail"):
        return "wrong_accept", "exit 0: " + _first(raw.stdout.splitlines())
    return "ok", _first(raw.stdout.splitlines())


# --- running ----------------------------------------------------------------------------------


@dataclass
class _Running:
    index: int
    case: Case
    argv: list[str]
    pid: int
    folder: Path
    start: float
    deadline: float


def _start(index: int, case: Case, root: Path, timeout_s: float | None) -> _Running:
    folder = Path(tempfile.mkdtemp(prefix=f"case{index}-", dir=root))
    unprivileged = _materialize(case, folder) and os.geteuid() == 0
    if unprivileged:
        folder.chmod(0o777)
    argv = full_argv(case)
    bound = timeout_s or case.timeout_s or default_timeout_s(case.command)
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        _child(folder, argv, unprivileged, getattr(case, "file_size_limit_bytes", None))
    with contextlib.suppress(OSError):
        os.setpgid(pid, pid)
    now = time.monotonic()
    return _Running(index, case, argv, pid, folder, now, now + bound)


def _read(path: Path, limit: int = 2**20) -> str | None:
    try:
        with open(path, "rb") as f:
            return f.read(limit).decode("utf-8", errors="replace")
    except OSError:
        return None


def _kill_group(pid: int) -> None:
    with contextlib.suppress(OSError):
        os.killpg(pid, signal.SIGKILL)


def _collect(r: _Running, status: int, hung: bool) -> _Raw:
    seconds = time.monotonic() - r.start
    _kill_group(r.pid)  # workers the command left behind
    json_path = r.folder / "out.json"
    json_text = None
    if json_path.is_file() and not json_path.is_symlink():
        json_text = _read(json_path, 64 * 2**20)
    raw = _Raw(
        r.case,
        r.argv,
        os.WEXITSTATUS(status) if os.WIFEXITED(status) and not hung else None,
        os.WTERMSIG(status) if os.WIFSIGNALED(status) and not hung else None,
        seconds,
        _read(r.folder / ".stdout") or "",
        _read(r.folder / ".stderr") or "",
        json_text,
        hung,
    )
    check = getattr(r.case, "post_check", None)
    if check is not None and not hung:
        try:
            raw.post_problem = check(r.folder, raw.exit_code)
        except Exception as exc:  # a broken check is a finding of the harness, not the tool
            raw.post_problem = f"post_check raised {type(exc).__name__}: {exc}"
    return raw


_BASELINES: dict[tuple[str, ...], set[str]] = {}


def _execute(
    cases: list[Case],
    jobs: int,
    timeout_s: float | None,
    root: Path,
    keep: bool,
    on_raw: Callable[[int, _Raw], None],
) -> None:
    queue = deque(enumerate(cases))
    running: dict[int, _Running] = {}
    try:
        while queue or running:
            while queue and len(running) < max(1, jobs):
                i, case = queue.popleft()
                r = _start(i, case, root, timeout_s)
                running[r.pid] = r
            time.sleep(0.005)
            for pid, r in list(running.items()):
                done, status = os.waitpid(pid, os.WNOHANG)
                hung = False
                if not done:
                    if time.monotonic() < r.deadline:
                        continue
                    _kill_group(pid)
                    _, status = os.waitpid(pid, 0)
                    hung = True
                del running[pid]
                raw = _collect(r, status, hung)
                if not keep:
                    _remove(r.folder)
                on_raw(r.index, raw)
    finally:
        for pid in running:
            _kill_group(pid)
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)


def _reference(case: Case) -> Case:
    """The valid case that ``case`` spoils (see ``Case.reference``, and a case's ``baseline``)."""
    baseline = getattr(case, "baseline", None)
    if baseline is not None:
        return baseline
    nominal = nominal_case(case.command)
    if case.reference is None:
        return nominal
    return Case(
        "reference:" + " ".join(case.reference),
        "nominal",
        nominal.files,
        list(case.reference),
        "ok",
    )


def _ref_key(ref: Case) -> tuple[str, ...]:
    return (ref.name, *ref.argv)


def _key(case: Case) -> tuple[str, ...]:
    return _ref_key(_reference(case))


def _baselines(cases: list[Case], jobs: int, root: Path, keep: bool) -> None:
    """Null and infinite paths of each case's valid reference (the command's own way
    of saying "none" or "unbounded", not a finding), run once per reference."""
    todo = {}
    for case in cases:
        ref = _reference(case)
        if _ref_key(ref) not in _BASELINES:
            todo.setdefault(_ref_key(ref), ref)
    refs = list(todo.values())

    def store(i: int, raw: _Raw) -> None:
        data = None
        with contextlib.suppress(ValueError, TypeError):
            data = _load_json(raw.json_text or "")
        _BASELINES[_ref_key(refs[i])] = _nonfinite_paths(data) if data is not None else set()

    _execute(refs, jobs, None, root, keep, store)


def run_cases(
    cases: list[Case],
    jobs: int = 1,
    timeout_s: float | None = None,
    on_result: Callable[[Result], None] | None = None,
    keep: Path | None = None,
    strict: bool = False,
) -> list[Result]:
    """Run ``cases``, ``jobs`` at a time, each in a fork under its time bound.

    Parameters
    ----------
    cases
        The cases.
    jobs
        Children at a time.
    timeout_s
        Time bound of every case [s]; None: :func:`default_timeout_s` or the case's own.
    on_result
        Called with each result as it comes (in the order the cases finish).
    keep
        A folder to leave the cases' folders in (for a look at them); None: removed.
    strict
        Count every null and infinity, also where the case's valid reference
        has them (by default those are the command's design, not a finding).

    Returns
    -------
    list of Result
        In the order of ``cases``.
    """
    warm_up()
    root = Path(tempfile.mkdtemp(prefix="hybridtable-fuzz-", dir=keep))
    root.chmod(0o755)
    results: list[Result | None] = [None] * len(cases)

    def judge(i: int, raw: _Raw) -> None:
        allowed = set() if strict else _BASELINES.get(_key(raw.case), set())
        outcome, detail = _judge(raw, allowed)
        results[i] = Result(
            raw.case,
            outcome,
            detail,
            raw.exit_code,
            raw.signal,
            raw.seconds,
            raw.stdout,
            raw.stderr,
            raw.argv,
        )
        if on_result is not None:
            on_result(results[i])

    try:
        if not strict:
            _baselines(cases, jobs, root, keep is not None)
        _execute(cases, jobs, timeout_s, root, keep is not None, judge)
    finally:
        if keep is None:
            _remove(root)
    return results


def run_case(case: Case, timeout_s: float | None = None, strict: bool = False) -> Result:
    """Run one case (a fork, under its time bound) and judge it."""
    return run_cases([case], 1, timeout_s, strict=strict)[0]
