"""Hostile cases for the command line: malformed and extreme runs, files and flags.

Written apart from the package (nothing here imports ``hybridtable``): what a
run is comes from ``docs/run-format.md``, the valid base run from the
independent rig simulator ``tests/generators/rigsim.py``, and the flags and
their ranges from each command's ``--help``, written out below as a table.

A :class:`Case` is a command line (``argv``, without the program name) and the
files of the folder it runs in; :mod:`tests.fuzz.runner` runs it and judges the
result against ``expect``:

``"refuse"``
    the input is certainly invalid (a NaN cell, a missing key, a negative
    mass): exit code 2 and one line on stderr;
``"ok"``
    a valid input: exit 0 with every number in the JSON finite;
``"either"``
    a clear refusal and a clean finite result are both right (a damping ratio
    of 1e-300, a 1e30 spike in the force).

:func:`corpus` is the fixed corpus (every class of the hostile tester of issue
19, at least 300 cases of ``compare``, 30 of ``diagnose`` and 300 flag values);
:func:`runs_strategy` and :func:`flag_strategy` draw more for hypothesis.

Why one module: the fixed corpus and the strategies share the base run, the
table of flags and the rules that give each input its expectation; split, the
rules would be written twice.
"""

from __future__ import annotations

import functools
import gzip
import json
import math
import random
from dataclasses import dataclass, field

import numpy as np
from hypothesis import strategies as st

from tests.generators.rigsim import NOMINAL, simulate_record

__all__ = [
    "Case",
    "Symlink",
    "Fifo",
    "Unreadable",
    "Folder",
    "COLUMNS",
    "RUN_KEYS",
    "HOSTILE_VALUES",
    "FlagSpec",
    "FLAG_SPECS",
    "flag_expect",
    "nominal_case",
    "corpus",
    "runs_strategy",
    "flag_strategy",
]


# --- what a case is ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Symlink:
    """A symbolic link to ``target`` (relative to the link's folder, or absolute)."""

    target: str


@dataclass(frozen=True)
class Fifo:
    """A named pipe where a file is expected (nothing ever writes into it)."""


@dataclass(frozen=True)
class Unreadable:
    """A file holding ``data`` with mode 000, or (``data`` None) a folder with mode 000.

    The runner drops root's privileges for a case holding one, so that the
    mode means what it says."""

    data: bytes | None = None


@dataclass(frozen=True)
class Folder:
    """An empty folder."""


FileSpec = bytes | Symlink | Fifo | Unreadable | Folder


@dataclass
class Case:
    """One hostile command line.

    Attributes
    ----------
    name
        Unique, ``command/klass/what``.
    klass
        The class of the defect (``cells``, ``time``, ``encoding``, ``structure``,
        ``json``, ``extreme``, ``contradictory``, ``files``, ``outputs``, ``flags``,
        ``lists``, ``stdout``, ``nominal``, ``hypothesis``).
    files
        ``{relative path: content}`` of the case's folder: bytes, or a
        :class:`Symlink`, :class:`Fifo`, :class:`Unreadable`, :class:`Folder`.
    argv
        The command line without the program name, e.g. ``["compare", "run.csv"]``;
        the runner adds ``--json out.json`` and ``--no-progress`` where the
        command has them and the case does not say otherwise.
    expect
        ``"refuse"``, ``"ok"`` or ``"either"`` (module docstring).
    why
        Why this expectation, where it is not obvious.
    timeout_s
        Time bound [s]; None: the runner's default for the command.
    inputs
        Numbers the case gives (run JSON values, flag values): a result may repeat them.
    reference
        The valid command line this case spoils (a flag case: its command line
        without the hostile flag); None: :func:`nominal_case` of the command.
        Its result shows where the command writes null or infinity by design.
    """

    name: str
    klass: str
    files: dict[str, FileSpec]
    argv: list[str]
    expect: str
    why: str = ""
    timeout_s: float | None = None
    inputs: list[float] = field(default_factory=list)
    reference: tuple[str, ...] | None = None

    @property
    def command(self) -> str:
        """The sub-command, ``argv[0]``."""
        return self.argv[0]


# --- the valid base run (tests/generators/rigsim.py) ------------------------------------------

#: The columns of ``hybridtable-run/1``, in their order.
COLUMNS = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")

#: The numeric keys of a run's JSON and their documented range.
RUN_KEYS = {
    "sample_rate_hz": ">0",
    "spacecraft_mass_kg": ">0",
    "contact_stiffness_n_per_m": ">0",
    "table_natural_frequency_hz": ">0",
    "initial_velocity_m_per_s": ">0",
    "sensor_delay_s": ">=0",
    "table_damping_ratio": ">=0",
    "lead_time_s": ">=0",
    "initial_gap_m": ">=0",
    "force_deadband_n": ">=0",
}
_ALL_KEYS = (*RUN_KEYS, "format", "run_id", "compensator")


@functools.cache
def _simulated(seed: int, changes: tuple[tuple[str, object], ...]) -> tuple[dict, dict]:
    info = dict(NOMINAL, run_id=f"fuzz-{seed}")
    info.update(dict(changes))
    columns = simulate_record(info, seed=seed)
    return info, columns


def _base(seed: int = 0, **changes) -> tuple[dict, dict[str, np.ndarray]]:
    """A valid run of the nominal rig (SDMDC, 1 kHz, 0.9 s): its JSON dict and columns (copies)."""
    info, columns = _simulated(seed, tuple(sorted(changes.items())))
    return dict(info), {k: v.copy() for k, v in columns.items()}


def _rows(columns: dict[str, np.ndarray], names=COLUMNS) -> list[list[str]]:
    """Header and cells as text, as ``rigsim.write_run`` writes them."""
    table = np.column_stack([columns[c] for c in names])
    return [list(names)] + [[f"{x:.10g}" for x in row] for row in table.tolist()]


def _csv(rows: list[list[str]], eol: str = "\n", final_eol: bool = True) -> bytes:
    return (eol.join(",".join(r) for r in rows) + (eol if final_eol else "")).encode("utf-8")


def _json(info) -> bytes:
    return (json.dumps(info, indent=2) + "\n").encode("utf-8")


@dataclass(frozen=True)
class _Marks:
    """Rows of the base run: contact start, force peak, separation, last."""

    start: int
    peak: int
    end: int
    last: int


def _marks(info: dict, columns: dict[str, np.ndarray]) -> _Marks:
    f = columns["f_mea_n"]
    touching = np.flatnonzero(f > info["force_deadband_n"] + 20.0)
    return _Marks(int(touching[0]), int(np.argmax(f)), int(touching[-1]), len(f) - 1)


def _pair(csv: FileSpec, info_json: FileSpec, stem: str = "run") -> dict[str, FileSpec]:
    return {f"{stem}.csv": csv, f"{stem}.json": info_json}


def _numbers(info) -> list[float]:
    """The finite numbers of a run's JSON (a result may repeat them)."""
    if not isinstance(info, dict):
        return []
    out = []
    for v in info.values():
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
            out.append(float(v))
    return out


# --- expectations of values -------------------------------------------------------------------


def _finite_float(text: str) -> float | None:
    try:
        x = float(text)
    except ValueError:
        return None
    return x if math.isfinite(x) else None


