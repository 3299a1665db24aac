"""``hybridtable simulate --table stewart``: what a user sees and the flags its errors name."""

from __future__ import annotations

import json
import re
import urllib.request

import pytest

from hybridtable.cli import build_parser, main
from hybridtable.errors import ParameterError
from hybridtable.stewart.view import ARROW_PATH, DRAWN_FRACTION_OF_RADIUS, MotionView

from .test_view import html_commands

STEWART = ["simulate", "--table", "stewart"]
RADIUS_M = 0.35


def simulate_flags() -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return {s for a in sub.choices["simulate"]._actions for s in a.option_strings}


def test_recording_is_magnified_and_the_console_opens_with_a_verdict(tmp_path, capsys):
    out, html = tmp_path / "run.json", tmp_path / "run.html"
    assert main([*STEWART, "--json", str(out), "--html", str(html)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("On the Stewart table, with no compensation the loop adds energy")
    assert "CoR 1.160, energy +34%" in lines[0]
    assert lines[2].startswith("Stewart table identified as 25.00 Hz")
    drawing = json.loads(out.read_text())["drawing"]
    # The peak plate displacement (17.1 mm) is drawn at about 30 % of the radius.
    drawn = drawing["magnify"] * drawing["peak_plate_displacement_m"]
    assert drawing["peak_plate_displacement_m"] == pytest.approx(0.0171, abs=5e-4)
    assert 0.4 * DRAWN_FRACTION_OF_RADIUS * RADIUS_M < drawn <= DRAWN_FRACTION_OF_RADIUS * RADIUS_M
    assert drawing["magnify"] == 5.0 and drawing["force_arrow_n_per_m"] == 5000.0
    assert any(line.startswith("Drawing: the plate's displacement magnified x5") for line in lines)
    assert f"/drake/{ARROW_PATH}/shaft".encode() in html_commands(html.read_text())


def test_live_view_serves_on_localhost_and_exits_without_a_terminal(monkeypatch, capsys):
    answers = []
    play = MotionView.play

    def play_and_check(self, rate, **kwargs):
        with urllib.request.urlopen(self.meshcat.web_url(), timeout=10) as reply:
            answers.append(reply.status)
        return play(self, rate, **kwargs)

    monkeypatch.setattr(MotionView, "play", play_and_check)
    argv = [*STEWART, "--compensator", "SDMDC", "--meshcat", "--magnify", "50"]
    assert main([*argv, "--realtime-rate", "20"]) == 0
    assert answers == [200]  # played once (stdin is no terminal), while the server was up
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("On the Stewart table, with SDMDC the contact keeps its energy")
    url = [line for line in lines if line.startswith("Meshcat live view: ")]
    assert len(url) == 1 and re.fullmatch(r"Meshcat live view: http://localhost:\d+", url[0])
    assert any("magnified x50" in line and "20 x real time" in line for line in lines)


ERRORS = {
    "too fast": (["--table-response-hz", "200"], "needs --table-response-hz <= 50"),
    "too fast here": (
        ["--table-response-hz", "60", "--sample-rate-hz", "1000"],
        "or --sample-rate-hz >= 1200",
    ),
    "infinite": (["--table-response-hz", "inf"], "finite --table-response-hz"),
    "gap": (["--initial-gap-m", "0.3"], "needs --initial-gap-m <= 0.19"),
    "damping": (["--contact-damping-n-s-per-m", "2e5"], "critical damping (31831 N s/m"),
    "magnify": (
        ["--html", "x.html", "--magnify", "0"],
        "--magnify: must be 0.001 to 1e+06 (got 0)",
    ),
    "drawing only": (["--magnify", "3"], "of --html or --meshcat"),
    "record": (["--record", "runs"], "not with --record"),
}


@pytest.mark.parametrize("case", ERRORS)
def test_errors_name_flags_that_exist(case, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    extra, expected = ERRORS[case]
    try:
        rc = main([*STEWART, *extra])
    except SystemExit as exc:  # argparse refuses a flag's value itself
        rc = exc.code
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and expected in err
    assert "_hz" not in err and "_s " not in err  # no parameter names of the API
    named = set(re.findall(r"--[a-z][a-z0-9-]*", err))
    assert named and named <= simulate_flags(), named - simulate_flags()
    assert not (tmp_path / "x.html").exists()


def test_errors_during_the_run_name_flags_that_exist(monkeypatch, capsys):
    # 1 m/s into a 0.5 Hz contact would penetrate ~0.32 m: beyond the stroke.
    argv = ["--initial-velocity-m-per-s", "1", "--contact-frequency-hz", "0.5"]
    assert main([*STEWART, *argv]) == 1  # the run failed: exit 1, as every failed run
    workspace = capsys.readouterr().err
    assert "left its workspace" in workspace and "0.318 m" in workspace

    def cannot_tune(*args, **kwargs):
        raise ParameterError("could not tune the table to 40 Hz: the servo_bandwidth_hz ...")

    monkeypatch.setattr("hybridtable.stewart.run.tune_table", cannot_tune)
    assert main([*STEWART, "--table-response-hz", "40"]) == 2
    tuning = capsys.readouterr().err
    assert "could not be tuned to --table-response-hz 40" in tuning
    assert "servo_bandwidth_hz" not in tuning
    for err in (workspace, tuning):
        named = set(re.findall(r"--[a-z][a-z0-9-]*", err))
        assert named and named <= simulate_flags(), named - simulate_flags()
