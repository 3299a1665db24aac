"""``hybridtable diagram NAME``: the loop's Graphviz picture and the paper's small
scenarios, written into an output folder under the overwrite policy."""

from __future__ import annotations

import re

import pytest

from hybridtable.cli import main


def test_list_names_every_diagram(capsys):
    from hybridtable.reports.diagrams import DIAGRAMS

    assert main(["diagram", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"{len(DIAGRAMS)} diagrams; draw one with: hybridtable diagram NAME"
    assert [line.split()[0] for line in lines[1:]] == list(DIAGRAMS)
    assert {"hybrid-loop", "sampled-rig", "delay-scenarios", "table1-compensators"} <= set(DIAGRAMS)


def test_hybrid_loop_writes_the_dot_and_replaces_it_only_with_force(tmp_path, capsys):
    import shutil

    out = tmp_path / "d"
    assert main(["diagram", "hybrid-loop", "--out-dir", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("The hybrid loop (Table 1 point, SDMDC) is a Drake diagram of 9")
    dot = (out / "hybrid_loop.dot").read_text()
    for system in ("spacecraft", "table", "contact", "force_sensor", "compensator"):
        assert system in dot
    if shutil.which("dot"):
        assert (out / "hybrid_loop.svg").read_text().lstrip().startswith("<?xml")
        assert lines[0].endswith("hybrid_loop.svg")
    # The same folder again: refused, nothing replaced, until --force.
    before = (out / "hybrid_loop.dot").stat().st_mtime_ns
    assert main(["diagram", "hybrid-loop", "--out-dir", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exists; give --force" in err
    assert (out / "hybrid_loop.dot").stat().st_mtime_ns == before
    assert main(["diagram", "hybrid-loop", "--out-dir", str(out), "--force"]) == 0


def test_without_graphviz_the_dot_is_written_and_the_render_line_given(
    tmp_path, capsys, monkeypatch
):
    import hybridtable.reports.diagrams as diagrams

    monkeypatch.setattr(diagrams.shutil, "which", lambda name: None)
    assert main(["diagram", "hybrid-loop", "--out-dir", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    dot, svg = tmp_path / "hybrid_loop.dot", tmp_path / "hybrid_loop.svg"
    assert dot.is_file() and not svg.exists()
    assert f"run: dot -Tsvg {dot} -o {svg}" in text


def test_table1_compensators_gives_the_paper_cors(tmp_path, capsys):
    assert main(["diagram", "table1-compensators", "--out-dir", str(tmp_path)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    # Table 1 of the paper: none 1.1611, SDMDC 0.9999; energy gain CoR^2 - 1 = +35 %.
    assert first.startswith(
        "At the Table 1 point SDMDC keeps CoR at 1.000 where no compensation gives 1.161 "
        "(energy +35%)"
    )
    within = float(re.search(r"within (\d\.\d+) of the paper", first).group(1))
    assert within < 0.001
    assert (tmp_path / "table1_compensators.txt").read_text().splitlines()[0] == first


def test_json_on_stdout_holds_the_cors_only(tmp_path, capsys):
    import json

    argv = ["diagram", "table1-compensators", "--out-dir", str(tmp_path), "--json", "-"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)  # nothing else on stdout
    assert set(doc["cor"]) == {"none", "SDC", "MDC", "SDMDC"}
    for name, cor in doc["cor"].items():
        assert abs(cor - doc["cor_paper"][name]) < 0.001


def test_delay_scenarios_follow_the_estimate(tmp_path, capsys):
    assert main(["diagram", "delay-scenarios", "--out-dir", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    within = float(re.search(r"within (\d\.\d+) over the paper's 7", lines[0]).group(1))
    assert within < 0.001
    rows = [line for line in lines if line.startswith("Fig.")]
    assert len(rows) == 7
    # More delay, larger CoR: the three sensor delays of Fig. 3 in order.
    cors = [float(r.split()[-3]) for r in rows[:3]]
    assert cors == sorted(cors) and cors[0] > 1.0


def test_sampled_rig_at_one_rate(tmp_path, capsys):
    argv = ["diagram", "sampled-rig", "--sample-rates-hz", "1000", "--out-dir", str(tmp_path)]
    assert main(argv) == 0
    first = capsys.readouterr().out.splitlines()[0]
    m = re.search(r"gives CoR (\S+) with no compensation and (\S+) with SDMDC", first)
    assert first.startswith("A rig computer at 1000 Hz")
    assert float(m.group(1)) == pytest.approx(1.155, abs=0.002)
    assert float(m.group(2)) == pytest.approx(1.000, abs=0.002)


@pytest.mark.parametrize(
    "argv, message",
    [
        ([], "give a diagram NAME"),
        (["nonesuch"], "no diagram 'nonesuch'"),
        (["hybrid-loop", "--sample-rates-hz", "1000"], "for sampled-rig only"),
    ],
)
def test_bad_input_is_one_line(argv, message, tmp_path, capsys):
    assert main(["diagram", *argv, "--out-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