def _in_range(x: float, accepted: str) -> bool:
    if math.isnan(x):
        return False
    if accepted == ">0":
        return x > 0.0 and math.isfinite(x)
    if accepted == ">=0":
        return x >= 0.0 and math.isfinite(x)
    if accepted == ">0|inf":
        return x > 0.0
    if accepted == "(-1,1)":
        return -1.0 < x < 1.0
    return math.isfinite(x)


def _key_expect(key: str, value) -> str:
    """A run's JSON key given ``value``: refuse what the format forbids, else either."""
    if key == "format":
        return "either" if value == "hybridtable-run/1" else "refuse"
    if key == "compensator":
        return "either" if value in ("none", "SDC", "MDC", "SDMDC") else "refuse"
    if key == "run_id":
        return "either" if isinstance(value, str) else "refuse"
    if isinstance(value, bool) or not isinstance(value, int | float):
        return "refuse"
    return "either" if _in_range(float(value), RUN_KEYS[key]) else "refuse"


# --- run defects (shared by compare, diagnose and effects --rig) ------------------------------


@dataclass
class _Defect:
    klass: str
    what: str
    files: dict[str, FileSpec]
    expect: str
    args: tuple[str, ...] = ("run.csv",)
    why: str = ""
    inputs: list[float] = field(default_factory=list)


_CELL_VALUES = ("nan", "inf", "-inf", "abc", "", "1e308", "1e30", "1e-300", "-1e308")
_SPELLINGS = (
    "NaN",
    "-nan",
    "Infinity",
    "+inf",
    "INF",
    "1e999",
    "-1e999",
    "0x10",
    "1.0.0",
    "--1",
    "1e",
    "\u221e",
    "1_0",
    " 1.0 ",
    "1E-3",
)


def _cell_expect(column: str, row: int, value: str, original: str) -> str:
    x = _finite_float(value)
    if x is None:
        return "refuse"
    if column == "time_s" and x != float(original) and not (row == 0 and abs(x) < 1e-9):
        return "refuse"  # a tick off its time k / rate
    return "either"


def _cell_defects(info, columns, marks) -> list[_Defect]:
    base = _rows(columns)
    meta = _json(info)
    out = []
    for column_index, column in enumerate(COLUMNS):
        for label, row in (("first", 0), ("peak", marks.peak), ("last", marks.last)):
            for value in _CELL_VALUES:
                rows = [r[:] for r in base]
                original = rows[row + 1][column_index]
                rows[row + 1][column_index] = value
                expect = _cell_expect(column, row, value, original)
                what = f"{column}-{label}-{value or 'empty'}"
                out.append(_Defect("cells", what, _pair(_csv(rows), meta), expect))
    for value in _SPELLINGS:
        rows = [r[:] for r in base]
        rows[marks.peak + 1][3] = value
        expect = _cell_expect("f_mea_n", marks.peak, value, "")
        out.append(
            _Defect("cells", f"f_mea_n-peak-spelled-{value!r}", _pair(_csv(rows), meta), expect)
        )
    rows = [r[:] for r in base]
    rows[marks.peak + 1][2] = "1" * 100_000  # a cell of 100 000 digits: 1e99999
    out.append(_Defect("cells", "p_act_m-100000-digits", _pair(_csv(rows), meta), "refuse"))
    return out


def _time_defects(info, columns, marks) -> list[_Defect]:
    h = 1.0 / info["sample_rate_hz"]
    meta = _json(info)
    n = len(columns["time_s"])
    rng = np.random.default_rng(7)

    def with_time(t, what, expect, why=""):
        c = dict(columns, time_s=np.asarray(t, dtype=float))
        return _Defect("time", what, _pair(_csv(_rows(c)), meta), expect, why=why)

    def with_rows(keep, what, expect="refuse"):
        c = {k: np.asarray(v)[keep] for k, v in columns.items()}
        return _Defect("time", what, _pair(_csv(_rows(c)), meta), expect)

    t = columns["time_s"]
    k = np.arange(n)
    swap = k.copy()
    swap[[100, 101]] = swap[[101, 100]]
    dup_time = t.copy()
    dup_time[101] = dup_time[100]
    rows = _rows(columns)
    blank_tail = rows + [["", "", "", "", "", ""]]
    out = [
        with_rows(swap, "two-rows-swapped"),
        with_rows(np.insert(k, 100, 100), "row-duplicated"),
        with_time(dup_time, "time-repeated", "refuse"),
        with_rows(np.delete(k, range(300, 310)), "gap-of-10-ticks"),
        with_rows(np.delete(k, 500), "one-tick-missing"),
        with_time(t + 0.5, "starts-at-0.5-s", "refuse"),
        with_time(t + h, "starts-one-tick-late", "refuse"),
        with_time(t - h, "starts-at-minus-one-tick", "refuse"),
        with_time(t * 2.0, "csv-at-500-hz-json-1000", "refuse"),
        with_time(t * 1000.0, "time-in-ms", "refuse"),
        with_time(k.astype(float), "time-in-ticks", "refuse"),
        with_time(t[::-1].copy(), "time-reversed", "refuse"),
        with_time(np.zeros(n), "time-all-zero", "refuse"),
        with_time(t + rng.uniform(-0.3, 0.3, n) * h, "jitter-30-percent", "refuse"),
        with_time(
            t + rng.uniform(-0.001, 0.001, n) * h, "jitter-0.1-percent", "either", "within 1 %"
        ),
        with_time(np.where(k == n - 1, t + 5.0, t), "last-tick-5-s-late", "refuse"),
        with_time(
            np.round(t, 2), "time-rounded-to-10-ms", "refuse", "steps of 0 and 10 ms at 1 kHz"
        ),
        _Defect("time", "trailing-empty-row", _pair(_csv(blank_tail), meta), "either"),
    ]
    off = dict(info, sample_rate_hz=1001.0)
    out.append(
        _Defect(
            "time",
            "json-rate-1001-hz-csv-1000",
            _pair(_csv(rows), _json(off)),
            "either",
            why="a 0.1 % rate error: inside the 1 % step tolerance, yet the ticks drift",
        )
    )
    return out


