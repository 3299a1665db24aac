"""The fast path of the run reader: a CSV of plain numbers read by pyarrow.

:func:`read_header` finds the header row (the first line that is neither blank
nor a comment, read with :mod:`csv` like the line-precise reader of
:mod:`hybridtable.measurement.run_reader`) and where the data start;
:func:`read_float_columns` reads the data as float64 columns with
``pyarrow.csv`` (multi-threaded, no Python string per cell). Neither raises on
a bad file: each returns ``None`` whenever the file is anything but a plain,
valid table, and the caller then reads the file with its line-precise Python
path, which names the defect. So the fast path only accepts files that the
Python path reads to the same bits:

- the data hold only the bytes ``0-9 . e E + - ,``, space, tab, CR, LF and
  the delimiter (no comment line, no quotes, no ``nan``/``inf`` words, no ``_``, no other line breaks of
  :meth:`str.splitlines`, nothing outside ASCII): on that alphabet pyarrow and
  :func:`float` accept the same cells (after trimming spaces and tabs) and
  both round correctly;
- every value is finite (``1e999`` parses to infinity);
- no stretch without a separator is long enough to exceed
  :func:`csv.field_size_limit`, which the Python path enforces.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["CsvHeader", "read_header", "read_float_columns"]

#: The bytes a data section read by the fast path may hold.
DATA_BYTES = b"0123456789.eE+-, \t\r\n"

_BOM = b"\xef\xbb\xbf"

#: Characters :meth:`str.splitlines` breaks at besides CR and LF, and the quote
#: (a quoted field may span lines): a header section holding one is left to the
#: Python path.
_UNUSUAL = frozenset('\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"\x00')

#: Bytes read from the file's start to find the header row.
HEADER_BYTES = 1 << 16

#: Bytes per read of the data section's byte check.
_CHUNK_BYTES = 1 << 22


@dataclass(frozen=True)
class CsvHeader:
    """The header row of a CSV file.

    Attributes
    ----------
    cells : list of str
        Its cells, stripped of surrounding whitespace.
    line : int
        Its file line (1-based, counted like :meth:`str.splitlines`).
    data_offset_bytes : int
        Byte offset of the first byte after its line break.
    """

    cells: list[str]
    line: int
    data_offset_bytes: int


def _next_break(data: bytes, start: int) -> tuple[int, int] | None:
    """Start and end (bytes) of the first line break at or after ``start``:
    LF, CR or CRLF; ``None`` if there is none or a CR ends ``data``."""
    ends = [i for i in (data.find(b"\n", start), data.find(b"\r", start)) if i >= 0]
    if not ends:
        return None
    i = min(ends)
    if data[i : i + 1] == b"\r":
        if i + 1 == len(data):
            return None  # CR or CRLF: the next byte decides
        return i, i + (2 if data[i + 1 : i + 2] == b"\n" else 1)
    return i, i + 1


def read_header(
    path: str | Path, delimiter: str = ",", comment: str | None = None
) -> CsvHeader | None:
    """The header row of the CSV file ``path``, or ``None`` where the fast path
    does not apply.

    Parameters
    ----------
    path : path
        The CSV file (UTF-8, an optional BOM).
    delimiter : str
        Its cell delimiter (a space delimiter is left to the Python path).
    comment : str, optional
        Lines starting with it (after leading blanks) are skipped.

    Returns
    -------
    CsvHeader or None
        ``None`` if the file cannot be read, the header is not within its first
        :data:`HEADER_BYTES` bytes or is not followed by a line break, or the
        lines up to it are not UTF-8 or hold a quote, a NUL or a line break of
        :meth:`str.splitlines` other than CR and LF.
    """
    if delimiter == " ":
        return None
    try:
        with open(path, "rb") as f:
            prefix = f.read(HEADER_BYTES)
    except OSError:
        return None
    pos = len(_BOM) if prefix.startswith(_BOM) else 0
    line = 0
    while True:
        brk = _next_break(prefix, pos)
        if brk is None:
            return None
        try:
            text = prefix[pos : brk[0]].decode("utf-8")
        except UnicodeDecodeError:
            return None
        if not _UNUSUAL.isdisjoint(text):
            return None
        line += 1
        pos = brk[1]
        if comment is not None and text.lstrip().startswith(comment):
            continue
        try:
            row = next(csv.reader([text], delimiter=delimiter), [])
        except csv.Error:
            return None
        if row and any(c.strip() for c in row):
            return CsvHeader([c.strip() for c in row], line, pos)


def _plain_bytes(path: str | Path, offset_bytes: int, delimiter: str = ",") -> bool:
    """True if the file from ``offset_bytes`` on holds only :data:`DATA_BYTES`
    and the ``delimiter``, and has no field longer than :func:`csv.field_size_limit`.

    The field check is conservative: the section is cut into tiles of half the
    limit (at most 64 KiB), and every tile must hold a separator (the
    delimiter, CR or LF); a field longer than the limit would cover a whole tile.
    """
    allowed = DATA_BYTES + delimiter.encode()
    sep = delimiter.encode()
    tile = max(1, min(csv.field_size_limit() // 2, 1 << 16))
    chunk_bytes = tile * max(1, _CHUNK_BYTES // tile)
    try:
        with open(path, "rb") as f:
            f.seek(offset_bytes)
            while chunk := f.read(chunk_bytes):
                if chunk.translate(None, allowed):
                    return False
                for k in range(0, len(chunk), tile):
                    end = k + tile
                    if end > len(chunk):
                        break  # a partial last tile: a longer field covers a whole one
                    if (
                        chunk.find(sep, k, end) < 0
                        and chunk.find(b"\n", k, end) < 0
                        and chunk.find(b"\r", k, end) < 0
                    ):
                        return False
    except OSError:
        return False
    return True


def read_float_columns(
    path: str | Path,
    offset_bytes: int,
    n_columns: int,
    delimiter: str = ",",
    decimal: str = ".",
    include: list[int] | None = None,
) -> list[np.ndarray] | None:
    """The data section of a CSV file as float64 columns, or ``None`` on any
    defect.

    Parameters
    ----------
    path : path
        The CSV file.
    offset_bytes : int
        Byte offset of its first data line (:attr:`CsvHeader.data_offset_bytes`).
    n_columns : int
        Number of cells every data row must have.
    delimiter, decimal : str
        The cell delimiter and the decimal mark.
    include : list of int, optional
        The columns to read (default all); the others are not parsed.

    Returns
    -------
    list of numpy.ndarray or None
        One writable, contiguous float64 array per column read (in file order), all
        values finite; empty lines are skipped. ``None`` if the section holds a
        byte outside :data:`DATA_BYTES`, a field longer than the csv module's
        limit, a cell pyarrow cannot parse as a number (an empty one too), a row
        of another length, a value that is not finite, or no row at all.
    """
    import pyarrow as pa
    import pyarrow.csv as pa_csv

    if delimiter == " " or not _plain_bytes(path, offset_bytes, delimiter):
        return None
    names = [f"c{i}" for i in range(n_columns)]
    read = names if include is None else [names[i] for i in include]
    try:
        with pa.OSFile(str(path)) as f:
            f.seek(offset_bytes)
            table = pa_csv.read_csv(
                f,
                read_options=pa_csv.ReadOptions(column_names=names),
                parse_options=pa_csv.ParseOptions(
                    delimiter=delimiter,
                    quote_char=False,
                    escape_char=False,
                    newlines_in_values=False,
                    ignore_empty_lines=True,
                ),
                convert_options=pa_csv.ConvertOptions(
                    column_types={n: pa.float64() for n in read},
                    include_columns=read,
                    decimal_point=decimal,
                    null_values=[],
                    strings_can_be_null=False,
                    quoted_strings_can_be_null=False,
                ),
            )
    except (pa.ArrowException, OSError):
        return None
    if table.num_rows == 0 or table.num_columns != len(read):
        return None
    columns: list[np.ndarray] = []
    for name in read:
        # One column at a time, dropped from the table as soon as it is copied
        # out, so the table and the arrays are not both held whole.
        values = table.column(name).to_numpy(zero_copy_only=False)
        table = table.drop_columns([name])
        if not (values.flags.writeable and values.flags.c_contiguous):
            values = np.array(values, dtype=np.float64)
        if values.dtype != np.float64 or not np.isfinite(values).all():
            return None
        columns.append(values)
    return columns
