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

A rig's own log (other column names, extra columns, another delimiter or
decimal mark, comment lines, other units) is read through a
:class:`~hybridtable.measurement.log_layout.LogLayout`: the values come out in
SI, and a channel that the JSON shows to be in another unit is refused naming
the column and the unit that fits (:mod:`~hybridtable.measurement.log_units`).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

from hybridtable._files import read_user_json, read_user_text, regular_file_problem
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.errors import MeasurementError
from hybridtable.limits import LIMITS
from hybridtable.measurement.channels import check_channels
from hybridtable.measurement.csv_fast import read_float_columns, read_header
from hybridtable.measurement.log_layout import DEFAULT_LAYOUT, LogLayout, parse_pairs
from hybridtable.measurement.log_units import check_units, time_unit_hint
from hybridtable.measurement.run_files import find_run_files
from hybridtable.measurement.run_format import (
    FORMAT,
    MIN_ROWS,
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
    "read_series",
    "check_time",
    "check_unique_ids",
    "find_run_files",
]


# -- column map ----------------------------------------------------------------
def parse_column_map(items: Iterable[str] | None) -> dict[str, str]:
    """Parse ``FORMAT=LOG`` items (each may hold several, comma separated) into
    ``{format_column: log_column}`` (the ``--column-map`` flag; the whole
    mapping of a log is :func:`~hybridtable.measurement.log_layout.log_layout`).

    Raises
    ------
    MeasurementError
        For an item without ``=``, an unknown format column, or a column
        mapped twice.
    """
    mapping = parse_pairs(items, "--column-map", "LOG_COLUMN")
    logs = list(mapping.values())
    twice = [log for log in logs if logs.count(log) > 1]
    if twice:
        raise MeasurementError(f"--column-map: log column {twice[0]!r} is mapped twice")
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


def _parse_cell(text: str, decimal: str = ".") -> float:
    s = text.strip()
    if not s or "_" in s:
        raise ValueError
    if decimal == ",":
        if "." in s:
            raise ValueError
        s = s.replace(",", ".")
    return float(s)


def _rows(lines: list[str], layout: LogLayout) -> Iterator[tuple[int, list[str]]]:
    """``(line number, cells)`` of every row; a comment line is a blank row
    (so the rows keep their numbers)."""
    comment = layout.comment
    if comment is not None:
        lines = ["" if line.lstrip().startswith(comment) else line for line in lines]
    if layout.delimiter == " ":
        yield from enumerate((line.split() for line in lines), start=1)
    else:
        yield from enumerate(csv.reader(lines, delimiter=layout.delimiter), start=1)


def _csv_rows(
    path: Path, layout: LogLayout = DEFAULT_LAYOUT
) -> tuple[list[str], int, list[list[str]], list[int]]:
    """The Python path: the header's cells and file line, every data row's
    cells and file line (blank and comment lines skipped)."""
    text = _read_text(path)
    if not text.strip():
        raise MeasurementError(f"{path}: empty file")
    lines = text.splitlines()
    header: list[str] | None = None
    header_line = 0
    data: list[list[str]] = []
    line_of_row: list[int] = []
    try:
        for i, row in _rows(lines, layout):
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

    def __init__(self, path: Path, layout: LogLayout):
        self._path = path
        self._layout = layout
        self._lines: list[int] | None = None

    def _get(self) -> list[int]:
        if self._lines is None:
            self._lines = _csv_rows(self._path, self._layout)[3]
        return self._lines

    def __getitem__(self, i):
        return self._get()[i]

    def __len__(self) -> int:
        return len(self._get())


def _read_series_fast(
    path: Path, layout: LogLayout
) -> tuple[dict[str, np.ndarray], tuple[str, ...]] | None:
    """Columns by format name read by pyarrow, in the log's units, and the
    log's columns not read; ``None`` if the file is not a plain valid table
    (the Python path then names its defect)."""
    header = read_header(path, layout.delimiter, layout.comment)
    if header is None:
        return None
    try:
        names = format_names(path, header.cells, header.line, layout)
    except MeasurementError:
        return None  # the Python path says it, or a defect before it
    read = [i for i, name in enumerate(names) if name is not None]
    columns = read_float_columns(
        path, header.data_offset_bytes, len(names), layout.delimiter, layout.decimal, read
    )
    if columns is None or len(columns[0]) < MIN_ROWS:
        return None
    skipped = tuple(c for c, name in zip(header.cells, names, strict=True) if name is None)
    return {names[i]: col for i, col in zip(read, columns, strict=True)}, skipped


def _decimal_hint(cell: str, layout: LogLayout) -> str:
    if layout.decimal == "." and "," in cell and "." not in cell:
        return ' (a decimal comma? give --decimal , or decimal = "," in a --log-map file)'
    return ""


def read_series(
    path: Path, layout: LogLayout
) -> tuple[dict[str, np.ndarray], Sequence[int], tuple[str, ...]]:
    """Columns by format name, in SI (the layout's units), the file line
    of every data row and the log's columns not read.

    A plain valid file is read by pyarrow (no Python string per cell; its row
    lines are found only if a message needs them); any other file, and every
    defect, by the Python path, line by line, whose message names the line.
    Only the columns the format reads are parsed.
    """
    fast = _read_series_fast(path, layout) if _FAST_CSV else None
    lines: Sequence[int]
    if fast is not None:
        (cols, skipped), lines = fast, _RowLines(path, layout)
    else:
        cols, lines, skipped = _read_series_python(path, layout)
    for name in layout.format_columns:
        factor = layout.factor(name)
        if factor != 1.0:
            cols[name] = cols[name] * factor
    return {name: cols[name] for name in layout.format_columns}, lines, skipped