def _text_defects(info, columns, marks) -> list[_Defect]:
    """Encodings and the CSV's structure."""
    meta = _json(info)
    rows = _rows(columns)
    text = _csv(rows).decode()
    enc, struct = "encoding", "structure"
    peak = marks.peak + 1

    def defect(klass, what, csv, expect, info_json=meta, why=""):
        return _Defect(klass, what, _pair(csv, info_json), expect, why=why)

    def edit(fn):
        r = [x[:] for x in rows]
        fn(r)
        return _csv(r)

    latin_cell = text.replace(rows[peak][3], rows[peak][3] + "\u00b0", 1).encode("latin-1")
    latin_head = text.replace("f_mea_n", "f_mea_\u00e9", 1).encode("latin-1")
    junk = random.Random(19).randbytes(4096)
    out = [
        defect(enc, "latin-1-byte-in-a-cell", latin_cell, "refuse"),
        defect(enc, "latin-1-byte-in-the-header", latin_head, "refuse"),
        defect(enc, "utf-16-with-bom", text.encode("utf-16"), "either"),
        defect(enc, "utf-16-le-without-bom", text.encode("utf-16-le"), "refuse"),
        defect(enc, "utf-8-bom", b"\xef\xbb\xbf" + text.encode(), "either"),
        defect(
            enc, "nul-byte-in-a-cell", text.replace(rows[peak][3], "1\x002", 1).encode(), "refuse"
        ),
        defect(enc, "nul-bytes-appended", text.encode() + b"\x00" * 16, "refuse"),
        defect(enc, "crlf-line-ends", _csv(rows, "\r\n"), "ok", why="a Windows CSV is a CSV"),
        defect(enc, "cr-line-ends", _csv(rows, "\r"), "either"),
        defect(enc, "no-final-newline", _csv(rows, final_eol=False), "ok"),
        defect(enc, "json-utf-8-bom", _csv(rows), "either", b"\xef\xbb\xbf" + meta),
        defect(enc, "json-utf-16", _csv(rows), "either", meta.decode().encode("utf-16")),
        defect(
            enc,
            "json-latin-1-run-id",
            _csv(rows),
            "either",
            _json(dict(info, run_id="caf\u00e9"))
            .decode("ascii")
            .replace("\\u00e9", "\u00e9")
            .encode("latin-1"),
        ),
        defect(enc, "binary-junk", junk, "refuse"),
        defect(enc, "junk-after-the-data", _csv(rows) + junk, "refuse"),
        defect(enc, "png-bytes", b"\x89PNG\r\n\x1a\n" + junk[:256], "refuse"),
        defect(enc, "gzip-compressed", gzip.compress(_csv(rows), mtime=0), "refuse"),
        defect(
            struct, "trailing-comma-every-line", edit(lambda r: [x.append("") for x in r]), "either"
        ),
        defect(
            struct,
            "trailing-comma-data-rows",
            edit(lambda r: [x.append("") for x in r[1:]]),
            "refuse",
        ),
        defect(
            struct, "extra-column-at-the-end", edit(lambda r: [x.append("1") for x in r]), "either"
        ),
        defect(
            struct,
            "extra-column-in-the-middle",
            edit(lambda r: [x.insert(2, "0") for x in r]),
            "either",
        ),
        defect(
            struct,
            "duplicate-column-f_mea_n",
            edit(lambda r: [x.append(x[3]) for x in r]),
            "refuse",
        ),
        defect(struct, "columns-permuted", edit(lambda r: [x.reverse() for x in r]), "either"),
        defect(
            struct,
            "header-upper-case",
            edit(lambda r: r.__setitem__(0, [c.upper() for c in r[0]])),
            "either",
        ),
        defect(
            struct,
            "header-with-spaces",
            edit(lambda r: r.__setitem__(0, [" " + c for c in r[0]])),
            "either",
        ),
        defect(struct, "semicolons", text.replace(",", ";").encode(), "refuse"),
        defect(struct, "tabs", text.replace(",", "\t").encode(), "refuse"),
        defect(struct, "no-header", _csv(rows[1:]), "refuse"),
        defect(struct, "header-only", _csv(rows[:1]), "refuse"),
        defect(struct, "one-row", _csv(rows[:2]), "refuse"),
        defect(struct, "two-rows", _csv(rows[:3]), "refuse"),
        defect(struct, "empty-file", b"", "refuse"),
        defect(struct, "one-newline", b"\n", "refuse"),
        defect(struct, "whitespace-only", b"  \n\t\n   \n", "refuse"),
        defect(struct, "row-with-a-missing-cell", edit(lambda r: r[peak].pop()), "refuse"),
        defect(struct, "row-with-an-extra-cell", edit(lambda r: r[peak].append("0")), "refuse"),
        defect(struct, "blank-line-inside", edit(lambda r: r.insert(peak, [""])), "either"),
        defect(struct, "comment-line-on-top", edit(lambda r: r.insert(0, ["# rig log"])), "either"),
        defect(
            struct,
            "quoted-cells",
            edit(lambda r: [r.__setitem__(i, [f'"{c}"' for c in x]) for i, x in enumerate(r)]),
            "either",
        ),
        defect(
            struct,
            "thousand-extra-columns",
            edit(
                lambda r: [
                    x.extend([f"x{j}" if i == 0 else "0" for j in range(1000)])
                    for i, x in enumerate(r)
                ]
            ),
            "either",
        ),
    ]
    for i, column in enumerate(COLUMNS):
        out.append(
            defect(
                struct,
                f"missing-column-{column}",
                edit(lambda r, i=i: [x.pop(i) for x in r]),
                "refuse",
            )
        )
    return out


