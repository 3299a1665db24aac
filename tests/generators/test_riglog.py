"""The rig-log generator against itself: a log it writes, read back with its
own reading of the spec (``read_log``), gives the run's SI columns to 1e-12;
its TOML is the mapping it says; its flags say the same; the JSON is the run's,
byte for byte; layouts the spec does not allow are refused."""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tests.generators.riglog import (
    FORMAT_COLUMNS,
    UNITS,
    Layout,
    flags_of,
    mapping_of,
    random_layout,
    read_log,
    read_run,
    to_toml,
    write_log,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "nominal"
RUN1 = EXAMPLES / "run1.csv"

ALL_TOGETHER = Layout(
    delimiter=";",
    decimal=",",
    comment="#",
    comments_above=2,
    comments_between=3,
    columns={
        "time_s": "Zeit",
        "p_des_m": "x_cmd",
        "p_act_m": "x_act",
        "f_mea_n": "F_sensor",
        "f_comp_n": "F_fed",
        "v_des_m_per_s": "v_cmd",
    },
    units={
        "time_s": "ms",
        "p_des_m": "mm",
        "p_act_m": "mm",
        "f_mea_n": "kN",
        "f_comp_n": "kN",
        "v_des_m_per_s": "mm/s",
    },
    extras=(("temperature_c", "temperature"), ("tick", "tick"), ("f_raw", "raw_force")),
    ignore=("f_raw",),
    shuffle=True,
    seed=3,
)


def _assert_round_trip(csv: Path, mapping: dict, run: Path = RUN1) -> None:
    want = read_run(run)
    got = read_log(csv, mapping)
    assert set(got) == set(FORMAT_COLUMNS)
    for column in FORMAT_COLUMNS:
        np.testing.assert_allclose(got[column], want[column], rtol=1e-12, atol=0, err_msg=column)


def _parse_flags(flags: list[str]) -> dict:
    """The mapping the flags say, read as the spec describes them."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--column-map", action="append", default=[])
    parser.add_argument("--unit", action="append", default=[])
    parser.add_argument("--delimiter")
    parser.add_argument("--decimal")
    parser.add_argument("--comment")
    parser.add_argument("--ignore-column", action="append", default=[])
    args = parser.parse_args(flags)
    mapping: dict = {}
    for key in ("delimiter", "decimal", "comment"):
        if getattr(args, key) is not None:
            mapping[key] = getattr(args, key)
    if args.ignore_column:
        mapping["ignore"] = args.ignore_column
    columns: dict = {}
    for option, key in ((args.column_map, "column"), (args.unit, "unit")):
        for item in ",".join(option).split(",") if option else []:
            column, value = item.split("=")
            columns.setdefault(column, {})[key] = value
    if columns:
        mapping["columns"] = columns
    return mapping


def _normal(mapping: dict) -> dict:
    """A mapping with every column entry as a table."""
    out = dict(mapping)
    if "columns" in out:
        out["columns"] = {
            k: ({"column": v} if isinstance(v, str) else dict(v)) for k, v in out["columns"].items()
        }
    return out


@pytest.mark.parametrize(
    "layout",
    [
        Layout(),
        Layout(extras=(("temperature_c", "temperature"), ("tick", "tick"), ("f_raw", "raw_force"))),
        Layout(delimiter=";", decimal=","),
        Layout(comment="#", comments_above=3, comments_between=4),
        Layout(units={"time_s": "ms"}),
        Layout(units={"time_s": "us"}, columns={"time_s": "Zeit"}),
        Layout(units={"f_mea_n": "kN", "f_comp_n": "mN"}),
        Layout(units={"p_des_m": "mm", "p_act_m": "um"}),
        Layout(units={"p_des_m": "cm", "v_des_m_per_s": "cm/s"}),
        Layout(scales={"f_mea_n": -1.0, "p_act_m": 1.25}),
        Layout(
            columns={"f_mea_n": "F_sensor"},
            extras=(("f_mea_n", "raw_force"),),
            ignore=("f_mea_n",),
        ),
        Layout(extras=(("status", "text"),), delimiter="|"),
        Layout(delimiter="\t", decimal=",", comment="//", comments_above=1),
        Layout(delimiter=" ", comment="%", comments_between=2, shuffle=True, seed=5),
        ALL_TOGETHER,
    ],
    ids=[
        "format",
        "extras",
        "semicolon-decimal-comma",
        "comments",
        "ms",
        "us-renamed",
        "kN-mN",
        "mm-um",
        "cm-cm_per_s",
        "scales",
        "ignored-namesake",
        "text-pipe",
        "tab-comma-slashes",
        "space-percent-shuffled",
        "all-together",
    ],
)
def test_a_log_reads_back_to_the_runs_si_columns(tmp_path, layout):
    log = write_log(RUN1, layout, tmp_path)
    assert log.csv == tmp_path / "run1.csv" and log.json == tmp_path / "run1.json"
    assert tomllib.loads(log.toml.read_text(encoding="utf-8")) == log.mapping
    _assert_round_trip(log.csv, log.mapping)
    _assert_round_trip(log.csv, tomllib.loads(log.toml.read_text(encoding="utf-8")))
    if log.flags is not None:
        assert _normal(_parse_flags(log.flags)) == _normal(log.mapping)
        _assert_round_trip(log.csv, _parse_flags(log.flags))


@pytest.mark.parametrize("seed", range(60))
def test_random_layouts_read_back(tmp_path, seed):
    for flags in (True, False):
        layout = random_layout(seed, flags=flags)
        assert layout == random_layout(seed, flags=flags)  # the seed decides
        log = write_log(RUN1, layout, tmp_path / str(flags))
        mapping = tomllib.loads(log.toml.read_text(encoding="utf-8"))
        assert mapping == log.mapping
        _assert_round_trip(log.csv, mapping)
        if flags:
            assert log.flags is not None
            _assert_round_trip(log.csv, _parse_flags(log.flags))
        else:
            assert log.flags is None  # a scale has no flag


def test_random_layouts_cover_the_spec():
    layouts = [random_layout(seed) for seed in range(60)]
    assert {layout.delimiter for layout in layouts} == {",", ";", "\t", "|", " "}
    assert {layout.decimal for layout in layouts} == {".", ","}
    assert {layout.comment for layout in layouts} == {None, "#", "//", "%"}
    for column, units in UNITS.items():
        assert {layout.unit(column) for layout in layouts} == set(units), column
    assert any(layout.ignore for layout in layouts)
    assert any(layout.shuffle for layout in layouts)


@pytest.mark.parametrize("run", ["run1", "run2", "run3"])
def test_every_example_round_trips_and_its_json_is_unchanged(tmp_path, run):
    log = write_log(EXAMPLES / f"{run}.csv", ALL_TOGETHER, tmp_path)
    assert log.json.read_bytes() == (EXAMPLES / f"{run}.json").read_bytes()
    _assert_round_trip(log.csv, log.mapping, EXAMPLES / f"{run}.csv")


def test_the_all_together_log_looks_like_a_rig_engineers(tmp_path):
    log = write_log(RUN1, ALL_TOGETHER, tmp_path)
    lines = log.csv.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# ") and lines[1].startswith("# ")
    assert lines[2] == ";".join(log.header)
    assert sorted(log.header) == sorted(ALL_TOGETHER.log_names())
    assert log.header != ALL_TOGETHER.log_names()  # shuffled
    assert not set(log.header) & set(FORMAT_COLUMNS)
    assert sorted(log.skipped) == ["f_raw", "temperature_c", "tick"]
    data = [line for line in lines[3:] if not line.startswith("#")]
    assert len(data) == len(read_run(RUN1)["time_s"])
    assert sum(line.startswith("#") for line in lines[3:]) == 3
    assert not any("." in line for line in data)  # decimal commas only
    cells = [line.split(";") for line in data]
    assert all(len(row) == len(log.header) for row in cells)
    time = [float(row[log.header.index("Zeit")].replace(",", ".")) for row in cells]
    assert time[:3] == [0.0, 1.0, 2.0]  # ms
    peak = max(float(row[log.header.index("F_sensor")].replace(",", ".")) for row in cells)
    assert 0.3 < peak < 1.0  # kN
    tick = [int(row[log.header.index("tick")]) for row in cells]
    assert np.all(np.diff(tick) == 1)


def test_the_toml_is_the_specs_example_shape(tmp_path):
    text = to_toml(mapping_of(ALL_TOGETHER))
    assert 'delimiter = ";"' in text and 'decimal = ","' in text and 'comment = "#"' in text
    assert 'ignore = ["f_raw"]' in text
    assert 'time_s = { column = "Zeit", unit = "ms" }' in text
    assert 'v_des_m_per_s = { column = "v_cmd", unit = "mm/s" }' in text
    plain = mapping_of(Layout(columns={"v_des_m_per_s": "v_cmd"}, units={"f_mea_n": "kN"}))
    assert plain == {"columns": {"f_mea_n": {"unit": "kN"}, "v_des_m_per_s": "v_cmd"}}
    tab = tomllib.loads(to_toml(mapping_of(Layout(delimiter="\t"))))
    assert tab == {"delimiter": "\t"}
    assert mapping_of(Layout()) == {}
    assert mapping_of(Layout(explicit_defaults=True, units={"time_s": "s"})) == {
        "delimiter": ",",
        "decimal": ".",
        "columns": {"time_s": {"unit": "s"}},
    }


def test_flags_say_the_mapping():
    mapping = mapping_of(ALL_TOGETHER)
    flags = flags_of(mapping)
    assert flags[:2] == ["--column-map", "time_s=Zeit"]
    assert ["--unit", "f_mea_n=kN"] == flags[
        flags.index("f_mea_n=kN") - 1 : flags.index("f_mea_n=kN") + 1
    ]
    assert flags[-8:] == [
        "--delimiter",
        ";",
        "--decimal",
        ",",
        "--comment",
        "#",
        "--ignore-column",
        "f_raw",
    ]
    joined = flags_of(mapping, joined=True)
    assert joined[:2] == [
        "--column-map",
        "time_s=Zeit,p_des_m=x_cmd,p_act_m=x_act,f_mea_n=F_sensor,f_comp_n=F_fed,v_des_m_per_s=v_cmd",
    ]
    assert flags_of(mapping_of(Layout(scales={"f_mea_n": -1.0}))) is None
    assert flags_of({}) == []


@pytest.mark.parametrize(
    "bad",
    [
        dict(delimiter=":"),
        dict(decimal=";"),
        dict(delimiter=",", decimal=","),
        dict(comments_above=1),
        dict(units={"f_mea_n": "ms"}),
        dict(units={"force": "kN"}),
        dict(scales={"f_mea_n": 0.0}),
        dict(scales={"f_mea_n": float("inf")}),
        dict(columns={"p_des_m": "x", "p_act_m": "x"}),
        dict(extras=(("f_mea_n", "raw_force"),)),
        dict(extras=(("t", "colour"),)),
        dict(ignore=("time_s",)),
        dict(delimiter=";", columns={"time_s": "t;ms"}),
        dict(comment="#", columns={"time_s": "#t"}),
    ],
)
def test_layouts_the_spec_does_not_allow_are_refused(bad):
    with pytest.raises(ValueError):
        Layout(**bad)
