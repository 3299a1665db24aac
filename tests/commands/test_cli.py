"""The ``hybridtable`` CLI: simulate, reproduce, bad input."""

import json
import subprocess
import sys

import pytest

from hybridtable.cli import main


@pytest.mark.parametrize(
    "args, name",
    [
        (["--sensor-delay-s", "-0.001"], "--sensor-delay-s: must be >= 0 [s] (got -0.001)"),
        (["--contact-stiffness-n-per-m", "nan"], "--contact-stiffness-n-per-m: must be > 0 [N/m]"),
        (["--compensator", "XYZ"], "--compensator must be one of none, SDC"),
        (["--contact-frequency-hz", "0"], "--contact-frequency-hz: must be > 0 [Hz] (got 0)"),
        (["--table-damping-ratio", "-1"], "--table-damping-ratio: must be >= 0 (got -1)"),
        (["--initial-velocity-m-per-s", "abc"], "--initial-velocity-m-per-s: not a number"),
        (["--table-response-hz", "0"], "--table-response-hz: must be > 0 (or inf) [Hz]"),
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


def test_a_parameter_error_names_the_flag_of_its_field(capsys):
    # Checked by the parameter dataclass, not by argparse: still named as a flag.
    assert main(["simulate", "--compensator", "SDMDC", "--table-response-hz", "inf"]) == 0
    capsys.readouterr()
    assert main(["margins", "--table-damping-ratio", "-1"]) == 2
    assert "--table-damping-ratio must be >= 0" in capsys.readouterr().err


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
