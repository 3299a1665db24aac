"""``hybridtable compare`` reading a rig's own log (docs/run-format.md, "Reading a
rig's own log"), tested from the spec with an independent generator
(``tests/generators/riglog.py``, which imports nothing from ``hybridtable``):

- a run written as a rig engineer's log (other names, extra columns, ``;`` and
  decimal commas, ``#`` comments, ms, kN, mm, mm/s, shuffled, sign-flipped or
  calibrated channels) and read with ``--log-map FILE`` or the equivalent flags
  gives the same numbers as the run itself (to 1e-9 relative), and ``--json``
  lists the mapping and the skipped columns under ``log_map``;
- every wrong mapping is exit code 2 and one line on stderr naming the file,
  the column at fault and, for a unit, the unit that fits;
- the user's files (log, JSON, mapping, the examples) are never modified.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import re
import shutil
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from hybridtable.cli import main
from tests.generators.riglog import (
    FORMAT_COLUMNS,
    UNITS,
    Layout,
    RigLog,
    flags_of,
    mapping_of,
    random_layout,
    write_log,
    write_toml,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "nominal"

#: Log column names that no message could hold by chance (none holds a unit).
NAMES = {
    "time_s": "Zeit",
    "p_des_m": "x_cmd",
    "p_act_m": "x_act",
    "f_mea_n": "F_sensor",
    "f_comp_n": "F_fed",
    "v_des_m_per_s": "v_cmd",
}
EXTRAS = (("temperature_c", "temperature"), ("tick", "tick"), ("f_raw", "raw_force"))

ALL_TOGETHER = Layout(
    delimiter=";",
    decimal=",",
    comment="#",
    comments_above=2,
    comments_between=3,
    columns=NAMES,
    units={
        "time_s": "ms",
        "p_des_m": "mm",
        "p_act_m": "mm",
        "f_mea_n": "kN",
        "f_comp_n": "kN",
        "v_des_m_per_s": "mm/s",
    },
    extras=EXTRAS,
    ignore=("f_raw",),
    shuffle=True,
    seed=3,
)

#: diagnose kept short: one candidate effect, one worker.
DIAGNOSE_ARGS = ["--effects", "force_bias", "--max-effects", "1", "--workers", "1"]

#: The layouts read back to the run's results; each with --log-map and, where a
#: flag can say it (no scale), with the equivalent flags.
LAYOUTS = {
    "extra_columns": Layout(extras=EXTRAS, shuffle=True, seed=1),
    "semicolon_decimal_comma": Layout(delimiter=";", decimal=","),
    "comments": Layout(comment="#", comments_above=3, comments_between=4, seed=2),
    # Comment lines only among the data rows, none above the header.
    "comments_below_the_header": Layout(comment="#", comments_between=5, seed=4),
    "time_ms": Layout(columns={"time_s": "Zeit"}, units={"time_s": "ms"}),
    "forces_kn": Layout(
        columns={"f_mea_n": "F_sensor", "f_comp_n": "F_fed"},
        units={"f_mea_n": "kN", "f_comp_n": "kN"},
    ),
    "positions_mm": Layout(
        columns={"p_des_m": "x_cmd", "p_act_m": "x_act"},
        units={"p_des_m": "mm", "p_act_m": "mm"},
    ),
    # A table without ``column`` keeps the format's name.
    "velocity_mm_per_s_same_name": Layout(units={"v_des_m_per_s": "mm/s"}),
    "all_together": ALL_TOGETHER,
    # The flags comma-joined (one --column-map, one --unit), two --ignore-column.
    "all_together_joined_flags": replace(ALL_TOGETHER, joined_flags=True, ignore=("f_raw", "tick")),
    # The defaults written out: delimiter ",", decimal ".", units s and N.
    "explicit_defaults": Layout(
        columns={"time_s": "Zeit", "f_mea_n": "F_sensor"},
        units={"time_s": "s", "f_mea_n": "N", "p_act_m": "m", "v_des_m_per_s": "m/s"},
        explicit_defaults=True,
    ),
    # An extra column named like a format column, ignored; the format column
    # is read from another log column.
    "ignored_namesake": Layout(
        columns={"f_mea_n": "F_sensor"}, extras=(("f_mea_n", "raw_force"),), ignore=("f_mea_n",)
    ),
    # A text column (a status word) is left alone like any column not needed.
    "text_column": Layout(
        columns={"f_mea_n": "F_sensor"},
        extras=(("status", "text"), ("temperature_c", "temperature")),
    ),
    "random_6": random_layout(6),  # space, //, every column in another unit
    "random_7": random_layout(7),  # tab, #, cm/um/cm/s, shuffled
    # Scales have no flag: --log-map only.
    "sign_flip_and_calibration": replace(
        ALL_TOGETHER, scales={"f_mea_n": -1.0, "p_act_m": 1.25, "v_des_m_per_s": -1.0}
    ),
    "random_scaled_3": random_layout(3, flags=False),
}

# --- running the command ------------------------------------------------------------


@dataclass
class Outcome:
    code: int
    out: str
    err: str


def _cli(*args: str) -> Outcome:
    """``hybridtable ARGS`` in this process, its stdout and stderr captured."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as stop:  # argparse
            code = stop.code if isinstance(stop.code, int) else 1
    return Outcome(code, out.getvalue(), err.getvalue())


