"""Reader and validator of recorded rig runs (``hybridtable-run/1``).

A run is a CSV time series and a JSON file of nominal parameters with the same
stem (``run1.csv`` + ``run1.json``); the format is described in
``docs/run-format.md``. :func:`read_runs` takes files or folders, checks
every pair and returns :class:`~hybridtable.measurement.run_format.Run` objects
(the format's columns, keys and objects are in
:mod:`hybridtable.measurement.run_format`); any defect raises
:class:`MeasurementError` whose message is one line naming the file, the line
(or JSON key) and what is wrong::

    run1.csv line 14, column f_mea_n: not a number ('1.2.3')
    run1.json: key sample_rate_hz must be a number (got "1000")

The CLI prints that line and exits with code 2.

Logs whose columns are named differently are read with a column map
``{format_name: log_name}`` (:func:`parse_column_map` reads the command-line
form ``FORMAT=LOG``).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np

from hybridtable._files import read_user_json, read_user_text, regular_file_problem
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.errors import MeasurementError
from hybridtable.limits import LIMITS
from hybridtable.measurement.channels import check_channels
from hybridtable.measurement.csv_fast import read_float_columns, read_header
from hybridtable.measurement.run_format import (
    FORMAT,
    MIN_ROWS,
    RUN_COLUMNS,
    RUN_KEYS,
    SAMPLE_RATE_TOLERANCE,
    Run,
    RunInfo,
)
from hybridtable.measurement.run_header import format_names, shown

__all__ = [
    "MeasurementError",
    "parse_column_map",
    "read_run",
    "run_info_from_dict",
    "read_runs",
    "find_run_files",
]


# -- column map ----------------------------------------------------------------
def parse_column_map(items: Iterable[str] | None) -> dict[str, str]:
    """Parse ``FORMAT=LOG`` items (each may hold several, comma separated) into
    ``{format_column: log_column}``.

    Raises
    ------
    MeasurementError
        For an item without ``=``, an unknown format column, or a column
        mapped twice.
    """
    mapping: dict[str, str] = {}
    for item in items or ():
        for part in str(item).split(","):
            part = part.strip()
            if not part:
                continue
            if "=" not in part:
                raise MeasurementError(
                    f"--column-map item {part!r} must be FORMAT_COLUMN=LOG_COLUMN "
                    f"(format columns: {', '.join(RUN_COLUMNS)})"
                )
            fmt, log = (s.strip() for s in part.split("=", 1))
            if fmt not in RUN_COLUMNS:
                raise MeasurementError(
                    f"--column-map: {fmt!r} is not a column of the format "
                    f"(one of {', '.join(RUN_COLUMNS)})"
                )
            if not log:
                raise MeasurementError(f"--column-map: empty log column name for {fmt}")
            if fmt in mapping:
                raise MeasurementError(f"--column-map: {fmt} is mapped twice")
            if log in mapping.values():
                raise MeasurementError(f"--column-map: log column {log!r} is mapped twice")
            mapping[fmt] = log
    return mapping


# -- JSON ----------------------------------------------------------------------
def _read_text(path: Path) -> str:
    return read_user_text(path, MeasurementError)


def _read_info(path: Path) -> RunInfo:
    raw = read_user_json(path, MeasurementError)
    return run_info_from_dict(raw, str(path))


def run_info_from_dict(raw: object, path: str) -> RunInfo:
    """A run's JSON object as a checked :class:`RunInfo` (``path`` names it in
    the messages).

    Raises
    ------
    MeasurementError
        For a missing key, a value of the wrong type or out of its range, an
        unknown format or compensator.
    """
    if not isinstance(raw, dict):
        raise MeasurementError(f"{path}: must hold a JSON object (got {type(raw).__name__})")
    missing = [k for k in RUN_KEYS if k not in raw]
    if missing:
        raise MeasurementError(f"{path}: missing key(s) {', '.join(missing)}")
    values: dict = {}
    for key, kind in RUN_KEYS.items():
        v = raw[key]
        if kind == "string":
            if not isinstance(v, str) or not v.strip():
                raise MeasurementError(
                    f"{path}: key {key} must be a non-empty string (got {json.dumps(v)})"
                )
            values[key] = v
            continue
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise MeasurementError(f"{path}: key {key} must be a number (got {json.dumps(v)})")
        x = float(v)
        if not math.isfinite(x):
            raise MeasurementError(f"{path}: key {key} must be finite (got {v})")
        limit = LIMITS[key]
        if not limit.contains(x):
            raise MeasurementError(
                f"{path}: key {key} = {x:g}{'' if limit.unit == '1' else ' ' + limit.unit} "
                f"is outside its plausible range {limit.words()}"
            )
        values[key] = x
    if values["format"] != FORMAT:
        raise MeasurementError(
            f"{path}: key format must be {FORMAT!r} (got {json.dumps(values['format'])})"
        )
    if values["compensator"] not in COMPENSATORS:
        raise MeasurementError(
            f"{path}: key compensator: unknown compensator {json.dumps(values['compensator'])} "
            f"(one of {', '.join(COMPENSATORS)})"
        )
    extra = {k: v for k, v in raw.items() if k not in RUN_KEYS}
    return RunInfo(extra=extra, **values)


# -- CSV -----------------------------------------------------------------------
#: Read a CSV with pyarrow first (:mod:`~hybridtable.measurement.csv_fast`),
#: falling back to the line-precise Python path on any defect; ``False`` forces
#: the Python path (for the benchmark and the tests that compare the two).
_FAST_CSV = True


def _parse_cell(text: str) -> float:
    s = text.strip()
    if not s or "_" in s:
        raise ValueError
    return float(s)


def _csv_rows(path: Path) -> tuple[list[str], int, list[list[str]], list[int]]:
    """The Python path: the header's cells and file line, every data row's
    cells and file line (blank lines skipped)."""
    text = _read_text(path)
    if not text.strip():
        raise MeasurementError(f"{path}: empty file")
    lines = text.splitlines()
    rows = csv.reader(lines)
    header: list[str] | None = None
    header_line = 0
    data: list[list[str]] = []
    line_of_row: list[int] = []
    try:
        for i, row in enumerate(rows, start=1):
            if not row or all(not c.strip() for c in row):
                continue  # blank line
            if header is None:
                header, header_line = [c.strip() for c in row], i
            else:
                data.append(row)
                line_of_row.append(i)
    except csv.Error as err:
        raise MeasurementError(f"{path}: not a CSV file ({err})") from None
    if header is None:
        raise MeasurementError(f"{path}: no header row")
    return header, header_line, data, line_of_row


class _RowLines(Sequence[int]):
    """The file line of every data row of a CSV read by the fast path, found
    on first use by reading the file again line by line: only a message about
    a row needs it, so a valid file never builds the list."""

    def __init__(self, path: Path):
        self._path = path
        self._lines: list[int] | None = None

    def _get(self) -> list[int]:
        if self._lines is None:
            self._lines = _csv_rows(self._path)[3]
        return self._lines

    def __getitem__(self, i):
        return self._get()[i]

    def __len__(self) -> int:
        return len(self._get())


def _read_series_fast(
    path: Path, column_map: Mapping[str, str] | None
) -> dict[str, np.ndarray] | None:
    """Columns by format name read by pyarrow, or ``None`` if the file is not
    a plain valid table (the Python path then names its defect)."""
    header = read_header(path)
    if header is None:
        return None
    try:
        names = format_names(path, header.cells, header.line, column_map)
    except MeasurementError:
        return None  # the Python path says it, or a defect before it
    columns = read_float_columns(path, header.data_offset_bytes, len(names))
    if columns is None or len(columns[0]) < MIN_ROWS:
        return None
    return {name: columns[names.index(name)] for name in RUN_COLUMNS}


def _read_series(
    path: Path, column_map: Mapping[str, str] | None
) -> tuple[dict[str, np.ndarray], Sequence[int]]:
    """Columns by format name and the file line of every data row.

    A plain valid file is read by pyarrow (no Python string per cell; its row
    lines are found only if a message needs them); any other file, and every
    defect, by the Python path, line by line, whose message names the line.
    """
    if _FAST_CSV:
        cols = _read_series_fast(path, column_map)
        if cols is not None:
            return cols, _RowLines(path)
    header, header_line, data, line_of_row = _csv_rows(path)
    names = format_names(path, header, header_line, column_map)
    if not data:
        raise MeasurementError(f"{path}: no data rows after the header")
    if len(data) < MIN_ROWS:
        raise MeasurementError(f"{path}: only {len(data)} data row(s), need at least {MIN_ROWS}")
    ncol = len(header)
    values = np.empty((len(data), ncol))
    for r, (row, line) in enumerate(zip(data, line_of_row, strict=True)):
        if len(row) != ncol:
            raise MeasurementError(f"{path} line {line}: {len(row)} cells, the header has {ncol}")
        for c, cell in enumerate(row):
            if not cell.strip():
                raise MeasurementError(f"{path} line {line}, column {names[c]}: empty cell")
            try:
                x = _parse_cell(cell)
            except ValueError:
                raise MeasurementError(
                    f"{path} line {line}, column {names[c]}: not a number ({shown(cell.strip())!r})"
                ) from None
            if not math.isfinite(x):
                raise MeasurementError(
                    f"{path} line {line}, column {names[c]}: not finite ({shown(cell.strip())})"
                )
            values[r, c] = x
    cols = {name: values[:, names.index(name)].copy() for name in RUN_COLUMNS}
    return cols, line_of_row


def _check_time(path: Path, json_path: Path, t: np.ndarray, lines: Sequence[int], info: RunInfo):
    h = info.sample_period_s
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise MeasurementError(
            f"{path} line {lines[i]}: time_s not increasing ({t[i]:.9g} s after {t[i - 1]:.9g} s)"
        )
    h_seen = float(np.median(dt))
    if abs(h_seen - h) > SAMPLE_RATE_TOLERANCE * h:
        raise MeasurementError(
            f"{path}: time_s is sampled at {1.0 / h_seen:.6g} Hz but {json_path.name} says "
            f"sample_rate_hz = {info.sample_rate_hz:g}"
        )
    uneven = np.flatnonzero(np.abs(dt - h) > SAMPLE_RATE_TOLERANCE * h)
    if uneven.size:
        i = int(uneven[0]) + 1
        raise MeasurementError(
            f"{path} line {lines[i]}: time_s unevenly sampled (step {dt[i - 1]:.6g} s, "
            f"sample period {h:.6g} s)"
        )
    if abs(t[0]) > SAMPLE_RATE_TOLERANCE * h:
        raise MeasurementError(
            f"{path} line {lines[0]}: time_s starts at {t[0]:.9g} s; the format's ticks are "
            "k / sample_rate_hz from 0"
        )
    drift = np.abs(t - h * np.arange(len(t)))
    late = np.flatnonzero(drift > 0.5 * h)
    if late.size:
        i = int(late[0])
        raise MeasurementError(
            f"{path} line {lines[i]}: time_s = {t[i]:.9g} s is not tick {i} at "
            f"{info.sample_rate_hz:g} Hz ({i * h:.9g} s)"
        )


# -- pairs ---------------------------------------------------------------------
def read_run(
    csv_path: str | Path,
    json_path: str | Path | None = None,
    column_map: Mapping[str, str] | None = None,
) -> Run:
    """Read and validate one run.

    Parameters
    ----------
    csv_path : path
        The time series.
    json_path : path, optional
        Its parameters (default: the CSV's stem with ``.json``).
    column_map : mapping, optional
        ``{format_column: log_column}`` for logs named differently.

    Raises
    ------
    MeasurementError
        For any defect, in one line naming the file and the line or key.
    """
    csv_path = Path(csv_path)
    json_path = Path(json_path) if json_path is not None else csv_path.with_suffix(".json")
    for p in (csv_path, json_path):
        problem = regular_file_problem(p)
        if problem == "no such file":
            partner = csv_path if p is json_path else json_path
            raise MeasurementError(
                f"{p}: no such file" + (f" (the partner of {partner})" if partner.is_file() else "")
            )
        if problem:
            raise MeasurementError(f"{p}: {problem}")
    info = _read_info(json_path)
    cols, lines = _read_series(csv_path, column_map)
    _check_time(csv_path, json_path, cols["time_s"], lines, info)
    return Run(info=info, csv_path=csv_path, json_path=json_path, **cols)


def _looks_like_run(path: Path) -> bool:
    """True if ``path`` is a JSON object with the format's ``format`` value."""
    if regular_file_problem(path):
        return False
    try:
        raw = json.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError, RecursionError):
        return False
    return isinstance(raw, dict) and raw.get("format") == FORMAT


