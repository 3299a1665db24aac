"""``hybridtable sweep SPEC --report DIR`` end to end: a 4-run campaign through
the Drake diagram on a one-worker Dask cluster leaves the Parquet file and a
report folder whose figures, captions and worst runs are those of the runs."""

from __future__ import annotations

import re

import pyarrow.parquet as pq

from hybridtable.cli import main

SPEC = """
name = "delay_vs_table"
description = "Two delays, two tables, no compensation"
seed = 7
engine = "diagram"
metrics = ["cor", "peak_force_n"]

[grid]
sensor_delay_s = [0.001, 0.005]
table_response_hz = [25.0, 100.0]
"""


def test_sweep_writes_a_report_of_its_runs(tmp_path, capsys):
    spec, out, report = tmp_path / "spec.toml", tmp_path / "runs.parquet", tmp_path / "report"
    spec.write_text(SPEC)
    argv = ["sweep", str(spec), "--out", str(out), "--report", str(report)]
    assert main([*argv, "--workers", "1", "--no-progress"]) == 0
    table = pq.read_table(out)
    assert table.num_rows == 4 and set(table.column("status").to_pylist()) == {"ok"}
    names = sorted(p.name for p in report.iterdir())
    figures = ["cor_cdf.png", "cor_map.png", "stability_boundary.png"]
    assert names == sorted([*figures, "report.md", "report.html"])
    for name in figures:
        assert (report / name).read_bytes()[:4] == b"\x89PNG"
    printed = capsys.readouterr().out
    for name in names:  # the command names every file the report wrote
        assert f"wrote {report / name}" in printed
    text = (report / "report.md").read_text()
    lines = text.splitlines()
    assert lines[0] == r"# Sweep delay\_vs\_table"
    assert lines[2].startswith(r"**sweep delay\_vs\_table: 4 of 4 runs finished; none gives CoR")
    for name in figures:
        i = lines.index(next(line for line in lines if line.endswith(f"]({name})")))
        assert re.fullmatch(r"\*[^*\s].*\*", lines[i + 1])
    # Every run gains energy; the worst is the longest delay on the slowest table.
    worst = [line for line in lines if re.match(r"\| \d+ \| none \|", line)]
    assert len(worst) == 4
    assert worst[0].startswith("| 2 | none | 0.005 | 25 | 1.16")
    cors = [float(line.split(" | ")[4]) for line in worst]
    assert cors == sorted(cors, reverse=True) and min(cors) > 1.0
    assert "| all | 4 | 4 |" in text
