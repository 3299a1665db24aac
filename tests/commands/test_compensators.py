"""``hybridtable compensators --quick``: JSON, report and acceptance lines."""

from __future__ import annotations


def test_compensators_command_quick(tmp_path, capsys):
    import json

    from hybridtable.cli import main

    out, report = tmp_path / "sweep.json", tmp_path / "report"
    argv = [
        "compensators",
        "--quick",
        "--compensators",
        "SDMDC,sdmdc-online",
        "--scenarios",
        "mismatch",
        "--prior-ratios",
        "0.5,1",
        "--jobs",
        "1",
        "--no-progress",
        "--report",
        str(report),
    ]
    assert main([*argv, "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert len(data["runs"]) == 8 and all(r["error"] is None for r in data["runs"])
    acc = data["acceptance"]
    assert acc["sdmdc_online"]["passed"] and acc["passivity"]["passed"]
    assert acc["fixed_k_sdmdc_at_half_k"][0]["cor_error"] > 0.04
    assert (report / "report.md").is_file()
    assert (report / "cor_error_vs_prior_stiffness.png").is_file()
    assert "sdmdc-online" in capsys.readouterr().out
    # Never overwrite a report; bad options are one-line errors with exit 2.
    assert main([*argv, "--json", str(out)]) == 2
    assert main(["compensators", "--compensators", "nonesuch", "--no-progress"]) == 2
    assert main(["compensators", "--scenarios", "nonesuch", "--no-progress"]) == 2