def _read_series_python(
    path: Path, layout: LogLayout
) -> tuple[dict[str, np.ndarray], list[int], tuple[str, ...]]:
    header, header_line, data, line_of_row = _csv_rows(path, layout)
    names = format_names(path, header, header_line, layout)
    if not data:
        raise MeasurementError(f"{path}: no data rows after the header")
    if len(data) < MIN_ROWS:
        raise MeasurementError(f"{path}: only {len(data)} data row(s), need at least {MIN_ROWS}")
    ncol = len(header)
    read = [(c, name) for c, name in enumerate(names) if name is not None]
    values = np.empty((len(data), len(read)))
    for r, (row, line) in enumerate(zip(data, line_of_row, strict=True)):
        if len(row) != ncol:
            hint = ""
            if len(row) > ncol and layout.delimiter == "," and layout.decimal == ".":
                hint = " (decimal commas in a comma-separated log cannot be read apart from it)"
            raise MeasurementError(
                f"{path} line {line}: {len(row)} cells, the header has {ncol}{hint}"
            )
        for j, (c, _) in enumerate(read):
            cell = row[c]
            if not cell.strip():
                raise MeasurementError(f"{path} line {line}, column {shown(header[c])}: empty cell")
            try:
                x = _parse_cell(cell, layout.decimal)
            except ValueError:
                raise MeasurementError(
                    f"{path} line {line}, column {shown(header[c])}: not a number "
                    f"({shown(cell.strip())!r}){_decimal_hint(cell, layout)}"
                ) from None
            if not math.isfinite(x):
                raise MeasurementError(
                    f"{path} line {line}, column {shown(header[c])}: not finite "
                    f"({shown(cell.strip())})"
                )
            values[r, j] = x
    cols = {name: values[:, j].copy() for j, (_, name) in enumerate(read)}
    skipped = tuple(c for c, name in zip(header, names, strict=True) if name is None)
    return cols, line_of_row, skipped


def check_time(
    path: Path,
    json_path: Path,
    t: np.ndarray,
    lines: Sequence[int],
    info: RunInfo,
    layout: LogLayout = DEFAULT_LAYOUT,
) -> None:
    """Refuse a ``time_s`` that is not the ticks ``k / sample_rate_hz`` from 0
    (``info`` is anything with ``sample_rate_hz`` and ``sample_period_s``: a
    run's JSON, a 6-DoF run's scenario), naming the file line."""
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
            f"sample_rate_hz = {info.sample_rate_hz:g}{time_unit_hint(h_seen / h, layout)}"
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
    layout: LogLayout | None = None,
) -> Run:
    """Read and validate one run.

    Parameters
    ----------
    csv_path : path
        The time series.
    json_path : path, optional
        Its parameters (default: the CSV's stem with ``.json``).
    column_map : mapping, optional
        ``{format_column: log_column}`` for logs named differently (a
        shorthand of ``layout``, which it overrides).
    layout : LogLayout, optional
        How the log maps to the format (default: the format's own CSV).

    Raises
    ------
    MeasurementError
        For any defect, in one line naming the file and the line or key.
    """
    layout = _layout(layout, column_map)
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
    cols, lines, skipped = read_series(csv_path, layout)
    check_time(csv_path, json_path, cols["time_s"], lines, info, layout)
    return Run(info=info, csv_path=csv_path, json_path=json_path, skipped_columns=skipped, **cols)


def _layout(layout: LogLayout | None, column_map: Mapping[str, str] | None) -> LogLayout:
    """``layout`` with the log names of ``column_map`` over its own."""
    base = layout or DEFAULT_LAYOUT
    if not column_map:
        return base
    try:
        return base.with_columns(column_map, source="--column-map")
    except MeasurementError as err:
        raise MeasurementError(f"--column-map: {err}") from None


def read_runs(
    paths: Sequence[str | Path],
    column_map: Mapping[str, str] | None = None,
    layout: LogLayout | None = None,
) -> list[Run]:
    """Read and validate every run named by ``paths`` (files or folders).

    All runs are read before any is returned, so a defect anywhere stops
    everything. Run ids must be unique, and each run's channels must be in
    the units read (:func:`hybridtable.measurement.log_units.check_units`) and
    agree with each other (:func:`hybridtable.measurement.channels.check_channels`:
    no dead or sign-flipped channel, a contact, a start apart).

    Raises
    ------
    MeasurementError
        For any defect (see :func:`read_run` and :func:`find_run_files`).
    """
    layout = _layout(layout, column_map)
    runs = [read_run(c, j, layout=layout) for c, j in find_run_files(paths)]
    for r in runs:
        check_units(r, layout)
        check_channels(r)
    check_unique_ids(runs)
    return runs


def check_unique_ids(runs: Sequence) -> None:
    """Refuse two runs of one set with the same ``run_id`` (runs of either
    format: ``run_id`` and ``json_path``), naming both files."""
    ids: dict[str, Path | None] = {}
    for r in runs:
        if r.run_id in ids:
            raise MeasurementError(
                f"{r.json_path}: run_id {r.run_id!r} is also the run_id of {ids[r.run_id]}"
            )
        ids[r.run_id] = r.json_path