def _json_defects(info, columns, marks) -> list[_Defect]:
    csv = _csv(_rows(columns))

    def defect(what, meta, expect, why=""):
        return _Defect("json", what, _pair(csv, meta), expect, why=why, inputs=_numbers_of(meta))

    good = _json(info)
    out = [
        defect("invalid-json-truncated", good[: len(good) // 2], "refuse"),
        defect("invalid-json-trailing-comma", good.rstrip()[:-1].rstrip() + b",\n}\n", "refuse"),
        defect("empty-file", b"", "refuse"),
        defect("a-list", b"[]\n", "refuse"),
        defect("a-number", b"42\n", "refuse"),
        defect("null", b"null\n", "refuse"),
        defect("a-string", b'"hybridtable-run/1"\n', "refuse"),
        defect("empty-object", b"{}\n", "refuse"),
        defect("binary-junk", random.Random(3).randbytes(512), "refuse"),
        defect("nested-1000-deep", b"[" * 1000 + b"]" * 1000, "refuse"),
        defect("nested-100000-deep", b"[" * 100_000 + b"]" * 100_000, "refuse"),
        defect("duplicate-key", good.replace(b"{", b'{\n  "spacecraft_mass_kg": -1,', 1), "either"),
        defect("unknown-key-kept", _json(dict(info, rig_room="B12")), "ok"),
    ]
    for key in _ALL_KEYS:
        out.append(
            defect(f"missing-{key}", _json({k: v for k, v in info.items() if k != key}), "refuse")
        )
    for key, value in (
        ("format", "hybridtable-run/2"),
        ("format", ""),
        ("format", None),
        ("compensator", "XYZ"),
        ("compensator", "sdmdc"),
        ("compensator", None),
        ("compensator", 3),
        ("run_id", 42),
        ("run_id", None),
        ("run_id", ["a"]),
        ("run_id", ""),
        ("run_id", "../../etc/passwd"),
        ("run_id", "x" * 10_000),
    ):
        out.append(
            defect(
                f"{key}={json.dumps(value)[:20]}",
                _json(dict(info, **{key: value})),
                _key_expect(key, value),
            )
        )
    for key in RUN_KEYS:
        for label, value in (
            ("string-number", str(info[key])),
            ("bool", True),
            ("null", None),
            ("list", [info[key]]),
            ("object", {"value": info[key]}),
        ):
            out.append(defect(f"{key}-{label}", _json(dict(info, **{key: value})), "refuse"))
        for literal in ("NaN", "Infinity", "-Infinity"):
            text = json.dumps(dict(info, **{key: 0.125})).replace(": 0.125", ": " + literal)
            out.append(defect(f"{key}-{literal}", text.encode(), "refuse"))
        for value in (-1.0, 0.0):
            out.append(
                defect(
                    f"{key}={value:g}", _json(dict(info, **{key: value})), _key_expect(key, value)
                )
            )
        out.append(
            defect(
                f"{key}=1e400-literal",
                json.dumps(dict(info, **{key: 0.125})).replace("0.125", "1e400").encode(),
                "refuse",
            )
        )
    return out


def _numbers_of(meta: bytes) -> list[float]:
    try:
        return _numbers(json.loads(meta))
    except (ValueError, UnicodeDecodeError, RecursionError):
        return []


#: Extreme but typed metadata: the CSV is the base run's (or re-timed for the rate).
_EXTREMES = (
    ("table_natural_frequency_hz", 1e6),
    ("table_natural_frequency_hz", 1e300),
    ("table_natural_frequency_hz", 1e-300),
    ("table_damping_ratio", 0.0),
    ("table_damping_ratio", 1e-300),
    ("table_damping_ratio", 1e300),
    ("spacecraft_mass_kg", 1e-6),
    ("spacecraft_mass_kg", 1e300),
    ("initial_gap_m", 1e300),
    ("initial_velocity_m_per_s", 1e300),
    ("initial_velocity_m_per_s", 1e-300),
    ("contact_stiffness_n_per_m", 1e12),
    ("contact_stiffness_n_per_m", 1e-300),
    ("contact_stiffness_n_per_m", 1e300),
    ("force_deadband_n", 1e300),
    ("sensor_delay_s", 1e300),
    ("sensor_delay_s", 1e-300),
    ("lead_time_s", 1e300),
    ("sample_rate_hz", 1e9),
    ("sample_rate_hz", 1e15),
    ("sample_rate_hz", 1e300),
    ("sample_rate_hz", 1e-3),
    ("sample_rate_hz", 1e-300),
)


def _extreme_defects(info, columns, marks) -> list[_Defect]:
    out = []
    for key, value in _EXTREMES:
        c = columns
        if key == "sample_rate_hz":  # a time column that matches the rate
            c = dict(columns, time_s=np.arange(len(columns["time_s"])) / value)
        meta = dict(info, **{key: value})
        out.append(
            _Defect(
                "extreme",
                f"{key}={value:g}",
                _pair(_csv(_rows(c)), _json(meta)),
                "either",
                inputs=_numbers(meta),
            )
        )
    return out


def _contradictory_defects(info, columns, marks) -> list[_Defect]:
    meta = _json(info)
    n = len(columns["time_s"])
    h = 1.0 / info["sample_rate_hz"]
    noise = np.random.default_rng(11).normal(0.0, 2.0, n)

    def defect(what, c, why, meta=meta):
        return _Defect("contradictory", what, _pair(_csv(_rows(c)), meta), "refuse", why=why)

    def cut(lo, hi):
        c = {k: v[lo:hi].copy() for k, v in columns.items()}
        c["time_s"] = np.arange(hi - lo) * h
        return c

    gap_info, gap_columns = _base(initial_gap_m=0.5)
    return [
        defect(
            "dead-sensor-zeros",
            dict(columns, f_mea_n=np.zeros(n), f_comp_n=np.zeros(n)),
            "the table penetrates, the sensor reads 0",
        ),
        defect(
            "dead-sensor-noise",
            dict(columns, f_mea_n=noise, f_comp_n=np.zeros(n)),
            "the table penetrates, the sensor reads noise",
        ),
        defect(
            "position-sign-flipped",
            dict(columns, p_des_m=-columns["p_des_m"], p_act_m=-columns["p_act_m"]),
            "force without penetration",
        ),
        defect(
            "force-sign-flipped",
            dict(columns, f_mea_n=-columns["f_mea_n"]),
            "penetration with a pulling force",
        ),
        defect(
            "both-force-columns-flipped",
            dict(columns, f_mea_n=-columns["f_mea_n"], f_comp_n=-columns["f_comp_n"]),
            "negative forces",
        ),
        defect(
            "starts-in-contact", cut(marks.start + 20, n), "no approach: the CoR cannot be measured"
        ),
        defect("starts-at-the-force-peak", cut(marks.peak, n), "no approach"),
        defect("ends-at-the-force-peak", cut(0, marks.peak), "ends in mid-contact"),
        defect("ends-just-after-touching", cut(0, marks.start + 5), "ends in mid-contact"),
        defect("no-contact", gap_columns, "a 0.5 m gap never closes in 0.9 s", _json(gap_info)),
        defect("no-contact-json-says-2-mm", gap_columns, "never touches"),
    ]


def _file_defects(info, columns, marks) -> list[_Defect]:
    csv, meta = _csv(_rows(columns)), _json(info)
    bad = [r[:] for r in _rows(columns)]
    bad[marks.peak + 1][3] = "nan"
    runs = {}
    for i, (v, comp) in enumerate(((0.06, "none"), (0.08, "SDMDC"), (0.1, "SDMDC")), start=1):
        ri, rc = _base(seed=i, initial_velocity_m_per_s=v, compensator=comp)
        ri["run_id"] = f"fuzz-run{i}"
        runs.update(_pair(_csv(_rows(rc)), _json(ri), f"runs/run{i}"))

    def defect(what, files, expect, args=("run.csv",), why=""):
        return _Defect("files", what, files, expect, tuple(args), why=why)

    return [
        defect("csv-without-json", {"run.csv": csv}, "refuse"),
        defect("json-without-csv", {"run.json": meta}, "refuse", ("run.json",)),
        defect("csv-symlink-loop", _pair(Symlink("run.csv"), meta), "refuse"),
        defect("json-symlink-loop", _pair(csv, Symlink("run.json")), "refuse"),
        defect(
            "two-link-loop-in-a-folder",
            {
                "runs/run.csv": Symlink("other.csv"),
                "runs/other.csv": Symlink("run.csv"),
                "runs/run.json": meta,
            },
            "refuse",
            ("runs",),
        ),
        defect(
            "folder-link-cycle",
            {"runs/run.csv": csv, "runs/run.json": meta, "runs/sub": Symlink(".")},
            "either",
            ("runs",),
            "a folder is not searched below its top",
        ),
        defect("csv-is-a-fifo", _pair(Fifo(), meta), "refuse"),
        defect("json-is-a-fifo", _pair(csv, Fifo()), "refuse"),
        defect(
            "fifo-pair-in-a-folder",
            {"runs/run.csv": Fifo(), "runs/run.json": Fifo()},
            "refuse",
            ("runs",),
        ),
        defect("csv-is-dev-zero", _pair(Symlink("/dev/zero"), meta), "refuse"),
        defect("csv-is-dev-urandom", _pair(Symlink("/dev/urandom"), meta), "refuse"),
        defect("json-is-dev-zero", _pair(csv, Symlink("/dev/zero")), "refuse"),
        defect("csv-is-dev-null", _pair(Symlink("/dev/null"), meta), "refuse"),
        defect("dangling-symlink", _pair(Symlink("gone.csv"), meta), "refuse"),
        defect("csv-unreadable", _pair(Unreadable(csv), meta), "refuse"),
        defect("json-unreadable", _pair(csv, Unreadable(meta)), "refuse"),
        defect("folder-unreadable", {"runs": Unreadable(None)}, "refuse", ("runs",)),
        defect("empty-folder", {"runs": Folder()}, "refuse", ("runs",)),
        defect("folder-without-runs", {"runs/README.txt": b"nothing here\n"}, "refuse", ("runs",)),
        defect(
            "duplicate-run-id",
            {**_pair(csv, meta, "runs/a"), **_pair(csv, meta, "runs/b")},
            "refuse",
            ("runs",),
        ),
        defect("same-run-twice", _pair(csv, meta), "either", ("run.csv", "run.json")),
        defect("no-such-path", _pair(csv, meta), "refuse", ("nothere.csv",)),
        defect("folder-named-csv", {"x.csv": Folder(), "x.json": meta}, "refuse", ("x.csv",)),
        defect("txt-argument", {"run.txt": csv, "run.json": meta}, "refuse", ("run.txt",)),
        defect(
            "good-and-nan-run-in-a-folder",
            {**runs, **_pair(_csv(bad), meta, "runs/run4")},
            "refuse",
            ("runs",),
        ),
        defect("three-good-runs", runs, "ok", ("runs",)),
        defect("base-run", _pair(csv, meta), "ok"),
        defect("base-run-by-its-json", _pair(csv, meta), "ok", ("run.json",)),
    ]


def _long_defects(info, columns, marks) -> list[_Defect]:
    """Long records: the base run followed by free flight, noise only."""
    out = []
    h = 1.0 / info["sample_rate_hz"]
    for seconds in (20, 100):
        extra = int(seconds / h) - len(columns["time_s"]) + 1
        last = {k: v[-1] for k, v in columns.items()}
        lag = last["p_des_m"] - last["p_act_m"]
        j = np.arange(1, extra + 1)
        p_des = last["p_des_m"] + last["v_des_m_per_s"] * h * j
        grown = {
            "time_s": np.arange(len(columns["time_s"]) + extra) * h,
            "p_des_m": np.concatenate([columns["p_des_m"], p_des]),
            "p_act_m": np.concatenate([columns["p_act_m"], p_des - lag]),
            "f_mea_n": np.concatenate(
                [columns["f_mea_n"], np.random.default_rng(5).normal(0, 2.0, extra)]
            ),
            "f_comp_n": np.concatenate([columns["f_comp_n"], np.zeros(extra)]),
            "v_des_m_per_s": np.concatenate(
                [columns["v_des_m_per_s"], np.full(extra, last["v_des_m_per_s"])]
            ),
        }
        out.append(
            _Defect("long", f"record-of-{seconds}-s", _pair(_csv(_rows(grown)), _json(info)), "ok")
        )
    return out


@functools.cache
def _run_defects() -> tuple[_Defect, ...]:
    info, columns = _base()
    marks = _marks(info, columns)
    out: list[_Defect] = []
    for make in (
        _cell_defects,
        _time_defects,
        _text_defects,
        _json_defects,
        _extreme_defects,
        _contradictory_defects,
        _file_defects,
        _long_defects,
    ):
        out += make(info, columns, marks)
    for d in out:
        d.inputs = d.inputs or _numbers(info)
    return tuple(out)


def _run_case(command: str, d: _Defect, extra: tuple[str, ...] = ()) -> Case:
    args = list(d.args) if command != "effects" else ["--rig", d.args[0]]
    return Case(
        f"{command}/{d.klass}/{d.what}",
        d.klass,
        dict(d.files),
        [command, *args, *extra],
        d.expect,
        d.why,
        inputs=list(d.inputs),
    )


#: The run defects ``diagnose`` gets (each costs seconds when accepted).
_DIAGNOSE = (
    "files/base-run",
    "cells/f_mea_n-peak-nan",
    "cells/f_mea_n-peak-inf",
    "cells/p_act_m-peak-abc",
    "cells/f_mea_n-peak-empty",
    "cells/f_mea_n-peak-1e30",
    "cells/p_des_m-peak-1e308",
    "time/two-rows-swapped",
    "time/gap-of-10-ticks",
    "time/csv-at-500-hz-json-1000",
    "encoding/latin-1-byte-in-a-cell",
    "encoding/utf-16-with-bom",
    "encoding/binary-junk",
    "structure/header-only",
    "structure/empty-file",
    "structure/missing-column-f_mea_n",
    "json/invalid-json-truncated",
    "json/a-list",
    "json/missing-spacecraft_mass_kg",
    "json/sample_rate_hz-string-number",
    "json/contact_stiffness_n_per_m-NaN",
    'json/compensator="XYZ"',
    "json/spacecraft_mass_kg=0",
    "extreme/spacecraft_mass_kg=1e+300",
    "extreme/contact_stiffness_n_per_m=1e+12",
    "extreme/table_damping_ratio=1e-300",
    "extreme/sample_rate_hz=1e+09",
    "contradictory/dead-sensor-zeros",
    "contradictory/position-sign-flipped",
    "contradictory/force-sign-flipped",
    "contradictory/starts-in-contact",
    "contradictory/ends-at-the-force-peak",
    "contradictory/no-contact",
    "files/csv-without-json",
    "files/csv-is-a-fifo",
    "files/csv-unreadable",
    "files/empty-folder",
    "files/duplicate-run-id",
)

#: The run defects ``effects --rig`` gets.
_EFFECTS = (
    "files/base-run",
    "cells/f_mea_n-peak-nan",
    "json/invalid-json-truncated",
    "json/spacecraft_mass_kg=-1",
    "extreme/spacecraft_mass_kg=1e+300",
    "extreme/contact_stiffness_n_per_m=1e-300",
    "extreme/initial_velocity_m_per_s=1e+300",
    "contradictory/no-contact",
    "files/csv-without-json",
    "files/csv-is-a-fifo",
    "files/empty-folder",
)


# --- flags ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FlagSpec:
    """A numeric flag of a command, its range as ``--help`` gives it, and the
    command line it is tried in (small grids for the heavy commands).

    ``kind``: a float range (``">0"``, ``">=0"``, ``">0|inf"``, ``"(-1,1)"``),
    ``"list" + range`` for comma-separated lists, or an integer (``"int"``: any,
    ``"int>=0"``, ``"int>=1"``, ``"count"``: a number of workers, where 0 and -1
    may mean "all")."""

    command: str
    flag: str
    kind: str
    base: tuple[str, ...]
    files: str = ""  # "run": the base run pair in the folder
    heavy: bool = False


_RUN_ARGS = ("run.csv",)
_MARGINS = (
    "margins",
    "--compensator",
    "SDMDC",
    "--sensor-delay-s",
    "0.005",
    "--table-response-hz",
    "25",
)


def _comp(scenario: str, *more: str) -> tuple[str, ...]:
    """``compensators`` at the Table 1 point, SDMDC only, no passivity runs, one scenario."""
    return (
        "compensators",
        "--quick",
        "--compensators",
        "SDMDC",
        "--no-passivity",
        "--scenarios",
        scenario,
        *more,
    )


#: The mismatch scenario without its ratios (one ratio unless a case gives them).
_COMP_MISMATCH = _comp("mismatch", "--jobs", "1")


def _margins_without(flag: str) -> tuple[str, ...]:
    args = list(_MARGINS)
    if flag in args:
        i = args.index(flag)
        del args[i : i + 2]
    return tuple(args)


_SIM = ("simulate",)
_REC = ("simulate", "--record", "rec")
_STEWART = ("simulate", "--table", "stewart", "--html", "view.html")

#: Every numeric flag of every command.
FLAG_SPECS: tuple[FlagSpec, ...] = (
    FlagSpec("simulate", "--sensor-delay-s", ">=0", _SIM),
    FlagSpec("simulate", "--table-response-hz", ">0|inf", _SIM),
    FlagSpec("simulate", "--table-damping-ratio", ">=0", _SIM),
    FlagSpec("simulate", "--contact-frequency-hz", ">0", _SIM),
    FlagSpec("simulate", "--contact-stiffness-n-per-m", ">0", _SIM),
    FlagSpec("simulate", "--contact-damping-n-s-per-m", ">=0", _SIM),
    FlagSpec("simulate", "--initial-velocity-m-per-s", ">0", _SIM),
    FlagSpec("simulate", "--initial-gap-m", ">=0", _SIM),
    FlagSpec("simulate", "--lead-time-s", ">=0", (*_SIM, "--compensator", "SDC")),
    FlagSpec(
        "simulate", "--compensator-stiffness-n-per-m", ">0", (*_SIM, "--compensator", "SDMDC")
    ),
    FlagSpec("simulate", "--force-deadband-n", ">=0", _SIM),
    FlagSpec("simulate", "--sample-rate-hz", ">0", _SIM),
    FlagSpec("simulate", "--time-step-s", ">0", _SIM),
    FlagSpec("simulate", "--runs", "int>=1", _REC),
    FlagSpec("simulate", "--velocities", "list>0", _REC),
    FlagSpec("simulate", "--noise-force-n", ">=0", _REC),
    FlagSpec("simulate", "--noise-position-m", ">=0", _REC),
    FlagSpec("simulate", "--noise-ar1", "(-1,1)", _REC),
    FlagSpec("simulate", "--seed", "int", _REC),
    FlagSpec("simulate", "--duration-s", ">0", _REC),
    FlagSpec("simulate", "--magnify", ">0", _STEWART, heavy=True),
    FlagSpec("simulate", "--realtime-rate", ">0", _STEWART, heavy=True),
    FlagSpec("reproduce", "--time-step-s", ">0", ("reproduce",), heavy=True),
    FlagSpec("compare", "--max-lag-s", ">0", ("compare", *_RUN_ARGS), "run"),
    FlagSpec("diagnose", "--max-effects", "int>=0", ("diagnose", *_RUN_ARGS), "run", heavy=True),
    FlagSpec("diagnose", "--workers", "count", ("diagnose", *_RUN_ARGS), "run", heavy=True),
    FlagSpec("compensators", "--prior-ratios", "list>0", _COMP_MISMATCH),
    FlagSpec("compensators", "--force-noise-ratio", ">=0", _comp("noise", "--jobs", "1")),
    FlagSpec("compensators", "--position-noise-ratio", ">=0", _comp("noise", "--jobs", "1")),
    FlagSpec("compensators", "--contact-damping-ratio", ">=0", _comp("damped", "--jobs", "1")),
    FlagSpec("compensators", "--sample-rate-hz", ">0", _comp("noise", "--jobs", "1")),
    FlagSpec("compensators", "--seed", "int", _comp("noise", "--jobs", "1")),
    FlagSpec("compensators", "--jobs", "count", _comp("noise")),
    FlagSpec("margins", "--sensor-delay-s", "list>=0", _margins_without("--sensor-delay-s")),
    FlagSpec(
        "margins", "--table-response-hz", "list>0|inf", _margins_without("--table-response-hz")
    ),
    FlagSpec("margins", "--table-damping-ratio", ">=0", _MARGINS),
    FlagSpec("margins", "--contact-frequency-hz", ">0", _MARGINS),
    FlagSpec("margins", "--contact-stiffness-n-per-m", ">0", _MARGINS),
    FlagSpec("margins", "--contact-damping-n-s-per-m", ">=0", _MARGINS),
    FlagSpec("margins", "--contact-damping-ratio", ">=0", _MARGINS),
    FlagSpec("margins", "--lead-time-s", ">=0", _MARGINS),
    FlagSpec("margins", "--initial-velocity-m-per-s", ">0", (*_MARGINS, "--validate", "1")),
    FlagSpec("margins", "--sample-rate-hz", ">0", _MARGINS),
    FlagSpec("margins", "--pade-order", "int>=1", _MARGINS),
    FlagSpec("margins", "--validate", "int>=0", _MARGINS),
    FlagSpec("margins", "--cor-limit", ">0", _MARGINS),
    FlagSpec("margins", "--operating-delay-s", ">=0", _MARGINS),
    FlagSpec("margins", "--operating-table-hz", ">0|inf", _MARGINS),
    FlagSpec(
        "diagram", "--sample-rates-hz", "list>0", ("diagram", "sampled-rig", "--out-dir", "d")
    ),
)

#: The hostile values every numeric flag gets.
HOSTILE_VALUES = ("0", "-1", "1e-300", "1e300", "inf", "nan", "-0", "", "text", "1" + "0" * 400)


def flag_expect(kind: str, text: str) -> str:
    """``"refuse"`` where ``text`` is certainly not a value of a flag of ``kind``, else ``"either"``."""
    if kind.startswith("list"):
        items = [x.strip() for x in text.split(",") if x.strip()]
        if not items:
            return "refuse"
        worst = [flag_expect(kind[4:], x) for x in items]
        return "refuse" if "refuse" in worst else "either"
    if kind.startswith("int") or kind == "count":
        try:
            n = int(text)
        except ValueError:
            return "refuse"
        if (kind == "int>=0" and n < 0) or (kind == "int>=1" and n < 1):
            return "refuse"
        return "either"
    try:
        x = float(text)
    except ValueError:
        return "refuse"
    return "either" if _in_range(x, kind) else "refuse"


def _run_files() -> dict[str, FileSpec]:
    info, columns = _base()
    return _pair(_csv(_rows(columns)), _json(info))


def _flag_number(text: str) -> list[float]:
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        return []


def _flag_case(spec: FlagSpec, value: str, klass: str = "flags", name: str | None = None) -> Case:
    files = _run_files() if spec.files == "run" else {}
    label = (
        name or (value if len(value) < 24 else value[:8] + f"...({len(value)} chars)") or "empty"
    )
    return Case(
        f"{spec.command}/{klass}/{spec.flag}={label}",
        klass,
        files,
        [*spec.base, f"{spec.flag}={value}"],
        flag_expect(spec.kind, value),
        inputs=_flag_number(value),
        reference=spec.base,
    )


def _list_cases() -> list[Case]:
    """Empty, malformed and enormous lists, names and maps."""
    run = _run_files()
    sim, dg = FlagSpec("simulate", "", "", _REC), ("diagnose", *_RUN_ARGS)
    out: list[Case] = []

    def case(command_line, what, expect, files=None, why=""):
        spoilt = [a for a in command_line if a != what]
        out.append(
            Case(
                f"{command_line[0]}/lists/{what}",
                "lists",
                dict(files or {}),
                list(command_line),
                expect,
                why,
                reference=tuple(spoilt) if len(spoilt) < len(command_line) else None,
            )
        )

    case(["diagnose", *_RUN_ARGS, "--effects="], "--effects=", "refuse", run)
    case(["diagnose", *_RUN_ARGS, "--effects=,,,"], "--effects=,,,", "refuse", run)
    case(["diagnose", *_RUN_ARGS, "--effects=nosuch_effect"], "--effects=nosuch", "refuse", run)
    case([*dg, "--column-map=f_mea_n="], "--column-map=f_mea_n=", "refuse", run)
    for flag in (
        "--scenarios=",
        "--compensators=",
        "--scenarios=XYZ",
        "--compensators=XYZ",
        "--prior-ratios=",
        "--prior-ratios=,",
    ):
        case([*_comp("noise", "--jobs", "1"), flag], flag, "refuse")
    case([*_COMP_MISMATCH, "--prior-ratios=1,,2"], "--prior-ratios=1,,2", "either")
    case(
        [
            "compensators",
            "--seed=-1",
            "--quick",
            "--compensators",
            "SDMDC",
            "--no-passivity",
            "--scenarios",
            "noise",
            "--jobs",
            "1",
        ],
        "--seed=-1",
        "either",
    )
    for flag in (
        "--add=",
        "--add=nosuch",
        "--add=contact_damping:damping_n_s_per_m=nan",
        "--add=contact_damping:damping_n_s_per_m=-1",
        "--add=contact_damping:nosuch=1",
        "--add=:",
        "--column-map=",
        "--column-map==",
        "--column-map=nonsense",
        "--column-map=time_s=nosuchcolumn",
        "--column-map=f_mea_n=f_mea_n,f_mea_n=p_act_m",
    ):
        expect = "either" if flag == "--column-map=" else "refuse"
        case(["compare", *_RUN_ARGS, flag], flag, expect, run)
    case(
        ["compare", *_RUN_ARGS, "--add=contact_damping:damping_n_s_per_m=1e300"],
        "--add=damping-1e300",
        "either",
        run,
    )
    for flag in (
        "--add=",
        "--add=nosuch",
        "--compensator=",
        "--compensator=XYZ",
        "--velocities=",
        "--velocities=,",
    ):
        base = list(sim.base) if flag.startswith("--velocities") else ["simulate"]
        case([*base, flag], flag, "refuse")
    for flag in (
        "--compensator=",
        "--compensator=XYZ",
        "--compensator=SDMDC,SDMDC",
        "--export-compensator=XYZ",
        "--sensor-delay-s=",
        "--table-response-hz=,",
    ):
        args = _margins_without(flag.split("=")[0]) if flag.split("=")[0] in _MARGINS else _MARGINS
        case([*args, flag], flag, "either" if flag.endswith("SDMDC,SDMDC") else "refuse")
    for grid, expect in (
        ("0:0.02:1e9", "either"),
        ("0:0.02:100000000", "either"),
        ("0:0.02:0", "refuse"),
        ("0:0.02:-1", "refuse"),
        ("0.02:0:5", "either"),
        ("0:inf:3", "refuse"),
        ("0:nan:3", "refuse"),
        ("0:1e300:3", "either"),
        ("0:0.02", "refuse"),
        ("::", "refuse"),
        ("0:0.02:3.5", "either"),
        ("1,,2", "either"),
        (",", "refuse"),
    ):
        case(
            [*_margins_without("--sensor-delay-s"), f"--sensor-delay-s={grid}"],
            f"--sensor-delay-s={grid}",
            expect,
        )
    for grid, expect in (
        ("5:200:1e9", "either"),
        ("inf,inf", "either"),
        ("0:200:3", "refuse"),
        ("-5:200:3", "refuse"),
    ):
        case(
            [*_margins_without("--table-response-hz"), f"--table-response-hz={grid}"],
            f"--table-response-hz={grid}",
            expect,
        )
    for flag in ("--sample-rates-hz=", "--sample-rates-hz=,"):
        case(["diagram", "sampled-rig", "--out-dir", "d", flag], flag, "refuse")
    case(["diagram", "nonsense", "--out-dir", "d"], "name-nonsense", "refuse")
    case(["diagram", "", "--out-dir", "d"], "name-empty", "refuse")
    case(["reproduce", "--tables=nosuch.json"], "--tables=nosuch", "refuse")
    case(
        ["reproduce", "--tables=tables.json"],
        "--tables=empty-object",
        "refuse",
        {"tables.json": b"{}\n"},
    )
    case(["reproduce", "--tables=tables.json"], "--tables=fifo", "refuse", {"tables.json": Fifo()})
    return out


def _model_cases() -> list[Case]:
    """``--model`` given something that is not a model file."""
    info, _ = _base()
    out = []
    for command, base in (
        ("simulate", ["simulate"]),
        ("margins", list(_MARGINS)),
        ("compare", ["compare", *_RUN_ARGS]),
    ):
        files = _run_files() if command == "compare" else {}
        for what, spec in (
            ("a-run-json", _json(info)),
            ("invalid-json", b"{"),
            ("empty-object", b"{}\n"),
            ("fifo", Fifo()),
            ("dev-zero", Symlink("/dev/zero")),
        ):
            f = dict(files)
            f["model.json"] = spec
            out.append(
                Case(
                    f"{command}/files/--model-{what}",
                    "files",
                    f,
                    [*base, "--model", "model.json"],
                    "refuse",
                )
            )
    return out


def _output_cases() -> list[Case]:
    """Outputs that cannot or must not be written."""
    run = _run_files()
    base = ["compare", *_RUN_ARGS, "--no-progress"]
    out = []

    def case(what, args, expect, extra=None, why=""):
        files = dict(run, **(extra or {}))
        out.append(Case(f"compare/outputs/{what}", "outputs", files, [*base, *args], expect, why))

    case("json-into-a-missing-folder", ["--json", "no/such/dir/out.json"], "either")
    case("json-is-a-folder", ["--json", "outdir"], "refuse", {"outdir": Folder()})
    case("json-is-the-input-json", ["--json", "run.json", "--force"], "refuse")
    case("json-is-the-input-csv", ["--json", "run.csv", "--force"], "refuse")
    case("json-exists-no-force", ["--json", "old.json"], "refuse", {"old.json": b"{}\n"})
    case(
        "json-into-an-unreadable-folder",
        ["--json", "locked/out.json"],
        "refuse",
        {"locked": Unreadable(None)},
    )
    # Never a system path as an output (an atomic write run by root replaces a
    # device): a link to one inside the case's folder instead.
    case(
        "json-is-a-link-to-dev-full",
        ["--json", "full.json"],
        "refuse",
        {"full.json": Symlink("/dev/full")},
        "it exists",
    )
    case(
        "json-is-a-link-to-dev-full-forced",
        ["--json", "full.json", "--force"],
        "either",
        {"full.json": Symlink("/dev/full")},
        "replacing the link, or one line saying the disk is full",
    )
    case("report-is-a-file", ["--json", "out.json", "--report", "run.csv"], "refuse")
    case("report-holds-the-inputs", ["--json", "out.json", "--report", "."], "refuse")
    case(
        "save-model-is-the-input",
        ["--json", "out.json", "--save-model", "run.json", "--force"],
        "refuse",
    )
    case("json-is-a-fifo", ["--json", "pipe.json"], "refuse", {"pipe.json": Fifo()})
    case(
        "json-is-a-fifo-forced",
        ["--json", "pipe.json", "--force"],
        "either",
        {"pipe.json": Fifo()},
        "replacing the pipe by a file is fine",
    )
    return out


def nominal_case(command: str) -> Case:
    """The command on a valid input with its small settings: what a clean result looks like."""
    base = {
        "simulate": ["simulate"],
        "reproduce": ["reproduce"],
        "compare": ["compare", *_RUN_ARGS],
        "diagnose": ["diagnose", *_RUN_ARGS],
        "effects": ["effects", "--rig", *_RUN_ARGS],
        "compensators": list(_comp("noise", "--jobs", "1")),
        "margins": list(_MARGINS),
        "diagram": ["diagram", "sampled-rig", "--out-dir", "d"],
    }[command]
    files = _run_files() if command in ("compare", "diagnose", "effects") else {}
    return Case(f"{command}/nominal/base", "nominal", files, base, "ok")


def _stdout_cases() -> list[Case]:
    """``--json -``: nothing but JSON on stdout."""
    out = []
    for command in ("simulate", "compare", "effects", "compensators", "margins", "diagram"):
        c = nominal_case(command)
        out.append(
            Case(
                f"{command}/stdout/json-to-stdout",
                "stdout",
                c.files,
                [*c.argv, "--json", "-"],
                "ok",
            )
        )
    return out


def corpus() -> list[Case]:
    """The fixed corpus: every class of hostile input, for every command.

    Returns
    -------
    list of Case
        Unique names; at least 300 ``compare`` cases, 30 ``diagnose`` cases and
        300 flag values (classes ``flags`` and ``lists``).
    """
    defects = _run_defects()
    by_name = {f"{d.klass}/{d.what}": d for d in defects}
    cases = [
        nominal_case(c)
        for c in (
            "simulate",
            "compare",
            "diagnose",
            "effects",
            "compensators",
            "margins",
            "diagram",
        )
    ]
    cases += [_run_case("compare", d) for d in defects]
    cases += [_run_case("diagnose", by_name[n]) for n in _DIAGNOSE]
    effects = [_run_case("effects", by_name[n]) for n in _EFFECTS]
    for c in effects:  # effects reads the rig of a run, never fits it: a run without
        if c.klass == "contradictory":  # a contact still has a rig
            c.expect = "either"
    cases += effects
    cases += [_flag_case(spec, v) for spec in FLAG_SPECS for v in HOSTILE_VALUES]
    cases += _list_cases() + _model_cases() + _output_cases() + _stdout_cases()
    names = [c.name for c in cases]
    assert len(names) == len(set(names)), "case names must be unique"
    return cases


# --- hypothesis -------------------------------------------------------------------------------

_TEXT = st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=6)
_CELL = st.one_of(
    st.sampled_from(_CELL_VALUES + _SPELLINGS),
    st.floats().map(repr),
    st.floats(width=32).map(lambda x: f"{x:g}"),
    st.integers(-(10**30), 10**30).map(str),
    _TEXT,
)
_KEY_VALUE = st.one_of(
    st.floats(),
    st.floats(min_value=1e-300, max_value=1e300),
    st.integers(-(10**20), 10**20),
    _TEXT,
    st.none(),
    st.booleans(),
    st.lists(st.integers(), max_size=2),
)


def _table_expect(rows: list[list[str]], info: dict, marks: _Marks) -> str:
    """``refuse`` where the docs' checks certainly refuse the table and its JSON."""
    if any(_key_expect(k, info.get(k)) == "refuse" for k in _ALL_KEYS):
        return "refuse"
    data = rows[1:]
    if len(data) < 3 or len(data) < marks.end + 5:  # too short, no contact, or mid-contact
        return "refuse"
    if any(_finite_float(c) is None for r in data for c in r):
        return "refuse"
    h = 1.0 / info["sample_rate_hz"]
    t = np.array([float(r[0]) for r in data])
    off_tick = np.abs(t - np.arange(len(t)) * h) > 0.5 * h
    off_step = np.abs(np.diff(t) - h) > 0.015 * h
    if off_tick.any() or off_step.any():
        return "refuse"
    return "either"


_CELL_TEXT = _CELL.filter(lambda v: not any(c in v for c in ',"\n\r'))


@st.composite
def _mutated_run(draw, command: str) -> Case:
    info, columns = _base()
    marks = _marks(info, columns)
    rows = _rows(columns)
    what = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(("cell", "key", "truncate", "drop", "scale_time")))
        if kind == "cell":
            row = draw(st.integers(0, len(rows) - 2)) if len(rows) > 1 else 0
            col = draw(st.integers(0, len(COLUMNS) - 1))
            value = draw(_CELL_TEXT)
            if len(rows) > 1:
                rows[row + 1][col] = value
            what.append(f"cell[{row},{COLUMNS[col]}]={value!r}")
        elif kind == "key":
            key = draw(st.sampled_from(_ALL_KEYS))
            info[key] = draw(_KEY_VALUE)
            what.append(f"{key}={info[key]!r}")
        elif kind == "truncate":
            n = draw(st.integers(0, len(rows) - 1))
            rows = rows[: n + 1]
            what.append(f"first-{n}-rows")
        elif kind == "drop" and len(rows) > 4:
            i = draw(st.integers(1, len(rows) - 2))
            del rows[i]
            what.append(f"drop-row-{i - 1}")
        elif kind == "scale_time":
            factor = draw(st.floats(0.5, 2.0))
            for r in rows[1:]:
                x = _finite_float(r[0])
                r[0] = f"{x * factor:.10g}" if x is not None else r[0]
            what.append(f"time-x{factor:.4g}")
    try:
        expect = _table_expect(rows, info, marks)
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        expect = "refuse"  # the rate is not a positive number
    csv = _csv(rows)
    if draw(st.integers(0, 3)) == 0:  # a quarter of the draws: raw bytes too
        junk = draw(st.binary(min_size=1, max_size=8))
        at = draw(st.integers(0, len(csv)))
        csv = csv[:at] + junk + csv[at:]
        what.append(f"bytes@{at}={junk!r}")
    meta = json.dumps(info, indent=2).encode()
    name = f"{command}/hypothesis/" + ";".join(what)
    return Case(
        name, "hypothesis", _pair(csv, meta), [command, *_RUN_ARGS], expect, inputs=_numbers(info)
    )


def runs_strategy(command: str = "compare") -> st.SearchStrategy[Case]:
    """Cases of ``command`` on the base run with one to three drawn defects (cells,
    JSON values, truncation, a dropped row, a re-scaled time, raw bytes); the
    expectation is ``refuse`` where one of them is certainly invalid."""
    return _mutated_run(command)


_FLAG_VALUE = st.one_of(
    st.sampled_from(HOSTILE_VALUES),
    st.floats().map(repr),
    st.floats(min_value=1e-12, max_value=1e6).map(lambda x: f"{x:.6g}"),
    st.integers(-(10**30), 10**30).map(str),
    _TEXT,
)


def flag_strategy(heavy: bool = False) -> st.SearchStrategy[Case]:
    """Cases of a numeric flag of a command with a drawn value (hostile words,
    any float, huge integers, short text). ``heavy``: also the flags whose
    accepted values cost seconds (Stewart, reproduce, diagnose)."""
    specs = [s for s in FLAG_SPECS if heavy or not s.heavy]
    return st.tuples(st.sampled_from(specs), _FLAG_VALUE).map(
        lambda sv: _flag_case(sv[0], sv[1], "hypothesis")
    )
