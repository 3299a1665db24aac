"""The ``hybridtable margins`` command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hybridtable.cli import main
from hybridtable.commands._grid import default_delays, parse_list
from hybridtable.errors import CommandError


def test_parse_list():
    np.testing.assert_allclose(parse_list("0:0.02:5", "x"), [0, 0.005, 0.01, 0.015, 0.02])
    np.testing.assert_allclose(parse_list("5, 25,inf", "x"), [5, 25, np.inf])
    np.testing.assert_allclose(parse_list("3:3:1", "x"), [3])
    for bad in ("", "a,b", "0:1", "0:1:0", "0:1:2.5", "nan", "0:inf:3"):
        with pytest.raises(CommandError):
            parse_list(bad, "--x")


def test_default_delays():
    d = default_delays(None)
    assert d.size == 41 and d[0] == 0.0 and d[-1] == pytest.approx(0.02)
    s = default_delays(1000.0)
    np.testing.assert_allclose(s * 1000.0, np.round(s * 1000.0), atol=1e-9)
    assert s[-1] == pytest.approx(0.02) and s.size == 21


def test_json_document(tmp_path):
    out = tmp_path / "m.json"
    rc = main(
        [
            "margins",
            "--sensor-delay-s",
            "0,0.005",
            "--table-response-hz",
            "25,50,100",
            "--compensator",
            "none,SDMDC",
            "--json",
            str(out),
            "--no-progress",
        ]
    )
    assert rc == 0
    d = json.loads(out.read_text())
    assert d["grid"] == {"sensor_delay_s": [0.0, 0.005], "table_response_hz": [25.0, 50.0, 100.0]}
    assert set(d["compensators"]) == {"none", "SDMDC"}
    for key in ("predicted_cor", "phase_margin_deg", "damping_ratio"):
        a = np.array(d["compensators"]["none"][key])
        assert a.shape == (2, 3)
    assert len(d["compensators"]["none"]["critical_delay_s"]) == 3
    assert d["compensators"]["none"]["predicted_cor"][1][0] == pytest.approx(1.16115, abs=1e-4)
    assert d["validation"] == []


def test_report_and_validation(tmp_path, capsys):
    rep = tmp_path / "rep"
    rc = main(
        [
            "margins",
            "--sensor-delay-s",
            "0.002,0.01",
            "--table-response-hz",
            "20,80",
            "--validate",
            "1",
            "--report",
            str(rep),
            "--json",
            str(tmp_path / "m.json"),
            "--no-progress",
        ]
    )
    assert rc == 0
    for name in ("cor_heatmaps.png", "critical.png", "energy_growth.png", "bode_table1.png"):
        assert (rep / name).stat().st_size > 10_000
    summary = (rep / "report.md").read_text()
    assert "Table 1 point" in summary and "Validation" in summary
    d = json.loads((tmp_path / "m.json").read_text())
    assert len(d["validation"]) == 4  # one point x four compensators
    assert d["max_validation_abs_error"] < 0.005
    t1 = d["table1_point"]["SDMDC"]
    assert t1["margins"]["predicted_cor"] == pytest.approx(t1["cor_sim"], abs=0.002)
    assert "max |CoR_linear - CoR_sim|" in capsys.readouterr().out
    # Never overwrite: the same directory again is refused.
    rc = main(
        ["margins", "--sensor-delay-s", "0", "--table-response-hz", "25", "--report", str(rep)]
    )
    assert rc == 2


@pytest.mark.parametrize(
    "args",
    [
        ["--sensor-delay-s", "0:0.01"],
        ["--sensor-delay-s", "-0.001"],
        ["--table-response-hz", "0,25"],
        ["--compensator", "PID"],
        ["--pade-order", "0"],
        ["--pade-order", "100"],
        ["--contact-frequency-hz", "1e300"],
        ["--sensor-delay-s", "0,1e300"],
        ["--table-response-hz", "25,1e300"],
    ],
)
def test_bad_input_is_one_line_exit_2(args, capsys):
    try:
        rc = main(["margins", *args, "--no-progress"])
    except SystemExit as exc:  # argparse refuses a flag's value itself
        rc = exc.code
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert err.count("\n") == 0 and "error" in err


def test_sampled_run(tmp_path):
    out = tmp_path / "s.json"
    rc = main(
        [
            "margins",
            "--sample-rate-hz",
            "500",
            "--sensor-delay-s",
            "0,0.004",
            "--table-response-hz",
            "25",
            "--compensator",
            "MDC",
            "--json",
            str(out),
            "--no-progress",
        ]
    )
    assert rc == 0
    d = json.loads(out.read_text())
    assert d["model"]["kind"] == "sampled" and d["model"]["pade_order"] is None
    assert d["compensators"]["MDC"]["predicted_cor"][1][0] > 1.0


def test_a_sampled_grid_takes_delays_between_ticks(tmp_path):
    # 1.5 ms at 1 kHz: the sensor reads the samples 1 and 2 ticks old, mixed
    # half and half, so its CoR lies between theirs (it used to be refused).
    out = tmp_path / "s.json"
    argv = ["margins", "--sample-rate-hz", "1000", "--sensor-delay-s", "0.001,0.0015,0.002"]
    argv += ["--table-response-hz", "25", "--compensator", "none", "--operating-delay-s", "0.0045"]
    assert main([*argv, "--json", str(out), "--no-progress"]) == 0
    cor = [row[0] for row in json.loads(out.read_text())["compensators"]["none"]["predicted_cor"]]
    assert cor[0] < cor[1] < cor[2]