def find_run_files(paths: Sequence[str | Path]) -> list[tuple[Path, Path]]:
    """The ``(csv, json)`` pairs named by ``paths``: a CSV or JSON file names its
    pair, a folder every pair in it (sorted by name, not recursive).

    Raises
    ------
    MeasurementError
        For a missing path, a file of another kind, a folder without runs, a
        CSV or run JSON file in a folder without its partner (other JSON files
        in a folder, e.g. results of ``compare --json``, are ignored).
    """
    pairs: list[tuple[Path, Path]] = []
    if not paths:
        raise MeasurementError("no runs given")
    for raw in paths:
        p = Path(raw)
        if p.is_dir():
            try:
                names = list(p.iterdir())
            except OSError as err:
                raise MeasurementError(f"{p}: cannot list the folder ({err.strerror})") from None
            stems = sorted({q.stem for q in names if q.suffix in (".csv", ".json")})
            if not stems:
                raise MeasurementError(f"{p}: folder holds no runs (no .csv/.json pairs)")
            found = len(pairs)
            for stem in stems:
                c, j = p / f"{stem}.csv", p / f"{stem}.json"
                for q in (c, j):
                    problem = regular_file_problem(q)
                    if problem and problem != "no such file":
                        raise MeasurementError(f"{q}: {problem}")
                if not c.is_file():
                    if not _looks_like_run(j):
                        continue  # another JSON file (e.g. results of compare)
                    raise MeasurementError(f"{j}: no {c.name} beside it")
                if not j.is_file():
                    raise MeasurementError(f"{c}: no {j.name} beside it")
                pairs.append((c, j))
            if len(pairs) == found:
                raise MeasurementError(f"{p}: folder holds no runs (no .csv/.json pairs)")
        elif p.is_file() or p.suffix in (".csv", ".json"):
            if p.suffix not in (".csv", ".json"):
                raise MeasurementError(f"{p}: not a run file (expected .csv or .json)")
            c, j = p.with_suffix(".csv"), p.with_suffix(".json")
            if not p.is_file():
                raise MeasurementError(f"{p}: no such file")
            other = j if p == c else c
            if not other.is_file():
                raise MeasurementError(f"{p}: no {other.name} beside it")
            pairs.append((c, j))
        else:
            raise MeasurementError(f"{p}: no such file or folder")
    seen: dict[Path, int] = {}
    unique = []
    for c, j in pairs:
        key = c.resolve()
        if key not in seen:
            seen[key] = len(unique)
            unique.append((c, j))
    return unique


def read_runs(
    paths: Sequence[str | Path], column_map: Mapping[str, str] | None = None
) -> list[Run]:
    """Read and validate every run named by ``paths`` (files or folders).

    All runs are read before any is returned, so a defect anywhere stops
    everything. Run ids must be unique, and each run's channels must agree
    with each other (:func:`hybridtable.measurement.channels.check_channels`:
    no dead or sign-flipped channel, a contact, a start apart).

    Raises
    ------
    MeasurementError
        For any defect (see :func:`read_run` and :func:`find_run_files`).
    """
    runs = [read_run(c, j, column_map) for c, j in find_run_files(paths)]
    for r in runs:
        check_channels(r)
    ids: dict[str, Path | None] = {}
    for r in runs:
        if r.run_id in ids:
            raise MeasurementError(
                f"{r.json_path}: run_id {r.run_id!r} is also the run_id of {ids[r.run_id]}"
            )
        ids[r.run_id] = r.json_path
    return runs
