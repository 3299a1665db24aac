"""Reader and validator of recorded runs; every malformed input: one line, exit 2,
nothing written, inputs untouched."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from hybridtable.cli import main
from hybridtable.errors import MeasurementError
from hybridtable.measurement.run_format import RUN_COLUMNS
from hybridtable.measurement.run_reader import parse_column_map, read_run, read_runs
from tests.examples import EXAMPLES


def _pair(tmp_path: Path, stem: str = "run1") -> tuple[Path, Path]:
    d = tmp_path / "runs"
    d.mkdir(exist_ok=True)
    c, j = d / f"{stem}.csv", d / f"{stem}.json"
    shutil.copyfile(EXAMPLES / "run1.csv", c)
    shutil.copyfile(EXAMPLES / "run1.json", j)
    return c, j


def _edit_csv(path: Path, fn) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(fn(lines)) + "\n")


def _edit_json(path: Path, fn) -> None:
    data = json.loads(path.read_text())
    fn(data)
    path.write_text(json.dumps(data))


def _set_cell(line_no: int, column: str, value: str):
    def fn(lines):
        col = lines[0].split(",").index(column)
        cells = lines[line_no - 1].split(",")
        cells[col] = value
        lines[line_no - 1] = ",".join(cells)
        return lines

    return fn


def _drop_column(column: str):
    def fn(lines):
        col = lines[0].split(",").index(column)
        return [",".join(c for i, c in enumerate(line.split(",")) if i != col) for line in lines]

    return fn


def _time_at(line_no: int, value):
    def fn(lines):
        cells = lines[line_no - 1].split(",")
        t = float(cells[0])
        cells[0] = repr(value(t))
        lines[line_no - 1] = ",".join(cells)
        return lines

    return fn


def _swap_times(lines):
    a, b = lines[10].split(","), lines[11].split(",")
    a[0], b[0] = b[0], a[0]
    lines[10], lines[11] = ",".join(a), ",".join(b)
    return lines


def _shift_all_times(lines):
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[0] = repr(float(cells[0]) + 0.5)
        out.append(",".join(cells))
    return out


# (id, csv edit, json edit, expected substring, file named in the message)
CASES = [
    ("missing_column", _drop_column("f_comp_n"), None, "missing column(s) f_comp_n", "csv"),
    (
        "column_named_twice",
        lambda lines: [lines[0] + ",f_comp_n"] + [line + ",0" for line in lines[1:]],
        None,
        "column 'f_comp_n' appears twice",
        "csv",
    ),
    (
        "non_numeric",
        _set_cell(11, "f_mea_n", "1.2.3"),
        None,
        "line 11, column f_mea_n: not a number",
        "csv",
    ),
    ("nan", _set_cell(40, "p_act_m", "nan"), None, "line 40, column p_act_m: not finite", "csv"),
    (
        "inf",
        _set_cell(41, "v_des_m_per_s", "-inf"),
        None,
        "line 41, column v_des_m_per_s: not finite",
        "csv",
    ),
    (
        "empty_cell",
        _set_cell(12, "p_des_m", ""),
        None,
        "line 12, column p_des_m: empty cell",
        "csv",
    ),
    (
        "short_row",
        lambda ls: ls[:20] + [ls[20].rsplit(",", 1)[0]] + ls[21:],
        None,
        "line 21: 5 cells, the header has 6",
        "csv",
    ),
    ("time_not_increasing", _swap_times, None, "line 12: time_s not increasing", "csv"),
    (
        "uneven_sampling",
        _time_at(30, lambda t: t + 0.0003),
        None,
        "line 30: time_s unevenly sampled",
        "csv",
    ),
    ("time_not_from_zero", _shift_all_times, None, "time_s starts at 0.5 s", "csv"),
    (
        "sample_rate_contradicts_json",
        None,
        lambda d: d.update(sample_rate_hz=500),
        "sampled at 1000 Hz but run1.json says sample_rate_hz = 500",
        "csv",
    ),
    ("header_only", lambda ls: ls[:1], None, "no data rows", "csv"),
    (
        "missing_key",
        None,
        lambda d: d.pop("spacecraft_mass_kg"),
        "missing key(s) spacecraft_mass_kg",
        "json",
    ),
    (
        "string_number",
        None,
        lambda d: d.update(sample_rate_hz="1000"),
        'key sample_rate_hz must be a number (got "1000")',
        "json",
    ),
    (
        "bool_number",
        None,
        lambda d: d.update(initial_gap_m=True),
        "key initial_gap_m must be a number (got true)",
        "json",
    ),
    (
        "negative_mass",
        None,
        lambda d: d.update(spacecraft_mass_kg=-1.0),
        "key spacecraft_mass_kg = -1 kg is outside its plausible range 0.001 to 1e+07 kg",
        "json",
    ),
    (
        "number_id",
        None,
        lambda d: d.update(run_id=7),
        "key run_id must be a non-empty string",
        "json",
    ),
    (
        "unknown_compensator",
        None,
        lambda d: d.update(compensator="PID"),
        'unknown compensator "PID"',
        "json",
    ),
    (
        "wrong_format",
        None,
        lambda d: d.update(format="hybridtable-run/2"),
        "key format must be 'hybridtable-run/1'",
        "json",
    ),
]


def _snapshot(paths):
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in paths}


def _run_cli(capsys, tmp_path: Path, args: list[str], inputs: list[Path], expect: str):
    before = _snapshot(inputs)
    out_json = tmp_path / "out" / "result.json"
    report = tmp_path / "report"
    rc = main(["compare", *args, "--json", str(out_json), "--report", str(report)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("hybridtable compare: error: "), err
    assert expect in err, err
    assert not out_json.exists() and not report.exists()
    assert _snapshot(inputs) == before
    return err


@pytest.mark.parametrize(
    "csv_edit,json_edit,expect,named", [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_malformed_run_one_line_exit_2_nothing_written(
    tmp_path, capsys, csv_edit, json_edit, expect, named
):
    c, j = _pair(tmp_path)
    if csv_edit:
        _edit_csv(c, csv_edit)
    if json_edit:
        _edit_json(j, json_edit)
    err = _run_cli(capsys, tmp_path, [str(c)], [c, j], expect)
    assert str(c if named == "csv" else j) in err


@pytest.mark.parametrize("which", ["csv", "json"])
def test_empty_file(tmp_path, capsys, which):
    c, j = _pair(tmp_path)
    target = c if which == "csv" else j
    target.write_bytes(b"")
    err = _run_cli(capsys, tmp_path, [str(c.parent)], [c, j], "empty file")
    assert str(target) in err


def test_invalid_json_names_line(tmp_path, capsys):
    c, j = _pair(tmp_path)
    j.write_text('{\n  "format": "hybridtable-run/1",\n  "run_id": oops\n}\n')
    _run_cli(capsys, tmp_path, [str(c)], [c, j], f"{j} line 3, column 13: not valid JSON")


def test_missing_partner_and_paths(tmp_path, capsys):
    c, j = _pair(tmp_path)
    j.unlink()
    _run_cli(capsys, tmp_path, [str(c)], [c], f"{c}: no run1.json beside it")
    _run_cli(capsys, tmp_path, [str(c.parent)], [c], f"{c}: no run1.json beside it")
    _run_cli(capsys, tmp_path, [str(tmp_path / "nope")], [c], "no such file or folder")
    empty = tmp_path / "empty"
    empty.mkdir()
    _run_cli(capsys, tmp_path, [str(empty)], [c], "folder holds no runs")
    (tmp_path / "notes.txt").write_text("x")
    _run_cli(capsys, tmp_path, [str(tmp_path / "notes.txt")], [c], "not a run file")


def test_duplicate_run_id(tmp_path, capsys):
    c1, j1 = _pair(tmp_path, "a")
    c2, j2 = _pair(tmp_path, "b")
    _run_cli(capsys, tmp_path, [str(c1.parent)], [c1, j1, c2, j2], "run_id 'nominal-run1' is also")


def test_record_without_contact_or_unfinished(tmp_path, capsys):
    c, j = _pair(tmp_path)
    _edit_csv(c, lambda ls: ls[:21])  # 20 ticks: the devices never touch
    _run_cli(capsys, tmp_path, [str(c)], [c, j], "no contact in the record")
    shutil.copyfile(EXAMPLES / "run1.csv", c)
    _edit_csv(c, lambda ls: ls[:201])  # ends in mid-contact
    _run_cli(
        capsys, tmp_path, [str(c)], [c, j], "the contact has not ended; cannot measure the CoR"
    )


def test_outputs_never_write_over_inputs(tmp_path, capsys):
    c, j = _pair(tmp_path)
    before = _snapshot([c, j])
    for args, expect in (
        (["--json", str(j)], "is one of the input files"),
        (["--report", str(c.parent)], "holds input files"),
        (["--report", str(c)], "is a file, not a folder"),
    ):
        assert main(["compare", str(c), *args]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and expect in err, err
    user = tmp_path / "user_folder"
    user.mkdir()
    (user / "thesis.md").write_text("mine")
    assert main(["compare", str(c), "--report", str(user)]) == 2
    assert "not empty" in capsys.readouterr().err
    # --force writes into the user's folder but leaves their other files alone.
    assert main(["compare", str(c), "--report", str(user), "--force", "--no-progress"]) == 0
    assert (user / "report.md").is_file()
    assert _snapshot([c, j]) == before
    assert (user / "thesis.md").read_text() == "mine"


def test_column_map_reads_renamed_log(tmp_path, capsys):
    c, j = _pair(tmp_path)
    reference = read_run(EXAMPLES / "run1.csv")
    _edit_csv(c, lambda ls: [ls[0].replace("f_mea_n", "Force").replace("time_s", "t")] + ls[1:])
    with pytest.raises(MeasurementError, match="missing column"):
        read_run(c)
    mapping = parse_column_map(["f_mea_n=Force,time_s=t"])
    assert mapping == {"f_mea_n": "Force", "time_s": "t"}
    run = read_run(c, column_map=mapping)
    for name in RUN_COLUMNS:
        np.testing.assert_array_equal(getattr(run, name), getattr(reference, name))
    # A map entry whose log column is absent is named in the error.
    with pytest.raises(
        MeasurementError, match=r"--column-map names log column\(s\) not in the header: p_act_m=pos"
    ):
        read_run(c, column_map=parse_column_map(["f_mea_n=Force", "time_s=t", "p_act_m=pos"]))
    for bad, expect in (
        ("f_mea_n", "must be FORMAT_COLUMN=LOG_COLUMN"),
        ("force=f", "not a column of the format"),
        ("f_mea_n=a,f_mea_n=b", "mapped twice"),
    ):
        _run_cli(capsys, tmp_path, [str(c), "--column-map", bad], [c, j], expect)


def test_reordered_columns_are_read_by_name(tmp_path):
    c, j = _pair(tmp_path)

    def reverse(lines):
        return [",".join(reversed(line.split(","))) for line in lines]

    _edit_csv(c, reverse)
    run, ref = read_run(c), read_run(EXAMPLES / "run1.csv")
    np.testing.assert_array_equal(run.f_mea_n, ref.f_mea_n)
    np.testing.assert_array_equal(run.time_s, ref.time_s)


def test_reads_the_example_folder():
    runs = read_runs([EXAMPLES])
    assert [r.run_id for r in runs] == ["nominal-run1", "nominal-run2", "nominal-run3"]
    r = runs[0]
    assert r.n == 966 and r.info.compensator == "none"
    assert r.info.sample_rate_hz == 1000.0 and r.sample_period_s == pytest.approx(1e-3)
    np.testing.assert_allclose(np.diff(r.time_s), 1e-3, rtol=1e-6)
    # Format semantics: v_des[0] is the velocity after tick 0 (no force yet).
    assert r.v_des_m_per_s[0] == r.info.initial_velocity_m_per_s
    assert r.p_des_m[0] == pytest.approx(-r.info.initial_gap_m + 1e-3 * r.v_des_m_per_s[0])
    # Naming the same run twice (CSV and JSON) reads it once.
    assert len(read_runs([EXAMPLES / "run2.csv", EXAMPLES / "run2.json"])) == 1


def test_folder_ignores_other_json_but_not_a_lone_run_json(tmp_path):
    c, j = _pair(tmp_path)
    (c.parent / "results.json").write_text('{"runs": []}\n')
    assert [r.run_id for r in read_runs([c.parent])] == ["nominal-run1"]
    shutil.copyfile(j, c.parent / "b.json")
    with pytest.raises(MeasurementError, match=r"b\.json: no b\.csv beside it"):
        read_runs([c.parent])
