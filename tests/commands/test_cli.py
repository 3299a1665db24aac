"""The ``hybridtable`` CLI: simulate, reproduce, bad input."""

import json
import re
import subprocess
import sys

import pytest

from hybridtable.cli import main


@pytest.mark.parametrize(
    "args, name",
    [
        (
            ["--sensor-delay-s", "-0.001"],
            "--sensor-delay-s: must be 0, or 1e-06 to 1 [s] (got -0.001)",
        ),
        (
            ["--contact-stiffness-n-per-m", "nan"],
            "--contact-stiffness-n-per-m: must be 1 to 1e+10 [N/m]",
        ),
        (["--compensator", "XYZ"], "--compensator must be one of none, SDC"),
        (
            ["--contact-frequency-hz", "0"],
            "--contact-frequency-hz: must be 0.001 to 10000 [Hz] (got 0)",
        ),
        (["--table-damping-ratio", "-1"], "--table-damping-ratio: must be 0 to 10 (got -1)"),
        (["--initial-velocity-m-per-s", "abc"], "--initial-velocity-m-per-s: not a number"),
        (["--table-response-hz", "0"], "--table-response-hz: must be 0.1 to 10000, or inf [Hz]"),
        (["--table-response-hz", "1e6"], "--table-response-hz: must be 0.1 to 10000, or inf [Hz]"),
        (
            ["--sensor-delay-s", "1e300"],
            "--sensor-delay-s: must be 0, or 1e-06 to 1 [s] (got 1e300)",
        ),
        (["--sensor-delay-s", "1e-300"], "--sensor-delay-s: must be 0, or 1e-06 to 1 [s]"),
        (["--table-response-hz", "1" + "0" * 400], "--table-response-hz: too large"),
        (["--initial-gap-m", "1e300"], "--initial-gap-m: must be 0 to 10 [m] (got 1e300)"),
        (["--contact-frequency-hz", "1e-300"], "--contact-frequency-hz: must be 0.001 to 10000"),
    ],
)
def test_bad_parameter_is_one_line_and_exit_2(args, name, capsys):
    with pytest.raises(SystemExit) as exc:
        sys.exit(main(["simulate", *args]))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert name in err
    assert "Traceback" not in err


