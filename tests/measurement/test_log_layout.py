"""A rig's own log read through a LogLayout: the same run, whatever the layout;
every wrong unit named against the run's JSON (measurement.log_layout, log_units)."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.measurement import run_reader
from hybridtable.measurement.log_layout import (
    DEFAULT_LAYOUT,
    UNITS,
    ColumnSource,
    LogLayout,
    log_layout,
    read_log_map,
)
from hybridtable.measurement.log_units import check_units
from hybridtable.measurement.run_format import RUN_COLUMNS
from hybridtable.measurement.run_reader import read_run, read_runs

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "nominal"


@pytest.fixture(scope="module")
def original():
    return read_run(EXAMPLES / "run1.csv")


def _write_log(folder: Path, run, layout: LogLayout, extra: bool = True) -> Path:
    """``run`` written as a log of ``layout`` (values divided by the layout's
    factors, a comment line above the header, extra columns first)."""
    folder.mkdir(parents=True, exist_ok=True)
    names = [layout.columns[c].column for c in RUN_COLUMNS]
    cols = [getattr(run, c) / layout.factor(c) for c in RUN_COLUMNS]
    header = (["temperature_c", "tick"] if extra else []) + names
    lines = [] if layout.comment is None else [f"{layout.comment} logger v2, rig B"]
    lines.append(layout.delimiter.join(header))
    for k in range(run.n):
        cells = (["21.5", str(k)] if extra else []) + [repr(float(c[k])) for c in cols]
        if layout.decimal == ",":
            cells = [c.replace(".", ",") for c in cells]
        lines.append(layout.delimiter.join(cells))
        if layout.comment is not None and k == 5:
            lines.append(f"{layout.comment} operator note")
    path = folder / "run1.csv"
    path.write_text("\n".join(lines) + "\n")
    shutil.copyfile(EXAMPLES / "run1.json", folder / "run1.json")
    return path


LAYOUTS = {
    "extra_columns": LogLayout(),
    "semicolon_decimal_comma": LogLayout(delimiter=";", decimal=","),
    "tab_comments": LogLayout(delimiter="\t", comment="#"),
    "space": LogLayout(delimiter=" "),
    "units": LogLayout(
        columns={
            "time_s": ColumnSource("t", "ms"),
            "p_des_m": ColumnSource("x_cmd", "mm"),
            "p_act_m": ColumnSource("x_act", "um"),
            "f_mea_n": ColumnSource("Fz", "kN"),
            "f_comp_n": ColumnSource("F_comp", "mN"),
            "v_des_m_per_s": ColumnSource("v", "mm/s", scale=-1.0),
        },
        delimiter="|",
        comment="//",
    ),
}


@pytest.mark.parametrize("fast", [True, False], ids=["pyarrow", "python"])
@pytest.mark.parametrize("name", list(LAYOUTS))
def test_a_log_of_any_layout_reads_to_the_run(tmp_path, original, monkeypatch, name, fast):
    layout = LAYOUTS[name]
    path = _write_log(tmp_path, original, layout)
    monkeypatch.setattr(run_reader, "_FAST_CSV", fast)
    (run,) = read_runs([path], layout=layout)
    for c in RUN_COLUMNS:
        np.testing.assert_allclose(getattr(run, c), getattr(original, c), rtol=1e-14, atol=0)
    assert run.skipped_columns == ("temperature_c", "tick")


def test_the_fast_and_python_paths_agree_bit_for_bit_on_a_decimal_comma_log(tmp_path, original):
    layout = LAYOUTS["semicolon_decimal_comma"]
    path = _write_log(tmp_path, original, layout)
    runs = {}
    for fast in (True, False):
        old = run_reader._FAST_CSV
        run_reader._FAST_CSV = fast
        try:
            runs[fast] = read_run(path, layout=layout)
        finally:
            run_reader._FAST_CSV = old
    for c in RUN_COLUMNS:
        assert getattr(runs[True], c).tobytes() == getattr(runs[False], c).tobytes()


@pytest.mark.parametrize("column", [c for c in RUN_COLUMNS if c != "time_s"])
def test_every_channel_in_every_other_unit_is_named_with_the_unit_that_fits(original, column):
    units = UNITS[RUN_COLUMNS[column]]
    for unit, factor in units.items():
        if factor == 1.0:
            continue
        # the log holds the channel in `unit`, read as SI
        run = dataclasses.replace(original, **{column: getattr(original, column) / factor})
        with pytest.raises(MeasurementError) as err:
            check_units(run, DEFAULT_LAYOUT)
        message = str(err.value)
        assert f"{column} (read in {RUN_COLUMNS[column]})" in message
        assert f"--unit {column}={unit}" in message
        assert "\n" not in message


def test_the_stated_units_of_a_correct_log_pass_and_a_wrong_statement_is_named(original):
    check_units(original, DEFAULT_LAYOUT)
    # the log is in N, the user said kN: the values come out 1000x
    run = dataclasses.replace(original, f_mea_n=original.f_mea_n * 1e3)
    with pytest.raises(MeasurementError, match=r"f_mea_n \(read in kN\).*like N"):
        check_units(run, log_layout(units=["f_mea_n=kN"]))


def test_several_wrong_units_are_named_in_one_line(original):
    run = dataclasses.replace(
        original, p_des_m=original.p_des_m * 1e3, p_act_m=original.p_act_m * 1e3
    )
    with pytest.raises(MeasurementError) as err:
        check_units(run, DEFAULT_LAYOUT)
    assert "--unit p_des_m=mm,p_act_m=mm" in str(err.value)


def test_time_in_ms_read_as_s_is_named(tmp_path, original):
    layout = LogLayout(columns={"time_s": ColumnSource("t_ms", "ms")})
    path = _write_log(tmp_path, original, layout)
    with pytest.raises(
        MeasurementError, match=r"time_s \(log column 't_ms', read in s\) looks like ms"
    ):
        read_run(path, column_map={"time_s": "t_ms"})
    assert read_run(path, layout=layout).n == original.n


def test_a_log_map_file_reads_and_each_bad_entry_is_one_line(tmp_path):
    good = tmp_path / "rig.toml"
    good.write_text(
        'delimiter = "\\t"\ndecimal = ","\ncomment = "#"\nignore = ["tick"]\n'
        '[columns]\ntime_s = { column = "t", unit = "ms" }\nf_mea_n = "Fz"\n'
        'v_des_m_per_s = { unit = "mm/s", scale = -1 }\n'
    )
    layout = log_layout(log_map=good, units=["f_mea_n=kN"], delimiter=";")
    assert layout.delimiter == ";" and layout.decimal == "," and layout.comment == "#"
    assert layout.columns["time_s"] == ColumnSource("t", "ms")
    assert layout.columns["f_mea_n"] == ColumnSource("Fz", "kN")
    assert layout.factor("v_des_m_per_s") == -1e-3
    assert read_log_map(good)["ignore"] == ("tick",)
    bad = {
        'columns = { time_s = { unit = "min" } }': "unknown unit 'min' for time_s",
        'columns = { f_mea = "Fz" }': "'f_mea' is not a column of the format",
        'columns = { f_mea_n = { column = "Fz", scale = 0 } }': "scale of f_mea_n",
        'delimiter = "::"': "delimiter '::'",
        'decimal = ","': "a decimal comma needs another delimiter",
        "colour = 1": "unknown key 'colour'",
        'columns = { f_mea_n = "F", f_comp_n = "F" }': "log column 'F' is read for",
        'ignore = ["time_s"]': "column 'time_s' is both read and ignored",
    }
    for text, words in bad.items():
        path = tmp_path / "bad.toml"
        path.write_text(text + "\n")
        with pytest.raises(MeasurementError) as err:
            log_layout(log_map=path)
        assert words in str(err.value) and str(path) in str(err.value)
        assert "\n" not in str(err.value)
    with pytest.raises(MeasurementError, match="--unit: unknown unit 'kn' for f_mea_n"):
        log_layout(units=["f_mea_n=kn"])


def test_without_a_mapping_the_format_is_read_as_before(original):
    assert log_layout() is DEFAULT_LAYOUT and DEFAULT_LAYOUT.plain
    assert original.skipped_columns == ()
