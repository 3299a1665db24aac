"""One overwrite policy for every command: an existing output is replaced only
with ``--force``, an input never, and the refusal comes before any work."""

from __future__ import annotations

import json
import time

import pytest

from hybridtable.cli import COMMANDS, build_parser, main
from tests.examples import EXAMPLES

#: A cheap invocation of every command (the check runs before the work).
INVOCATIONS = {
    "simulate": ["simulate"],
    "reproduce": ["reproduce"],
    "compare": ["compare", str(EXAMPLES / "run1.csv")],
    "diagnose": ["diagnose", str(EXAMPLES / "run1.csv")],
    "effects": ["effects"],
    "compensators": ["compensators", "--quick"],
    "margins": ["margins"],
    "sweep": ["sweep", str(EXAMPLES.parent / "sweeps" / "table2.toml"), "--out", "unused.parquet"],
}


def _sub_parsers():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return action.choices


def test_every_command_has_force():
    names = {c.__name__.rsplit(".", 1)[-1] for c in COMMANDS}
    assert set(INVOCATIONS) <= names
    for name, sub in _sub_parsers().items():
        flags = {s for a in sub._actions for s in a.option_strings}
        assert "--force" in flags, name


@pytest.mark.parametrize("command", sorted(INVOCATIONS))
def test_existing_json_is_refused_quickly_and_left_alone(command, tmp_path, capsys):
    out = tmp_path / "out.json"
    out.write_text("mine")
    t0 = time.perf_counter()
    assert main([*INVOCATIONS[command], "--json", str(out)]) == 2
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--json" in err and "--force" in err, err
    assert out.read_text() == "mine"
    assert elapsed < 30.0  # refused before the work, not after it


def test_force_replaces_and_a_non_empty_folder_needs_it(tmp_path, capsys):
    out = tmp_path / "out.json"
    out.write_text("mine")
    assert main(["simulate", "--json", str(out), "--force"]) == 0
    assert json.loads(out.read_text())["cor"] > 1.1
    plot = tmp_path / "run.png"
    plot.write_bytes(b"mine")
    assert main(["simulate", "--plot", str(plot)]) == 2
    assert "--plot" in capsys.readouterr().err and plot.read_bytes() == b"mine"
    folder = tmp_path / "report"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    assert main(["margins", "--report", str(folder)]) == 2
    assert "not empty" in capsys.readouterr().err


def test_an_input_is_never_an_output_even_with_force(tmp_path, capsys):
    run = tmp_path / "run1.json"
    run.write_text((EXAMPLES / "run1.json").read_text())
    (tmp_path / "run1.csv").write_text((EXAMPLES / "run1.csv").read_text())
    before = run.read_text()
    assert main(["compare", str(run), "--json", str(run), "--force"]) == 2
    assert "input" in capsys.readouterr().err
    assert run.read_text() == before


def test_an_output_that_cannot_be_written_is_refused_before_the_work(tmp_path, capsys):
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    t0 = time.perf_counter()
    assert main(["simulate", "--json", str(blocker / "out.json")]) == 2
    assert main(["compare", str(EXAMPLES), "--report", str(blocker / "rep")]) == 2
    assert time.perf_counter() - t0 < 30.0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and all("is a file, not a folder" in line for line in err), err


def test_the_tables_are_never_written_over(tmp_path, capsys):
    from hybridtable.studies.paper import load_tables

    tables = tmp_path / "tables.json"
    text = json.dumps(load_tables())
    tables.write_text(text)
    rc = main(["reproduce", "--tables", str(tables), "--json", str(tables), "--force"])
    assert rc == 2
    assert "one of the input files" in capsys.readouterr().err
    assert tables.read_text() == text


def test_a_plot_suffix_matplotlib_cannot_write_is_refused_first(tmp_path, capsys):
    assert main(["simulate", "--plot", str(tmp_path / "out.txt")]) == 2
    err = capsys.readouterr().err
    assert "--plot" in err and "png" in err and err.count("\n") == 1
    assert not (tmp_path / "out.txt").exists()


def test_an_interrupted_report_leaves_the_folder_as_it_was(tmp_path, monkeypatch, capsys):
    import hybridtable.reports.compare as report_module

    report = tmp_path / "rep"
    report.mkdir()
    (report / "mine.txt").write_text("mine")
    real = report_module.write_report

    def interrupted(comparisons, folder, **kw):
        real(comparisons, folder, **kw)  # every file written, then Ctrl-C
        raise KeyboardInterrupt

    monkeypatch.setattr(report_module, "write_report", interrupted)
    argv = ["compare", str(EXAMPLES / "run1.csv"), "--report", str(report), "--force"]
    assert main(argv) == 130
    assert capsys.readouterr().err.strip().endswith("hybridtable: interrupted")
    assert sorted(p.name for p in report.iterdir()) == ["mine.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]  # no staging folder


def test_a_run_id_with_dollars_is_drawn_as_written(tmp_path, capsys):
    import shutil

    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(EXAMPLES / "run1.csv", runs / "run1.csv")
    info = json.loads((EXAMPLES / "run1.json").read_text())
    info["run_id"] = "cost $5 and $x^2$"
    (runs / "run1.json").write_text(json.dumps(info))
    assert main(["compare", str(runs), "--report", str(tmp_path / "rep"), "--no-progress"]) == 0
    assert "cost $5 and $x^2$" in (tmp_path / "rep" / "report.md").read_text()