def _compare(run: Path, out_json: Path, *mapping: str) -> dict:
    result = _cli("compare", run, "--json", out_json, "--no-progress", *mapping)
    assert result.code == 0, f"exit {result.code}: {result.err.strip()}"
    return json.loads(out_json.read_text(encoding="utf-8"))


def _snapshot(*paths: Path) -> dict[str, object]:
    """Each file's SHA-256 and each folder's listing."""
    state: dict[str, object] = {}
    for path in paths:
        if path.is_dir():
            state[str(path)] = sorted(p.name for p in path.iterdir())
            for child in sorted(path.iterdir()):
                if child.is_file():
                    state[str(child)] = hashlib.sha256(child.read_bytes()).hexdigest()
        else:
            state[str(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
    return state


def _mapping_args(log: RigLog, mode: str) -> list[str]:
    if mode == "log_map":
        return ["--log-map", str(log.toml)]
    assert log.flags is not None
    return list(log.flags)


# --- the results, compared --------------------------------------------------------


def _differences(
    got,
    want,
    where: str,
    dirs: tuple[str, str],
    rel: float = 1e-9,
    skip=frozenset(),
    tiny: float = 0.0,
) -> list[str]:
    """Where the JSON results differ: numbers beyond ``rel`` relative (and
    ``tiny`` absolute), other values at all; ``log_map``, ``inputs`` (the
    flags the command was given, which differ by design) and the keys ``skip``
    left out, the run folders' paths made equal."""
    if isinstance(want, dict) and isinstance(got, dict):
        out = []
        keys = (set(got) | set(want)) - {"log_map", "inputs"} - set(skip)
        for key in sorted(keys):
            if key not in got or key not in want:
                out.append(f"{where}/{key}: only in the {'log' if key in got else 'run'}'s")
                continue
            out += _differences(got[key], want[key], f"{where}/{key}", dirs, rel, skip, tiny)
        return out
    if isinstance(want, list) and isinstance(got, list):
        if len(got) != len(want):
            return [f"{where}: {len(got)} items, the run's {len(want)}"]
        out = []
        for i, (a, b) in enumerate(zip(got, want, strict=True)):
            out += _differences(a, b, f"{where}[{i}]", dirs, rel, skip, tiny)
        return out
    if isinstance(want, float) and isinstance(got, int | float) and not isinstance(got, bool):
        if math.isnan(want) and math.isnan(got):
            return []
        if not math.isclose(got, want, rel_tol=rel, abs_tol=tiny):
            return [f"{where}: {got!r} (log) vs {want!r} (run)"]
        return []
    if isinstance(want, str) and isinstance(got, str):
        got = got.replace(dirs[0], "<RUN_DIR>")
        want = want.replace(dirs[1], "<RUN_DIR>")
    if got != want or type(got) is not type(want):
        return [f"{where}: {got!r} (log) vs {want!r} (run)"]
    return []


def _assert_same_results(
    got: dict,
    want: dict,
    log_dir: Path,
    run_dir: Path,
    rel: float = 1e-9,
    skip=frozenset(),
    tiny: float = 0.0,
) -> None:
    diffs = _differences(got, want, "", (str(log_dir), str(run_dir)), rel, skip, tiny)
    assert not diffs, f"{len(diffs)} difference(s):\n" + "\n".join(diffs[:20])


def _log_maps(data) -> list:
    """Every ``log_map`` entry of a JSON result, wherever it is."""
    found = []
    if isinstance(data, dict):
        for key, value in data.items():
            if key == "log_map":
                found.append(value)
            else:
                found += _log_maps(value)
    elif isinstance(data, list):
        for value in data:
            found += _log_maps(value)
    return found


# --- fixtures ------------------------------------------------------------------


@pytest.fixture(scope="module", autouse=True)
def _examples_stay_unchanged():
    before = _snapshot(EXAMPLES)
    yield
    assert _snapshot(EXAMPLES) == before, "examples/nominal was modified"


class _Baselines:
    """``compare`` on a copy of each example run as the format writes it (run
    once per run)."""

    def __init__(self, factory):
        self.factory = factory
        self.cache: dict[str, dict] = {}

    def __getitem__(self, run: str) -> dict:
        if run not in self.cache:
            folder = self.factory.mktemp(f"original-{run}")
            for suffix in (".csv", ".json"):
                shutil.copy(EXAMPLES / f"{run}{suffix}", folder / f"{run}{suffix}")
            data = _compare(folder / f"{run}.csv", self.factory.mktemp("out") / f"{run}.json")
            self.cache[run] = {"data": data, "dir": folder}
        return self.cache[run]


@pytest.fixture(scope="module")
def baselines(tmp_path_factory) -> _Baselines:
    return _Baselines(tmp_path_factory)


class _Logs:
    """Each (layout, run)'s log (written once), and each (layout, mode, run)'s
    compare result (run once), with whether the user's files stayed as they
    were."""

    def __init__(self, factory):
        self.factory = factory
        self.logs: dict[tuple[str, str], RigLog] = {}
        self.results: dict[tuple[str, str, str], dict] = {}

    def log(self, name: str, run: str = "run1") -> RigLog:
        if (name, run) not in self.logs:
            folder = self.factory.mktemp(f"log-{name}-{run}")
            maps = self.factory.mktemp(f"map-{name}-{run}")
            self.logs[(name, run)] = write_log(
                EXAMPLES / f"{run}.csv", LAYOUTS[name], folder, toml_path=maps / "rig.toml"
            )
        return self.logs[(name, run)]

    def result(self, name: str, mode: str, run: str = "run1", command: str = "compare") -> dict:
        key = (name, mode, run, command)
        if key not in self.results:
            log = self.log(name, run)
            before = _snapshot(log.csv.parent, log.toml)
            out_json = self.factory.mktemp("out") / "result.json"
            extra = DIAGNOSE_ARGS if command == "diagnose" else []
            outcome = _cli(
                command,
                log.csv,
                "--json",
                out_json,
                "--no-progress",
                *extra,
                *_mapping_args(log, mode),
            )
            data = json.loads(out_json.read_text()) if outcome.code == 0 else None
            self.results[key] = {
                "outcome": outcome,
                "data": data,
                "unchanged": _snapshot(log.csv.parent, log.toml) == before,
                "log": log,
                "command": f"{command} {log.csv.name} {' '.join(_mapping_args(log, mode))}",
            }
        return self.results[key]


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> _Logs:
    return _Logs(tmp_path_factory)


#: The layouts also read from run2 and run3 (SDMDC: f_comp_n is not f_mea_n).
OTHER_RUNS = ("all_together", "random_6", "random_scaled_3")


def _cases() -> list:
    cases = []
    for name, layout in LAYOUTS.items():
        modes = ["log_map"]
        if flags_of(mapping_of(layout)) is not None:
            modes.append("flags")
        runs = ["run1", "run2", "run3"] if name in OTHER_RUNS else ["run1"]
        for run in runs:
            for mode in modes:
                if run != "run1" and mode == "flags" and name != "all_together":
                    continue
                cases.append(pytest.param(name, mode, run, id=f"{name}-{mode}-{run}"))
    return cases


# --- a log reads as its run ----------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize(("name", "mode", "run"), _cases())
def test_a_log_gives_the_runs_results(logs, baselines, name, mode, run):
    result = logs.result(name, mode, run)
    outcome = result["outcome"]
    assert outcome.code == 0, f"{result['command']}: exit {outcome.code}: {outcome.err.strip()}"
    assert result["unchanged"], "the log, its JSON, its folder or the mapping was modified"
    want = baselines[run]
    _assert_same_results(result["data"], want["data"], result["log"].csv.parent, want["dir"])


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["log_map", "flags"])
@pytest.mark.parametrize("name", ["all_together", "extra_columns", "ignored_namesake"])
def test_json_lists_the_mapping_and_the_skipped_columns(logs, name, mode):
    result = logs.result(name, mode)
    assert result["outcome"].code == 0, result["outcome"].err.strip()
    entries = _log_maps(result["data"])
    assert entries, f"no log_map in the JSON (top-level keys: {sorted(result['data'])})"
    text = json.dumps(entries)
    layout = LAYOUTS[name]
    for column in FORMAT_COLUMNS:
        if layout.log_name(column) != column:
            assert f'"{layout.log_name(column)}"' in text, (
                f"log_map lacks {layout.log_name(column)}"
            )
        if column in layout.units:
            assert f'"{layout.units[column]}"' in text, f"log_map lacks the unit of {column}"
    for skipped in result["log"].skipped:
        assert f'"{skipped}"' in text, f"log_map does not list the skipped column {skipped}"
    if layout.delimiter != ",":
        assert json.dumps(layout.delimiter) in text, "log_map lacks the delimiter"


@pytest.mark.slow
def test_flags_override_the_files_entries(tmp_path, baselines):
    """A map (valid on its own) with the wrong delimiter, decimal mark, comment
    prefix and time unit, each corrected by its flag (each flag overrides the
    file's entry)."""
    baseline = baselines["run1"]
    log = write_log(
        EXAMPLES / "run1.csv", ALL_TOGETHER, tmp_path / "log", toml_path=tmp_path / "right.toml"
    )
    mapping = json.loads(json.dumps(log.mapping))
    mapping.update(delimiter="|", decimal=".", comment="%")
    mapping["columns"]["time_s"]["unit"] = "s"
    toml = write_toml(mapping, tmp_path / "wrong.toml")
    before = _snapshot(log.csv.parent, toml)
    data = _compare(
        log.csv,
        tmp_path / "out.json",
        "--log-map",
        str(toml),
        "--delimiter",
        ";",
        "--decimal",
        ",",
        "--comment",
        "#",
        "--unit",
        "time_s=ms",
    )
    assert _snapshot(log.csv.parent, toml) == before
    _assert_same_results(data, baseline["data"], log.csv.parent, baseline["dir"])


@pytest.mark.slow
def test_a_namesake_column_not_ignored_is_never_read_silently(tmp_path, baselines):
    """The log has a raw-count column named ``f_mea_n`` and the map reads
    f_mea_n from ``F_sensor`` without ignoring the namesake. The spec says to
    ignore such a column but not what happens if one does not: either the map
    wins (the run's results) or it is refused in one line naming the column;
    never the raw counts read as newtons."""
    baseline = baselines["run1"]
    layout = Layout(
        columns={"f_mea_n": "F_sensor"}, extras=(("f_mea_n", "raw_force"),), ignore=("f_mea_n",)
    )
    log = write_log(EXAMPLES / "run1.csv", layout, tmp_path / "log", toml_path=tmp_path / "m.toml")
    mapping = json.loads(json.dumps(log.mapping))
    del mapping["ignore"]
    toml = write_toml(mapping, tmp_path / "m.toml")
    outcome = _cli(
        "compare", log.csv, "--json", tmp_path / "out.json", "--no-progress", "--log-map", toml
    )
    if outcome.code == 0:
        data = json.loads((tmp_path / "out.json").read_text())
        _assert_same_results(data, baseline["data"], log.csv.parent, baseline["dir"])
    else:
        err = _assert_one_line(outcome, "namesake not ignored")
        assert _has(err, "f_mea_n"), err


@pytest.mark.slow
def test_a_folder_of_logs_gives_the_folder_of_runs_results(tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    logs = tmp_path / "logs"
    for name in ("run1", "run2", "run3"):
        for suffix in (".csv", ".json"):
            shutil.copy(EXAMPLES / f"{name}{suffix}", runs / f"{name}{suffix}")
        log = write_log(
            EXAMPLES / f"{name}.csv", ALL_TOGETHER, logs, toml_path=tmp_path / "rig.toml"
        )
    before = _snapshot(logs, log.toml)
    want = _compare(runs, tmp_path / "runs.json")
    got = _compare(logs, tmp_path / "logs.json", "--log-map", str(log.toml))
    assert _snapshot(logs, log.toml) == before
    _assert_same_results(got, want, logs, runs)


@pytest.mark.slow
def test_the_installed_command_reads_a_log(tmp_path, baselines):
    """``hybridtable compare LOG --log-map FILE --json FILE`` as a user runs it."""
    baseline = baselines["run1"]
    log = write_log(
        EXAMPLES / "run1.csv", ALL_TOGETHER, tmp_path / "log", toml_path=tmp_path / "m.toml"
    )
    command = shutil.which("hybridtable", path=str(Path(sys.executable).parent)) or "hybridtable"
    out = tmp_path / "out.json"
    proc = subprocess.run(
        [
            command,
            "compare",
            str(log.csv),
            "--log-map",
            str(log.toml),
            "--json",
            str(out),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    data = json.loads(out.read_text())
    _assert_same_results(data, baseline["data"], log.csv.parent, baseline["dir"])


@pytest.mark.slow
def test_diagnose_reads_a_log_as_its_run(tmp_path, logs):
    """diagnose (one candidate effect, one worker) on the all-together log
    gives the run's results, and its JSON lists the mapping under log_map. Its
    fits iterate, so a few-ulp difference in the input may move them further
    than compare's arithmetic: 1e-6 relative; and its audit solves for
    quantities that are 0 in exact arithmetic (the lead time of a run without
    compensation, residuals), whose round-off is compared to 1e-10 absolute."""
    result = logs.result("all_together", "log_map", "run1", "diagnose")
    outcome = result["outcome"]
    assert outcome.code == 0, f"{result['command']}: exit {outcome.code}: {outcome.err.strip()}"
    assert result["unchanged"]
    folder = tmp_path / "original"
    folder.mkdir()
    for suffix in (".csv", ".json"):
        shutil.copy(EXAMPLES / f"run1{suffix}", folder / f"run1{suffix}")
    got = _cli(
        "diagnose",
        folder / "run1.csv",
        "--json",
        tmp_path / "d.json",
        "--no-progress",
        *DIAGNOSE_ARGS,
    )
    assert got.code == 0, got.err
    want = json.loads((tmp_path / "d.json").read_text())
    _assert_same_results(
        result["data"],
        want,
        result["log"].csv.parent,
        folder,
        rel=1e-6,
        skip={"wall_time_s"},
        tiny=1e-10,
    )


@pytest.mark.slow
def test_diagnose_json_lists_the_mapping(logs):
    result = logs.result("all_together", "log_map", "run1", "diagnose")
    assert result["outcome"].code == 0, result["outcome"].err.strip()
    entries = _log_maps(result["data"])
    assert entries, f"no log_map in diagnose's JSON (top-level keys: {sorted(result['data'])})"
    text = json.dumps(entries)
    for skipped in result["log"].skipped:
        assert f'"{skipped}"' in text, f"log_map does not list the skipped column {skipped}"


# --- wrong mappings ----------------------------------------------------------------


def _drop(*path: str):
    """A mutation of the mapping: delete mapping[path[0]]...[path[-1]]."""

    def mutate(mapping: dict) -> dict:
        node = mapping
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
        return mapping

    return mutate


def _set(value, *path: str):
    def mutate(mapping: dict) -> dict:
        node = mapping
        for key in path[:-1]:
            node = node.setdefault(key, {})
        node[path[-1]] = value
        return mapping

    return mutate


def _both(*mutations):
    def mutate(mapping: dict) -> dict:
        for m in mutations:
            mapping = m(mapping)
        return mapping

    return mutate


@dataclass(frozen=True)
class Wrong:
    """A log, a wrong mapping of it, and what the one-line error must name:
    ``columns`` (any one of them: the log's name or the format's), ``unit``
    (the unit that fits), ``words`` (regular expressions), ``file`` ("csv": the
    log's name; "toml": the mapping's, with --log-map; "any": either)."""

    layout: Layout
    mutate: object
    columns: tuple[str, ...] = ()
    unit: str | None = None
    words: tuple[str, ...] = ()
    file: str = "csv"
    modes: tuple[str, ...] = ("log_map", "flags")


def _units(**units) -> Layout:
    return Layout(columns=NAMES, units=units)


def _names(*columns: str) -> tuple[str, ...]:
    return tuple(x for c in columns for x in (c, NAMES[c]))


WRONG = {
    # A channel read in the wrong unit: caught against the JSON and the
    # computer's arithmetic; the message names the column and the unit that fits.
    "time_ms_no_unit": Wrong(
        _units(time_s="ms"), _drop("columns", "time_s", "unit"), _names("time_s"), "ms"
    ),
    "time_us_no_unit": Wrong(
        _units(time_s="us"), _drop("columns", "time_s", "unit"), _names("time_s"), "us"
    ),
    "f_mea_kn_read_as_n": Wrong(
        _units(f_mea_n="kN"), _drop("columns", "f_mea_n", "unit"), _names("f_mea_n"), "kN"
    ),
    "f_mea_mn_read_as_n": Wrong(
        _units(f_mea_n="mN"), _drop("columns", "f_mea_n", "unit"), _names("f_mea_n"), "mN"
    ),
    "f_mea_n_read_as_kn": Wrong(
        _units(),
        _set({"column": "F_sensor", "unit": "kN"}, "columns", "f_mea_n"),
        _names("f_mea_n"),
        "N",
    ),
    "forces_kn_read_as_n": Wrong(
        _units(f_mea_n="kN", f_comp_n="kN"),
        _both(_drop("columns", "f_mea_n", "unit"), _drop("columns", "f_comp_n", "unit")),
        _names("f_mea_n", "f_comp_n"),
        "kN",
    ),
    "positions_mm_read_as_m": Wrong(
        _units(p_des_m="mm", p_act_m="mm"),
        _both(_drop("columns", "p_des_m", "unit"), _drop("columns", "p_act_m", "unit")),
        _names("p_des_m", "p_act_m"),
        "mm",
    ),
    "p_act_mm_read_as_m": Wrong(
        _units(p_act_m="mm"), _drop("columns", "p_act_m", "unit"), _names("p_act_m"), "mm"
    ),
    "positions_um_read_as_m": Wrong(
        _units(p_des_m="um", p_act_m="um"),
        _both(_drop("columns", "p_des_m", "unit"), _drop("columns", "p_act_m", "unit")),
        _names("p_des_m", "p_act_m"),
        "um",
    ),
    "velocity_mm_per_s_read_as_m_per_s": Wrong(
        _units(v_des_m_per_s="mm/s"),
        _drop("columns", "v_des_m_per_s", "unit"),
        _names("v_des_m_per_s"),
        "mm/s",
    ),
    "velocity_cm_per_s_read_as_m_per_s": Wrong(
        _units(v_des_m_per_s="cm/s"),
        _drop("columns", "v_des_m_per_s", "unit"),
        _names("v_des_m_per_s"),
        "cm/s",
    ),
    # The file's shape: the delimiter, comments, decimal commas to give.
    "semicolon_without_delimiter": Wrong(
        Layout(delimiter=";", columns=NAMES), _drop("delimiter"), words=(r"delimiter\W{1,6};",)
    ),
    "tab_without_delimiter": Wrong(
        Layout(delimiter="\t", columns=NAMES), _drop("delimiter"), words=(r"delimiter",)
    ),
    "comments_without_comment": Wrong(
        Layout(comment="#", comments_above=2, columns=NAMES),
        _drop("comment"),
        words=(r"comment\W{1,6}#",),
    ),
    "decimal_commas_without_decimal": Wrong(
        Layout(delimiter=";", decimal=",", columns=NAMES),
        _drop("decimal"),
        _names(*FORMAT_COLUMNS),
        words=(r"decimal\W{1,6},",),
    ),
    "missing_rename": Wrong(
        Layout(columns=NAMES),
        _drop("columns", "f_mea_n"),
        ("f_mea_n",),
        words=(r"F_sensor", r"--column-map"),
    ),
    # Refused when the mapping is read.
    "unknown_unit": Wrong(
        _units(f_mea_n="kN"),
        _set("lbf", "columns", "f_mea_n", "unit"),
        _names("f_mea_n"),
        words=(r"lbf",),
        file="toml",
    ),
    "unit_of_another_column": Wrong(
        _units(p_act_m="mm"),
        _set("kN", "columns", "p_act_m", "unit"),
        _names("p_act_m"),
        words=(r"kN",),
        file="toml",
    ),
    "unknown_format_column": Wrong(
        Layout(columns=NAMES), _set("F_sensor", "columns", "force_z"), ("force_z",), file="toml"
    ),
    "scale_zero": Wrong(
        _units(f_mea_n="kN"),
        _set(0.0, "columns", "f_mea_n", "scale"),
        _names("f_mea_n"),
        words=(r"scale",),
        file="toml",
        modes=("log_map",),
    ),
    "scale_infinite": Wrong(
        _units(f_mea_n="kN"),
        _set(math.inf, "columns", "f_mea_n", "scale"),
        _names("f_mea_n"),
        words=(r"scale",),
        file="toml",
        modes=("log_map",),
    ),
    "scale_nan": Wrong(
        _units(f_mea_n="kN"),
        _set(math.nan, "columns", "f_mea_n", "scale"),
        _names("f_mea_n"),
        words=(r"scale",),
        file="toml",
        modes=("log_map",),
    ),
    "unknown_delimiter": Wrong(
        Layout(delimiter=";", columns=NAMES),
        _set(":", "delimiter"),
        words=(r"delimiter", ":"),
        file="toml",
    ),
    "unknown_decimal": Wrong(
        Layout(columns=NAMES), _set(";", "decimal"), words=(r"decimal",), file="toml"
    ),
    "decimal_comma_with_comma_delimiter": Wrong(
        Layout(columns=NAMES), _set(",", "decimal"), words=(r"decimal", r"delimiter"), file="toml"
    ),
    "unknown_key": Wrong(
        Layout(delimiter=";", columns=NAMES),
        _both(_drop("delimiter"), _set(";", "delimeter")),
        words=(r"delimeter",),
        file="toml",
        modes=("log_map",),
    ),
    "unknown_key_in_a_column": Wrong(
        Layout(columns=NAMES),
        _set({"column": "F_sensor", "units": "kN"}, "columns", "f_mea_n"),
        words=(r"units",),
        file="toml",
        modes=("log_map",),
    ),
    # "a column both read and ignored is an error" (the TOML example's comment).
    "ignore_a_column_read": Wrong(
        Layout(columns=NAMES), _set(["F_sensor"], "ignore"), _names("f_mea_n"), file="any"
    ),
    "ignore_a_column_read_by_its_format_name": Wrong(
        Layout(extras=EXTRAS), _set(["time_s"], "ignore"), ("time_s",), file="any"
    ),
    "log_column_mapped_twice": Wrong(
        Layout(columns=NAMES), _set("x_cmd", "columns", "p_act_m"), ("x_cmd",), file="toml"
    ),
}


def _wrong_cases() -> list:
    """Each case with each of its modes on run1; the unit cases also on run2
    and run3 (SDMDC: f_comp_n is not f_mea_n) with --log-map."""
    cases = [
        pytest.param(name, mode, "run1", id=f"{name}-{mode}")
        for name, case in WRONG.items()
        for mode in case.modes
    ]
    cases += [
        pytest.param(name, "log_map", run, id=f"{name}-log_map-{run}")
        for name, case in WRONG.items()
        if case.unit
        for run in ("run2", "run3")
    ]
    return cases


def _has(text: str, word: str) -> bool:
    """``word`` in ``text`` as a whole word (``mm`` is not in ``mm/s``, ``N``
    not in ``kN``)."""
    return re.search(rf"(?<![\w/]){re.escape(word)}(?![\w/])", text) is not None


def _assert_one_line(outcome: Outcome, what: str) -> str:
    err = outcome.err.strip()
    assert outcome.code == 2, f"{what}: exit {outcome.code}, stderr: {err!r}"
    assert err, f"{what}: nothing on stderr"
    assert "\n" not in err, f"{what}: not one line:\n{err}"
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize(("name", "mode", "run"), _wrong_cases())
def test_a_wrong_mapping_is_one_line_naming_the_column_and_the_unit(tmp_path, name, mode, run):
    case = WRONG[name]
    log = write_log(
        EXAMPLES / f"{run}.csv", case.layout, tmp_path / "log", toml_path=tmp_path / "rig.toml"
    )
    mapping = case.mutate(json.loads(json.dumps(log.mapping)))
    toml = write_toml(mapping, tmp_path / "rig.toml")
    if mode == "log_map":
        args = ["--log-map", str(toml)]
    else:
        args = flags_of(mapping)
        assert args is not None
    before = _snapshot(log.csv.parent, toml)
    outcome = _cli("compare", log.csv, "--json", tmp_path / "out.json", "--no-progress", *args)
    what = f"compare {log.csv.name} {' '.join(args)}"
    err = _assert_one_line(outcome, what)
    assert _snapshot(log.csv.parent, toml) == before, "the user's files were modified"
    assert not (tmp_path / "out.json").exists(), "an output was written for a refused input"
    if case.file == "csv":
        assert f"{run}.csv" in err, f"{what}: the log file is not named: {err}"
    elif case.file == "toml" and mode == "log_map":
        assert "rig.toml" in err, f"{what}: the mapping file is not named: {err}"
    elif mode == "log_map":
        assert "rig.toml" in err or f"{run}.csv" in err, f"{what}: no file named: {err}"
    if case.columns:
        assert any(_has(err, c) for c in case.columns), (
            f"{what}: none of {case.columns} named: {err}"
        )
    if case.unit:
        assert _has(err, case.unit), f"{what}: the unit that fits ({case.unit}) is not named: {err}"
    for word in case.words:
        assert re.search(word, err), f"{what}: {word!r} not in: {err}"


@pytest.mark.parametrize("run", ["run1", "run2"])
@pytest.mark.parametrize("column", FORMAT_COLUMNS)
def test_every_channel_in_every_other_unit_is_named_with_the_unit_that_fits(tmp_path, column, run):
    """Each channel logged in each of its units and read in each other one:
    exit 2, one line naming the column, the unit it was read in and the unit
    that fits (run2 is SDMDC: f_comp_n is not f_mea_n there)."""
    failures = []
    for true in UNITS[column]:
        log = write_log(
            EXAMPLES / f"{run}.csv",
            Layout(columns=NAMES, units={column: true}),
            tmp_path / true.replace("/", "_"),
            toml_path=tmp_path / "rig.toml",
        )
        for declared in UNITS[column]:
            if declared == true:
                continue
            mapping = json.loads(json.dumps(log.mapping))
            mapping["columns"][column] = {"column": NAMES[column], "unit": declared}
            toml = write_toml(mapping, tmp_path / "rig.toml")
            outcome = _cli("compare", log.csv, "--no-progress", "--log-map", toml)
            err = outcome.err.strip()
            named = (
                outcome.code == 2
                and err
                and "\n" not in err
                and (_has(err, column) or _has(err, NAMES[column]))
                and _has(err, declared)
                and _has(err, true)
            )
            if not named:
                failures.append(f"log in {true}, read in {declared}: exit {outcome.code}: {err}")
    assert not failures, "\n".join(failures)


@pytest.mark.slow
def test_a_user_fixes_the_map_from_the_messages_one_by_one(tmp_path, baselines):
    """The all-together log read with the column names only: each run of
    compare names at least one fault (comment, delimiter, decimal comma, a
    unit) with its fix, which the user then gives; with every fix given, the
    run's results. A unit's fix is named as in the spec's example
    (``--unit f_mea_n=kN``): ``COLUMN=UNIT``."""
    baseline = baselines["run1"]
    log = write_log(
        EXAMPLES / "run1.csv", ALL_TOGETHER, tmp_path / "log", toml_path=tmp_path / "m.toml"
    )
    flags = ["--column-map", ",".join(f"{k}={v}" for k, v in NAMES.items())]
    faults = {
        "comment": (r"comment\W{1,6}#", ["--comment", "#"]),
        "delimiter": (r"delimiter\W{1,6};", ["--delimiter", ";"]),
        "decimal": (r"decimal\W{1,6},", ["--decimal", ","]),
    }
    for column, unit in ALL_TOGETHER.units.items():
        pattern = rf"(?<![\w/]){column}={re.escape(unit)}(?![\w/])"
        faults[column] = (pattern, ["--unit", f"{column}={unit}"])
    seen: list[list[str]] = []
    for _ in range(len(faults) + 1):
        outcome = _cli("compare", log.csv, "--json", tmp_path / "out.json", "--no-progress", *flags)
        if outcome.code == 0:
            break
        err = _assert_one_line(outcome, f"compare with {' '.join(flags)}")
        fixed = [name for name, (pattern, _) in faults.items() if re.search(pattern, err)]
        assert fixed, f"after fixing {seen}: no fix of the faults left ({sorted(faults)}) in: {err}"
        seen.append(fixed)
        for name in fixed:
            flags += faults.pop(name)[1]
    assert outcome.code == 0, f"after fixing {seen}: exit {outcome.code}: {outcome.err.strip()}"
    assert not faults, f"never named: {sorted(faults)} (named: {seen})"
    data = json.loads((tmp_path / "out.json").read_text())
    _assert_same_results(data, baseline["data"], log.csv.parent, baseline["dir"])


def test_the_specs_example_message_for_forces_in_kn(tmp_path):
    """The spec's example: f_mea_n in kN read in N names the log column, the
    unit it was read in and the flag that reads it."""
    layout = Layout(columns={"f_mea_n": "Fz"}, units={"f_mea_n": "kN"})
    log = write_log(
        EXAMPLES / "run1.csv", layout, tmp_path / "log", toml_path=tmp_path / "rig.toml"
    )
    mapping = _drop("columns", "f_mea_n", "unit")(json.loads(json.dumps(log.mapping)))
    toml = write_toml(mapping, tmp_path / "rig.toml")
    err = _assert_one_line(_cli("compare", log.csv, "--log-map", toml, "--no-progress"), "kN as N")
    assert err.startswith("run1.csv") or "run1.csv:" in err, err
    assert "'Fz'" in err and "read in N" in err, err
    assert "--unit f_mea_n=kN" in err, err
    assert 'unit = "kN"' in err, err


def test_a_missing_map_file_is_one_line(tmp_path):
    shutil.copy(EXAMPLES / "run1.csv", tmp_path / "run1.csv")
    shutil.copy(EXAMPLES / "run1.json", tmp_path / "run1.json")
    outcome = _cli(
        "compare", tmp_path / "run1.csv", "--log-map", tmp_path / "nope.toml", "--no-progress"
    )
    err = _assert_one_line(outcome, "missing map")
    assert "nope.toml" in err


def test_a_map_that_is_not_toml_is_one_line(tmp_path):
    shutil.copy(EXAMPLES / "run1.csv", tmp_path / "run1.csv")
    shutil.copy(EXAMPLES / "run1.json", tmp_path / "run1.json")
    toml = tmp_path / "rig.toml"
    toml.write_text('delimiter = ";\n[columns\ntime_s = t\n', encoding="utf-8")
    outcome = _cli("compare", tmp_path / "run1.csv", "--log-map", toml, "--no-progress")
    err = _assert_one_line(outcome, "broken TOML")
    assert "rig.toml" in err


def test_diagnose_refuses_a_wrong_unit_the_same_way(tmp_path):
    layout = _units(f_mea_n="kN", f_comp_n="kN")
    log = write_log(
        EXAMPLES / "run1.csv", layout, tmp_path / "log", toml_path=tmp_path / "rig.toml"
    )
    mapping = _both(_drop("columns", "f_mea_n", "unit"), _drop("columns", "f_comp_n", "unit"))(
        json.loads(json.dumps(log.mapping))
    )
    toml = write_toml(mapping, tmp_path / "rig.toml")
    outcome = _cli("diagnose", log.csv, "--log-map", toml, "--no-progress", "--workers", "1")
    err = _assert_one_line(outcome, "diagnose kN as N")
    assert any(_has(err, c) for c in _names("f_mea_n", "f_comp_n")), err
    assert _has(err, "kN"), err


@pytest.mark.parametrize("command", ["compare", "diagnose", "effects"])
def test_every_command_that_reads_runs_takes_a_log_map(command):
    """The spec: --log-map "to compare, diagnose and every command that reads
    runs" (effects --rig reads runs; simulate --model reads a model file, not runs)."""
    outcome = _cli(command, "--help")
    assert outcome.code == 0
    for flag in ("--log-map", "--unit", "--delimiter", "--decimal", "--comment", "--ignore-column"):
        assert flag in outcome.out, f"{command} --help lacks {flag}"