def test_zero_mass_via_stiffness_is_rejected_without_traceback():
    proc = subprocess.run(
        [sys.executable, "-m", "hybridtable.cli", "simulate", "--contact-stiffness-n-per-m", "0"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert "--contact-stiffness-n-per-m" in proc.stderr


def test_simulate_json_and_plot(tmp_path):
    out = tmp_path / "run.json"
    png = tmp_path / "run.png"
    assert main(["simulate", "--compensator", "SDMDC", "--json", str(out), "--plot", str(png)]) == 0
    data = json.loads(out.read_text())
    assert data["cor"] == pytest.approx(1.0, abs=0.003)
    assert data["peak_force_n"] > 0 and data["contact_duration_s"] > 0
    assert png.stat().st_size > 10_000


def test_help_for_every_command():
    for cmd in (["--help"], ["simulate", "--help"], ["reproduce", "--help"]):
        with pytest.raises(SystemExit) as exc:
            main(cmd)
        assert exc.value.code == 0


def test_every_help_reads_as_written_and_the_version_is_given(capsys):
    """No command's help shows a doubled ``%%`` (argparse formats only the
    options' help, not a description), and ``--version`` names the version."""
    from hybridtable.cli import COMMANDS, build_parser

    parser = build_parser()
    for name in ["", *(m.__name__.rsplit(".", 1)[-1] for m in COMMANDS)]:
        with pytest.raises(SystemExit) as exc:
            parser.parse_args([name, "--help"] if name else ["--help"])
        assert exc.value.code == 0
        text = capsys.readouterr().out
        assert "%%" not in text, f"{name or 'hybridtable'} --help prints %%"
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert re.fullmatch(r"hybridtable \d+\.\d+\.\d+\S*\n", capsys.readouterr().out)


def test_reproduce_json_shape_and_tables(tmp_path):
    out = tmp_path / "rep.json"
    figs = tmp_path / "figs"
    assert main(["reproduce", "--json", str(out), "--out-dir", str(figs), "--no-progress"]) == 0
    data = json.loads(out.read_text())
    assert set(data["table1"]) == {"none", "SDC", "MDC", "SDMDC"}
    for c, cor in data["table1"].items():
        assert cor == pytest.approx(data["table1_paper"][c], abs=0.003)
        assert abs(data["table1_half_step"][c] - cor) < 5e-4
    assert len(data["table2"]) == 15
    keys = {
        "sensor_delay_ms",
        "table_response_hz",
        "contact_frequency_hz",
        "contact_stiffness_n_per_mm",
        "initial_velocity_mm_per_s",
        "cor_sdmdc",
        "paper",
    }
    for row in data["table2"]:
        assert keys <= set(row)
        assert row["cor_sdmdc"] == pytest.approx(row["paper"], abs=0.01)
        assert abs(row["cor_sdmdc_half_step"] - row["cor_sdmdc"]) < 5e-4
    # The paper's order: delays 1, 3, 5 ms come first.
    assert [r["sensor_delay_ms"] for r in data["table2"][:3]] == [1, 3, 5]
    names = sorted(p.name for p in figs.glob("*.png"))
    assert names == sorted(
        [
            "fig3_sensor_delay.png",
            "fig4_table_response.png",
            "fig5_both_delays.png",
            "fig6_compensated_velocity.png",
            "fig7_compensated_force.png",
        ]
    )


#: Endings of option names that carry a unit, and the unit the help must show.
_UNIT_SUFFIXES = {
    "_s": "[s]",
    "_hz": "[Hz]",
    "_n": "[N]",
    "_m": "[m]",
    "_n_per_m": "[N/m]",
    "_n_s_per_m": "[N s/m]",
    "_m_per_s": "[m/s]",
    "_ratio": "[1]",
}


def _options():
    import argparse

    from hybridtable.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        for a in p._actions:
            if a.option_strings and a.nargs != 0 and a.dest != "help":
                yield name, a


def test_help_shows_the_unit_of_every_physical_option():
    missing = []
    for name, a in _options():
        suffix = max((s for s in _UNIT_SUFFIXES if a.dest.endswith(s)), key=len, default=None)
        if suffix is None or a.dest.endswith(("_json", "_ms")):
            continue
        unit = _UNIT_SUFFIXES[suffix]
        if unit == "[1]" and "[1]" not in (a.help or "") and "ratio" in (a.help or ""):
            continue  # a ratio named in words, e.g. "believed / true stiffness ratio"
        if unit not in (a.help or ""):
            missing.append(f"{name} {a.option_strings[-1]}: {a.help!r}")
    assert missing == []


def test_help_shows_every_default():
    from hybridtable.cli import _HelpFormatter

    missing = []
    for name, a in _options():
        if a.default is None or a.default == []:
            continue  # "not given" (an output, an optional input, a derived value)
        text = _HelpFormatter("x")._get_help_string(a)
        if "default" not in text:
            missing.append(f"{name} {a.option_strings[-1]}")
    assert missing == []


def test_a_closed_pipe_stops_quietly_and_the_files_are_written(tmp_path):
    # `hybridtable simulate --json out.json | head -0`: the reader has gone
    # before the first line; the console text stops, the JSON is still written.
    out = tmp_path / "out.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "hybridtable.cli", "simulate", "--json", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait() == 0
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert json.loads(out.read_text())["cor"] > 1.1
    # With the JSON itself on the closed stdout, it is lost: exit 141.
    proc = subprocess.Popen(
        [sys.executable, "-m", "hybridtable.cli", "simulate", "--json", "-"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait() == 141 and "Traceback" not in err, err


def test_every_json_document_records_its_inputs(tmp_path):
    """A document opens with what the command was asked (every option, the
    defaults applied); simulate's also holds the loop it simulated."""
    out = tmp_path / "s.json"
    assert (
        main(["simulate", "--compensator", "SDC", "--sensor-delay-s", "0.004", "--json", str(out)])
        == 0
    )
    data = json.loads(out.read_text())
    assert next(iter(data)) == "inputs"
    inputs = data["inputs"]
    assert inputs["command"] == "simulate" and inputs["compensator"] == "SDC"
    assert inputs["sensor_delay_s"] == 0.004 and inputs["table_response_hz"] is None
    assert not any(k.startswith("_") for k in inputs)
    assert data["params"]["sensor_delay_s"] == 0.004
    assert data["params"]["table_response_hz"] == 25.0  # the default, resolved


def test_a_compensator_is_named_in_any_letter_case_everywhere(tmp_path):
    """simulate refused ``sdmdc`` while explain accepted it: a registered name
    spelled in other letter case is that compensator in every command and in
    the API; an unknown one is still one line naming the choices."""
    from hybridtable.errors import ParameterError
    from hybridtable.studies.paper import table1_params

    assert table1_params("sdmdc").compensator == "SDMDC"
    assert table1_params("Sdmdc-Online").compensator == "sdmdc-online"
    with pytest.raises(ParameterError, match="compensator must be one of"):
        table1_params("pid")
    out = tmp_path / "s.json"
    assert main(["simulate", "--compensator", "sdmdc", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["compensator"] == "SDMDC"
    argv = ["margins", "--compensator", "sdc,SDMDC", "--sensor-delay-s", "0.005"]
    assert main([*argv, "--table-response-hz", "25", "--no-progress"]) == 0
