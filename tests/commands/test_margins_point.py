"""``hybridtable margins``: the verdict it opens with, the gain / phase / delay
margins at the operating point, the delay a CoR limit allows, and
``--export-linear``."""

from __future__ import annotations

import json
import re

import control
import numpy as np
import pytest

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.cli import main
from hybridtable.studies.paper import paper_params

GRID = ["--sensor-delay-s", "0,0.005,0.01", "--table-response-hz", "25,100"]


def _run(capsys, *args):
    rc = main(["margins", *GRID, *args])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_undamped_contact_opens_with_the_cor_not_a_critical_delay(capsys):
    rc, out, err = _run(capsys, "--json", "-", "--no-progress")
    assert rc == 0
    doc = json.loads(out)  # nothing but JSON on stdout
    verdict = doc["verdict"]
    assert verdict.startswith("margins: an undamped contact is marginal at any delay; with SDMDC")
    # The numbers of the sentence are the grid's.
    cor = {c: np.array(v["predicted_cor"]) for c, v in doc["compensators"].items()}
    assert f"within {cor['SDMDC'].min():.3f}-{cor['SDMDC'].max():.3f} over the grid" in verdict
    assert verdict.endswith(f"without compensation it reaches {cor['none'].max():.2f}")
    point = doc["operating_point_margins"]
    assert point["sensor_delay_s"] == 0.005 and point["table_response_hz"] == 25.0
    assert point["contact_damped"] is False
    for c, m in point["compensators"].items():
        # Undamped with a lagging rig: unstable, critical delay 0, and the
        # delay margin is minus the effective delay (no damping lead).
        assert m["closed_loop_stable"] is False and m["critical_delay_s"] == 0.0
        eff = doc["compensators"][c]["effective_delay_s"][1][0]
        assert m["delay_margin_s"] == pytest.approx(-eff, rel=1e-6)
        assert m["predicted_cor"] == pytest.approx(cor[c][1][0], rel=1e-12)
    # The CoR limit: MDC (CoR 1 at zero delay) stays within 1.01 up to about 1 ms.
    mdc = point["compensators"]["MDC"]
    assert 0.0 < mdc["cor_limited_delay_s"] < 0.005
    assert point["compensators"]["none"]["cor_limited_delay_s"] == 0.0
    assert doc["cor_limit"] == 1.01
    assert len(doc["compensators"]["MDC"]["cor_limited_delay_s"]) == 2  # per table frequency


def test_console_opens_with_the_verdict_and_the_bar_stays_off_stdout(capsys):
    rc, out, err = _run(capsys)  # with the progress bar
    assert rc == 0
    lines = out.splitlines()
    assert lines[0].startswith("margins: an undamped contact is marginal at any delay")
    assert "%|" not in out and "it/s" not in out and "pt/s" not in out
    assert lines[1].startswith("at sensor delay 5 ms, table 25 Hz")
    assert any("Undamped contact" in line for line in lines)
    assert not any("0/" in line and "stable" in line for line in lines)


def test_damped_contact_opens_with_its_critical_delays(capsys):
    rc, out, err = _run(capsys, "--contact-damping-ratio", "0.05", "--json", "-")
    assert rc == 0
    doc = json.loads(out)
    point = doc["operating_point_margins"]
    assert point["contact_damped"] is True
    crit = {c: m["critical_delay_s"] for c, m in point["compensators"].items()}
    verdict = doc["verdict"]
    assert verdict.startswith("margins: at table 25 Hz the loop is stable for sensor delays below")
    shown = re.findall(r"below ([0-9.]+) ms (without compensation|with \w+)", verdict)
    assert len(shown) == 4
    for value, who in shown:
        c = "none" if who == "without compensation" else who.split()[1]
        assert float(value) * 1e-3 == pytest.approx(crit[c], rel=5e-3)
    # No compensator: the delay margin at 5 ms is what is left to the critical delay.
    none = point["compensators"]["none"]
    assert none["closed_loop_stable"] and none["gain_margin"] > 1.0
    assert none["delay_margin_s"] == pytest.approx(none["critical_delay_s"] - 0.005, rel=1e-4)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_export_linear_loads_in_python_control(tmp_path, capsys, suffix):
    path = tmp_path / f"loop{suffix}"
    args = ["--compensator", "none,MDC", "--export-linear", str(path), "--no-progress"]
    args += ["--operating-delay-s", "0.004", "--operating-table-hz", "50"]
    rc, out, _ = _run(capsys, *args)
    assert rc == 0 and f"wrote {path}" in out
    d = json.load(open(path)) if suffix == ".json" else np.load(path)
    G = control.ss(d["A"], d["B"], d["C"], d["D"], float(d["dt"]))
    # The tool's linearization at that point, of the default compensator (SDMDC
    # if listed, else the first listed: none).
    p = paper_params(sensor_delay_s=0.004, table_response_hz=50.0, compensator="none")
    ref = ContactLoopLinearizer(3).open_loop(p).closed_loop_poles()
    key = lambda z: (round(z.real, 6), round(z.imag, 6))  # noqa: E731
    np.testing.assert_allclose(
        sorted(control.feedback(G, 1, sign=1).poles(), key=key), sorted(ref, key=key), rtol=1e-9
    )
    # The overwrite policy: refused without --force, replaced with it.
    rc, _, err = _run(capsys, *args)
    assert rc == 2 and "--export-linear" in err and "--force" in err
    rc, _, _ = _run(capsys, *args, "--force", "--export-compensator", "MDC")
    assert rc == 0
    doc = json.load(open(path)) if suffix == ".json" else json.loads(str(np.load(path)["metadata"]))
    assert doc["compensator"] == "MDC"


@pytest.mark.parametrize(
    "args",
    [
        ["--export-linear", "loop.mat"],
        ["--export-linear", "loop.json", "--export-compensator", "SDC", "--compensator", "MDC"],
        ["--cor-limit", "0"],
        ["--operating-table-hz", "0"],
    ],
)
def test_bad_operating_options_are_one_line_exit_2(args, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        rc = main(["margins", "--no-progress", *GRID[:2], "--table-response-hz", "25", *args])
    except SystemExit as exc:  # a value out of range is refused by argparse, naming the flag
        rc = exc.code
    err = capsys.readouterr().err.strip()
    assert rc == 2 and err.count("\n") == 0 and "error" in err
    assert not (tmp_path / "loop.json").exists()


def test_report_has_every_figure_with_a_caption(tmp_path, capsys):
    rep = tmp_path / "rep"
    rc, _, _ = _run(capsys, "--report", str(rep), "--no-progress", "--compensator", "MDC,SDMDC")
    assert rc == 0
    lines = (rep / "report.md").read_text().splitlines()
    figures = [i for i, line in enumerate(lines) if line.startswith("![")]
    assert len(figures) == 4
    for i in figures:
        name = lines[i][lines[i].index("(") + 1 : -1]
        assert (rep / name).stat().st_size > 10_000
        caption = lines[i + 1]
        assert caption.startswith("*") and caption.endswith("*") and "[" in caption
    text = "\n".join(lines)
    assert "## At the operating point" in text and "gain margin" in text
    assert lines[2].startswith("Margins: an undamped contact is marginal")
