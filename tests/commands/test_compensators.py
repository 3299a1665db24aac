"""``hybridtable compensators --quick``: the verdict, the checks in JSON and as
sentences, the report with a caption under every figure, the overwrite policy."""

from __future__ import annotations

import json
import re

from hybridtable.cli import main


def test_compensators_command_quick(tmp_path, capsys):
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
    assert len(data["runs"]) == 8 and all(r["error"] == "" for r in data["runs"])
    assert "acceptance" not in data
    found = data["checks"]
    assert found["sdmdc_online"]["passed"] and found["passivity"]["passed"]
    # The stiffness believed 50 % low: fixed-k SDMDC overshoots by +0.05 at Table 1.
    assert found["fixed_k_sdmdc_at_half_k"][0]["cor_error"] > 0.04
    text = capsys.readouterr().out
    lines = text.splitlines()
    # The first line is the verdict: sdmdc-online comes closest, SDMDC leaves ~0.05.
    assert lines[0].startswith("Closest to the ideal loop at the Table 1 point under a believed")
    assert ": sdmdc-online (worst" in lines[0]
    m = re.search(r"SDMDC leaves (\d\.\d{3})", lines[0])
    assert m and 0.04 < float(m.group(1)) < 0.06
    assert "sdmdc-online keeps |CoR error| <= 0.000" in text
    assert re.search(r"the passivity guard holds CoR <= (0\.9\d\d|1\.000) in all 4 guarded", text)
    assert "PASS" not in text and "FAIL" not in text and "acceptance" not in text
    md = (report / "report.md").read_text().splitlines()
    figures = [i for i, line in enumerate(md) if line.startswith("![")]
    assert len(figures) == 4
    for i in figures:
        assert md[i].endswith(".png)") and re.fullmatch(r"\*[^*].*\*", md[i + 1])
    assert (report / "cor_error_vs_prior_stiffness.png").is_file()
    # An existing report is replaced only with --force; bad options are one-line errors.
    assert main([*argv, "--json", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["compensators", "--compensators", "nonesuch", "--no-progress"]) == 2
    assert main(["compensators", "--scenarios", "nonesuch", "--no-progress"]) == 2
