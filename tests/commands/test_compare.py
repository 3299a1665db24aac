"""``hybridtable compare`` as a user sees it: the verdict first, fit % per
channel in the table and JSON, the whiteness in words, run ids whole, a report
whose every figure has a caption, outputs replaced only with ``--force``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from hybridtable.cli import main
from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.phases import PHASES
from hybridtable.measurement.run_reader import read_run
from tests.examples import EXAMPLES
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record, write_run

LONG_ID = "rig-B-2024-06-12-damped-contact-trial-07"  # 40 characters


@pytest.fixture(scope="module")
def damped_dir(tmp_path_factory) -> Path:
    """One run of a rig whose contact has 600 N s/m of damping the model lacks."""
    folder = tmp_path_factory.mktemp("damped")
    info = dict(NOMINAL, run_id=LONG_ID)
    contact = damped_spring(NOMINAL["contact_stiffness_n_per_m"], 600.0)
    write_run(folder, "damped", info, simulate_record(info, contact))
    return folder


def _fit_by_hand(y: np.ndarray, y_hat: np.ndarray) -> float:
    return 100.0 * (1.0 - np.linalg.norm(y - y_hat) / np.linalg.norm(y - y.mean()))


def test_console_opens_with_the_verdict_on_the_examples(tmp_path, capsys):
    out_json = tmp_path / "result.json"
    assert main(["compare", str(EXAMPLES), "--json", str(out_json)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert lines[0].startswith("The model matches the 3 runs within the noise (force error ")
    assert "the noise; fit " in lines[0]
    # The examples' position residual follows the command (docs/compare.md,
    # Limitations): the verdict says it, as too small to matter.
    assert re.search(
        r"% position\); the position residual still has structure in 3 of 3 runs \(a "
        r"systematic effect too small to matter: error at most 1\.\d\dx the noise\)$",
        lines[0],
    )
    assert "compare" not in out.replace("hybridtable compare", "")  # progress bar on stderr
    data = json.loads(out_json.read_text())
    assert data["verdict"] == lines[0]
    # The table shows each run's fit (force/position) as the JSON holds it.
    for entry in data["runs"]:
        fit = entry["fit_percent"]
        assert set(fit) == {"f_mea_n", "p_act_m"}
        assert 98.0 < fit["f_mea_n"] < 100.0 and 99.9 < fit["p_act_m"] < 100.0
        row = next(line for line in lines if line.startswith(entry["run_id"] + " "))
        assert f"{fit['f_mea_n']:.1f}/" in row
    lo = min(e["fit_percent"]["f_mea_n"] for e in data["runs"])
    assert f"fit {lo:.1f}-" in lines[0]
    # Whiteness in words: the force residual is noise in every run; the
    # examples' position residual follows the command (docs/compare.md,
    # Limitations) but stays within the noise.
    force = [line for line in lines if "  force:" in line]
    position = [line for line in lines if "  position:" in line]
    assert len(force) == len(position) == 3
    assert all("the residual is white: what is left is sensor noise" in x for x in force)
    assert all("a small one (error 1.0" in x for x in position if "follows the command" in x)
    assert "diagnose" not in "\n".join(position)


def test_fit_percent_in_json_is_the_nrmse_fit_by_hand(capsys):
    run = read_run(EXAMPLES / "run2.csv")
    replay = compare_run(run).replay
    assert main(["compare", str(EXAMPLES / "run2.csv"), "--json", "-"]) == 0
    out = capsys.readouterr().out
    (entry,) = json.loads(out)["runs"]  # nothing but JSON on stdout
    assert entry["fit_percent"]["f_mea_n"] == pytest.approx(
        _fit_by_hand(run.f_mea_n, replay.f_mea_n), abs=1e-9
    )
    assert entry["fit_percent"]["p_act_m"] == pytest.approx(
        _fit_by_hand(run.p_act_m, replay.p_act_m), abs=1e-9
    )
    assert entry["within_noise"] == {"f_mea_n": True, "p_act_m": True}


def test_damped_rig_long_run_id_verdict_whiteness_and_report(damped_dir, tmp_path, capsys):
    assert len(LONG_ID) == 40
    report = tmp_path / "report"
    assert main(["compare", str(damped_dir), "--report", str(report)]) == 0
    lines = capsys.readouterr().out.splitlines()
    # The verdict names the channel, its size and the phase, and the next step.
    first = lines[0]
    assert first.startswith("The model misses something in the run: force error ")
    ratio = float(first.split("force error ")[1].split("x")[0])
    assert ratio > 5.0
    assert "worst in compression" in first and first.endswith("try hybridtable diagnose")
    assert "position" not in first  # the table is not affected
    # The run id whole, and the columns after it aligned with the header.
    head = next(line for line in lines if line.startswith("run "))
    row = next(line for line in lines if line.startswith(LONG_ID + " "))
    assert row.index("SDMDC") == head.index("comp")
    assert row.index(" x") > len(LONG_ID)
    # Whiteness: the force residual is structure, the position residual noise.
    force = next(line for line in lines if line.startswith(f"  {LONG_ID}  force:"))
    assert "the residual is not noise" in force and "try hybridtable diagnose" in force
    position = next(line for line in lines if line.startswith(f"  {LONG_ID}  position:"))
    assert "the residual is white: what is left is sensor noise" in position
    # The report: verdict first, run id whole, every figure with a caption.
    md = (report / "report.md").read_text().splitlines()
    assert md[2] == f"**{first}.**"
    assert any(line.startswith(LONG_ID + " ") for line in md)
    figures = [i for i, line in enumerate(md) if line.startswith("![")]
    assert len(figures) == 4
    for i in figures:
        name = md[i][md[i].index("](") + 2 : -1]
        assert (report / name).stat().st_size > 1000
        caption = md[i + 1]
        assert caption.startswith("*") and caption.endswith("*") and "[" in caption
    assert any("the residual is not noise" in line for line in md)


def test_outputs_replaced_only_with_force(tmp_path, capsys):
    out = tmp_path / "result.json"
    report = tmp_path / "report"
    args = ["compare", str(EXAMPLES / "run2.csv"), "--json", str(out), "--report", str(report)]
    assert main(args) == 0
    data = json.loads(out.read_text())
    (entry,) = data["runs"]
    assert set(entry["phases"]) == set(PHASES)
    assert sum(ph["share"] for ph in entry["phases"].values()) == pytest.approx(1.0)
    capsys.readouterr()
    assert main(args) == 2
    assert "--force" in capsys.readouterr().err
    assert main([*args, "--force"]) == 0
