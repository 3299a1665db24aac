"""The fast (pyarrow) path of the run reader against its line-precise Python
path: on every file the fast path accepts, the same bits; on every file the
Python path rejects, the same one-line message; a valid file never pays for the
Python path or for the line numbers of its rows."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridtable.errors import MeasurementError
from hybridtable.measurement import run_reader
from hybridtable.measurement.csv_fast import DATA_BYTES, read_float_columns, read_header
from hybridtable.measurement.run_format import RUN_COLUMNS
from hybridtable.measurement.run_reader import read_run
from tests.examples import EXAMPLES

HEADER = ",".join(RUN_COLUMNS)


def _write(folder: Path, data: bytes, stem: str = "run1") -> Path:
    """``data`` as a run's CSV beside the examples' run1.json (1 kHz)."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(EXAMPLES / "run1.json", folder / f"{stem}.json")
    path = folder / f"{stem}.csv"
    path.write_bytes(data)
    return path


def _outcome(path: Path, fast: bool):
    """``("ok", columns)`` or ``("error", message)`` of :func:`read_run`."""
    old = run_reader._FAST_CSV
    run_reader._FAST_CSV = fast
    try:
        run = read_run(path)
    except MeasurementError as err:
        return "error", str(err)
    finally:
        run_reader._FAST_CSV = old
    return "ok", run.columns()


def _bits(columns: dict[str, np.ndarray]) -> dict[str, bytes]:
    return {k: np.ascontiguousarray(v, dtype=np.float64).tobytes() for k, v in columns.items()}


def _same(path: Path):
    """Read ``path`` both ways; assert the same message or the same bits."""
    fast, slow = _outcome(path, True), _outcome(path, False)
    assert fast[0] == slow[0], (fast, slow)
    if fast[0] == "error":
        assert fast[1] == slow[1]
        assert "\n" not in fast[1]
    else:
        assert _bits(fast[1]) == _bits(slow[1])
        for v in fast[1].values():
            assert v.dtype == np.float64 and v.flags.writeable and v.flags.c_contiguous
    return fast


@pytest.fixture
def python_path_calls(monkeypatch):
    """How often the line-by-line Python reader ran."""
    calls = []
    original = run_reader._csv_rows

    def spy(path, *args):
        calls.append(path)
        return original(path, *args)

    monkeypatch.setattr(run_reader, "_csv_rows", spy)
    return calls


def _rows(n: int = 8) -> list[list[str]]:
    """The first ``n`` data rows of the examples' run1 (ticks at 1 kHz)."""
    lines = (EXAMPLES / "run1.csv").read_text().splitlines()
    return [line.split(",") for line in lines[1 : n + 1]]


def _csv(rows, eol: str = "\n", header: str = HEADER) -> bytes:
    return (eol.join([header, *(",".join(r) for r in rows)]) + eol).encode()


# -- files the fast path reads ---------------------------------------------------
def _respell(rows):
    """The same numbers spelled otherwise: trailing zeros, exponents, a plus
    sign, leading zeros, spaces and tabs around the cells."""
    out = []
    for i, row in enumerate(rows):
        new = []
        for c, x in enumerate(row):
            k = i + c
            if "e" not in x.lower():
                if "." in x:
                    x += "0" * (k % 2)
                if k % 3 == 0:
                    x += "e0" if k % 2 else "E+00"
            if not x.startswith("-"):
                x = ("", "+", "00")[k % 3] + x
            new.append(("", " ", "\t")[k % 3] + x + ("", "\t ", " ")[(k // 3) % 3])
        out.append(new)
    return out


PLAIN_VARIANTS = {
    "as_written": lambda: _csv(_rows()),
    "crlf": lambda: _csv(_rows(), "\r\n"),
    "lone_cr": lambda: _csv(_rows(), "\r"),
    "bom": lambda: b"\xef\xbb\xbf" + _csv(_rows()),
    "blank_lines": lambda: b"\n\n" + _csv(_rows()).replace(b"\n", b"\n\n", 3) + b"\n\r\n",
    "blank_lines_before_header": lambda: b"\n , \n\r\n" + _csv(_rows()),
    "spaces_in_header": lambda: _csv(
        _rows(), header=" time_s , p_des_m,p_act_m\t,f_mea_n,f_comp_n,v_des_m_per_s"
    ),
    "respelled_numbers": lambda: _csv(_respell(_rows())),
    "no_final_newline": lambda: _csv(_rows())[:-1],
    "reordered": lambda: _csv(
        [r[::-1] for r in _rows()], header=",".join(reversed(list(RUN_COLUMNS)))
    ),
}


@pytest.mark.parametrize("variant", sorted(PLAIN_VARIANTS))
def test_plain_files_are_read_by_pyarrow_to_the_same_bits(tmp_path, python_path_calls, variant):
    path = _write(tmp_path, PLAIN_VARIANTS[variant]())
    fast = _outcome(path, True)
    assert fast[0] == "ok", fast
    assert python_path_calls == []  # neither the rows nor their lines in Python
    reference = _outcome(path, False)
    assert _bits(fast[1]) == _bits(reference[1])
    np.testing.assert_array_equal(fast[1]["time_s"], np.arange(8) * 1e-3)


def test_the_examples_are_read_by_pyarrow_to_the_same_bits(python_path_calls):
    for path in sorted(EXAMPLES.glob("*.csv")):
        fast = _outcome(path, True)
        assert fast[0] == "ok" and python_path_calls == []
        assert _bits(fast[1]) == _bits(_outcome(path, False)[1])
        assert len(fast[1]["time_s"]) == len(path.read_text().splitlines()) - 1
        python_path_calls.clear()


# -- files the fast path leaves to the Python path ---------------------------------
FALLBACK_VARIANTS = {
    "quoted_cells": lambda: _csv([[f'"{c}"' for c in r] for r in _rows()]),
    "commas_only_line": lambda: _csv(_rows()).replace(b"\n", b"\n,,,,,\n", 2),
    "spaces_only_line": lambda: _csv(_rows()).replace(b"\n", b"\n   \n", 2),
    "form_feed_line_break": lambda: _csv(_rows()).replace(b"\n", b"\x0c", 3),
    "quoted_header": lambda: _csv(_rows(), header=HEADER.replace("time_s", '"time_s"')),
}


@pytest.mark.parametrize("variant", sorted(FALLBACK_VARIANTS))
def test_other_valid_files_are_read_by_python_to_the_same_bits(
    tmp_path, python_path_calls, variant
):
    path = _write(tmp_path, FALLBACK_VARIANTS[variant]())
    assert _same(path)[0] == "ok"


# -- defects: the Python path's message, line and all ------------------------------
def _cell(row: int, column: str, text: str):
    """Rows with data row ``row`` (0-based), column ``column`` set to ``text``."""
    rows = _rows()
    rows[row][list(RUN_COLUMNS).index(column)] = text
    return rows


DEFECTS = [
    ("nan", _csv(_cell(3, "p_act_m", "nan")), "line 5, column p_act_m: not finite (nan)"),
    ("inf", _csv(_cell(3, "f_mea_n", "-inf")), "line 5, column f_mea_n: not finite (-inf)"),
    ("overflow", _csv(_cell(2, "f_mea_n", "1e999")), "line 4, column f_mea_n: not finite"),
    ("underscore", _csv(_cell(2, "f_mea_n", "1_0")), "line 4, column f_mea_n: not a number"),
    ("hex", _csv(_cell(2, "f_mea_n", "0x10")), "line 4, column f_mea_n: not a number ('0x10')"),
    ("empty_cell", _csv(_cell(4, "p_des_m", "")), "line 6, column p_des_m: empty cell"),
    ("blank_cell", _csv(_cell(4, "p_des_m", " \t")), "line 6, column p_des_m: empty cell"),
    ("two_points", _csv(_cell(1, "f_comp_n", "1.2.3")), "line 3, column f_comp_n: not a number"),
    ("short_row", _csv([*_rows()[:5], _rows()[5][:5], *_rows()[6:]]), "line 7: 5 cells"),
    ("long_row", _csv([*_rows()[:5], [*_rows()[5], "1"], *_rows()[6:]]), "line 7: 7 cells"),
    ("not_utf8", _csv(_rows()).replace(b"0.001,", b"0.001\xff,", 1), "not a UTF-8 text file"),
    ("nul", _csv(_rows()).replace(b"0.001,", b"0.001\x00,", 1), "line 3, column time_s"),
    ("header_only", _csv([]), "no data rows after the header"),
    ("two_rows", _csv(_rows(2)), "only 2 data row(s), need at least 3"),
    ("empty", b"", "empty file"),
    ("blank", b" \n\r\n", "empty file"),
    ("missing_column", _csv(_rows(), header=HEADER.replace("f_mea_n", "force")), "f_mea_n=force"),
    (
        # The time defect is found after pyarrow read the file: the line of the
        # row is counted then, blank lines and all.
        "time_after_blank_lines",
        b"\n" + _csv(_cell(5, "time_s", "0.0052")).replace(b"\n", b"\n\n", 4),
        "line 12: time_s unevenly sampled",
    ),
    ("time_crlf", _csv(_cell(5, "time_s", "0.0052"), "\r\n"), "line 7: time_s unevenly sampled"),
    ("time_lone_cr", _csv(_cell(6, "time_s", "0.005"), "\r"), "line 8: time_s not increasing"),
    ("time_start", _csv([[f"{float(r[0]) + 1:.3f}", *r[1:]] for r in _rows()]), "starts at 1 s"),
]


@pytest.mark.parametrize("data,expect", [d[1:] for d in DEFECTS], ids=[d[0] for d in DEFECTS])
def test_every_defect_gets_the_python_paths_one_line_message(tmp_path, data, expect):
    path = _write(tmp_path, data)
    kind, message = _same(path)
    assert kind == "error"
    assert message.startswith(str(path)) and expect in message, message


def test_a_field_longer_than_the_csv_limit_is_refused_like_the_python_path(tmp_path):
    # A finite number longer than csv.field_size_limit(): pyarrow would read it,
    # the Python path refuses the file, so the fast path must too.
    limit = csv.field_size_limit()
    try:
        for new_limit, length in ((limit, limit + 10), (50, 60), (50, 40)):
            csv.field_size_limit(new_limit)
            long_zero = "0." + "0" * (length - 2)
            path = _write(tmp_path / f"{new_limit}_{length}", _csv(_cell(2, "f_comp_n", long_zero)))
            kind, message = _same(path)
            if length > new_limit:
                assert kind == "error" and "field larger than field limit" in message, message
            else:
                assert kind == "ok"
    finally:
        csv.field_size_limit(limit)


# -- the proofs: pyarrow and float() agree on the fast path's alphabet ---------------
CELL_ALPHABET = DATA_BYTES.decode().replace(",", "").replace("\r", "").replace("\n", "")


def _python_cell(text: str) -> float | None:
    try:
        x = run_reader._parse_cell(text)
    except ValueError:
        return None
    return x if np.isfinite(x) else None


@settings(max_examples=400, deadline=None)
@given(cell=st.text(alphabet=CELL_ALPHABET, max_size=14))
def test_a_cell_of_the_fast_alphabet_is_read_alike_or_left_to_python(tmp_path_factory, cell):
    path = tmp_path_factory.mktemp("cell") / "x.csv"
    path.write_bytes(f"a,b\n{cell},1\n".encode())
    header = read_header(path)
    got = read_float_columns(path, header.data_offset_bytes, 2)
    want = _python_cell(cell)
    if want is None:
        assert got is None  # Python refuses it (or it is not finite): so does the fast path
    else:
        assert got is not None, cell
        assert got[0].tobytes() == np.float64(want).tobytes(), cell


SPELLINGS = ["{!r}", "{:.17g}", "{:.9g}", "{:e}", "{:.3E}", "{:+}", " {:.12g}\t", "{:.20f}"]


def _spelled(x: float, fmt: str) -> str:
    """``x`` written by ``fmt``, or by ``repr`` where ``fmt`` rounds it to infinity."""
    text = fmt.format(x)
    return text if np.isfinite(float(text)) else repr(x)


@settings(max_examples=150, deadline=None)
@given(
    values=st.lists(
        st.tuples(
            st.floats(allow_nan=False, allow_infinity=False, width=64),
            st.sampled_from(SPELLINGS),
        ),
        min_size=5 * 8,
        max_size=5 * 8,
    )
)
def test_any_finite_number_reads_to_the_same_bits_both_ways(tmp_path_factory, values):
    rows = []
    for i, row in enumerate(_rows()):
        cells = values[5 * i : 5 * i + 5]
        rows.append([row[0], *(_spelled(x, fmt) for x, fmt in cells)])
    path = _write(tmp_path_factory.mktemp("numbers"), _csv(rows))
    fast, slow = _outcome(path, True), _outcome(path, False)
    assert fast[0] == slow[0] == "ok"
    assert _bits(fast[1]) == _bits(slow[1])


#: What the mutations insert: the fast path's bytes, the words and spellings the
#: two parsers treat differently, quotes, other line breaks, non-UTF-8 bytes.
TOKENS = [
    *(bytes([b]) for b in DATA_BYTES),
    b"\r\n",
    b'"',
    b"_",
    b"nan",
    b"inf",
    b"x",
    b"0x10",
    b"1_0",
    b"+.5",
    b"1e999",
    b"\x00",
    b"\xff",
    b"\xef\xbb\xbf",
    b"\x0b",
    b"\xc2\x85",
    b"\xe2\x80\xa8",
    b",,,,,\n",
    b"   \n",
    b"\n\n",
]


@settings(max_examples=400, deadline=None)
@given(
    edits=st.lists(
        st.tuples(
            st.floats(min_value=0.0, max_value=1.0),
            st.integers(min_value=0, max_value=3),
            st.sampled_from(TOKENS),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_a_mutated_file_gives_the_same_message_or_the_same_bits(tmp_path_factory, edits):
    data = bytearray(_csv(_rows(6)))
    for where, drop, token in edits:
        i = int(where * len(data))
        data[i : i + drop] = token
    _same(_write(tmp_path_factory.mktemp("mutated"), bytes(data)))
