"""The report of a campaign (``hybridtable sweep --report``): its figures and
their captions, the CoR map's axes, the stability boundary against a known
one, the worst runs, and the campaigns that give little to draw (margins only,
all diverged, all invalid, text inputs only, one run)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hybridtable.reports.sweep import (
    STABLE_COR,
    axis_label,
    classify_runs,
    plane_inputs,
    stability_map,
    worst_runs,
    write_report,
)
from hybridtable.reports.sweep_summary import summarize, verdict
from hybridtable.sweeps.runner import blank_row, run_one
from hybridtable.sweeps.spec import parse_spec
from hybridtable.sweeps.store import read_results, write_results

FIGURE_LINE = re.compile(r"!\[[^\]]*\]\(([^)]*\.png)\)")
CAPTION_LINE = re.compile(r"\*[^*\s].*\*")
UNIT = re.compile(r"\[[^\[\]]+\]")

#: The hand-made loop: CoR = 1 + A delay - B / table frequency (SDMDC 0.05 lower).
A_PER_S, B_HZ = 40.0, 2.0


def known_cor(delay_s, table_hz, compensator="none"):
    return 1.0 + A_PER_S * delay_s - B_HZ / table_hz - (0.05 if compensator == "SDMDC" else 0.0)


def fill_known(row, values):
    cor = known_cor(values["sensor_delay_s"], values["table_response_hz"], row["compensator"])
    if cor > 1.2:
        return "diverged", "the loop diverged: |v| grew past 10 m/s"
    row["cor"] = cor
    return "ok", ""


GRID = {
    "name": "delay_vs_table",
    "description": "a made-up loop | with *Markdown* characters",
    "seed": 3,
    "metrics": ["cor", "peak_force_n"],
    "compensators": ["none", "SDMDC"],
    "base": {"contact_frequency_hz": 1.0},
    "grid": {
        "sensor_delay_s": {"start": 0.0005, "stop": 0.006, "num": 8},
        "table_response_hz": {"start": 10.0, "stop": 200.0, "num": 9, "scale": "log"},
    },
}


def campaign(tmp_path: Path, raw: dict, fill=fill_known, rows=None):
    """The spec, table and summary of ``raw`` with rows filled by ``fill``
    (or given), through the Parquet file."""
    spec = parse_spec(raw)
    if rows is None:
        rows = []
        for i in range(spec.n_runs):
            inputs = spec.run_inputs(i)
            row = blank_row(spec, inputs)
            status, message = fill(row, inputs.values)
            row.update(status=status, message=message, engine="fast", seconds=0.01)
            rows.append(row)
    write_results(tmp_path / "runs.parquet", spec, rows)
    table = read_results(tmp_path / "runs.parquet", spec)
    return spec, table, summarize(table, spec.n_runs, spec.metrics)


@pytest.fixture
def axes_seen(monkeypatch):
    """``(file, x label, y label, x scale, y scale)`` of every axes saved."""
    from matplotlib.figure import Figure

    seen = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        for ax in self.axes:
            seen.append(
                (Path(str(fname)).name, ax.get_xlabel(), ax.get_ylabel())
                + (ax.get_xscale(), ax.get_yscale())
            )
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return seen


def report(tmp_path: Path, spec, table, summary) -> tuple[list[Path], str]:
    folder = tmp_path / "report"
    folder.mkdir()
    paths = write_report(table, spec, summary, folder)
    assert all(p.parent == folder and p.stat().st_size > 0 for p in paths)
    assert sorted(p.name for p in folder.iterdir()) == sorted(p.name for p in paths)
    return paths, (folder / "report.md").read_text()


def figures_with_captions(text: str) -> dict[str, str]:
    lines = text.splitlines() + [""]
    found = {}
    for i, line in enumerate(lines):
        m = FIGURE_LINE.fullmatch(line.strip())
        if m:
            assert CAPTION_LINE.fullmatch(lines[i + 1].strip()), f"no caption under {line}"
            found[m.group(1)] = lines[i + 1]
    return found


def test_a_grid_campaign_gives_three_captioned_figures_with_units(tmp_path, axes_seen):
    spec, table, summary = campaign(tmp_path, GRID)
    paths, text = report(tmp_path, spec, table, summary)
    names = [p.name for p in paths]
    assert names == [
        "cor_map.png",
        "cor_cdf.png",
        "stability_boundary.png",
        "report.md",
        "report.html",
    ]
    for p in paths[:3]:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert set(figures_with_captions(text)) == set(names[:3])
    # The report opens with the verdict, then the campaign.
    head = [line for line in text.splitlines() if line.strip()]
    assert head[0] == r"# Sweep delay\_vs\_table"
    assert head[1].replace("\\", "") == f"**{verdict(spec.name, summary)}.**"
    assert f"{summary['status']['diverged']} diverged" in head[1]
    assert r"description: a made-up loop \| with \*Markdown\* characters" in text
    assert "`sensor_delay_s` (grid, 8 values): 0.0005 to 0.006 s" in text
    assert "metrics: `cor`, `peak_force_n`" in text
    # Every label has a unit; the table axis spans 1.3 decades (log), the delay
    # 1.08 (log too), the CDF's CoR less than one (linear).
    assert all(UNIT.search(label) for *_, x, y, _, _ in axes_seen for label in (x, y) if label)
    maps = [a for a in axes_seen if a[0] == "cor_map.png" and a[1]]
    assert len(maps) == 2  # a panel per compensator (the colour bar has only a y label)
    assert {a[1] for a in maps} == {"table response [Hz]"}
    assert {a[2] for a in maps} == {"sensor delay [s]"}
    assert {a[3] for a in maps} == {"log"} and {a[4] for a in maps} == {"log"}
    cdf = [a for a in axes_seen if a[0] == "cor_cdf.png"]
    assert cdf == [("cor_cdf.png", "CoR [1]", "fraction of runs [1]", "linear", "linear")]
    html = (tmp_path / "report" / "report.html").read_text()
    assert html.count("<figcaption>") == 3 and "data:image/png;base64," in html


def test_the_map_takes_the_two_inputs_with_most_values_and_shows_cell_counts(tmp_path):
    raw = {
        "name": "with_draws",
        "metrics": ["cor"],
        "grid": {"sensor_delay_s": [0.001, 0.002, 0.003], "table_response_hz": [20.0, 40.0]},
        "monte_carlo": {
            "samples": 3,
            "draw": {"initial_velocity_m_per_s": {"distribution": "choice", "values": [0.1]}},
        },
    }
    spec, table, summary = campaign(tmp_path, raw)
    # The drawn velocity has one value: the map is delay (3) against table (2).
    assert plane_inputs(spec, table) == ("sensor_delay_s", "table_response_hz")
    _, text = report(tmp_path, spec, table, summary)
    caption = figures_with_captions(text)["cor_map.png"]
    assert "median over the other inputs and samples (numbers: the runs of a cell, up to 3)" in (
        caption
    )
    assert "black line: CoR = 1" in caption  # the known CoR crosses 1 inside the grid


def test_the_stability_boundary_on_a_grid_is_the_known_one(tmp_path):
    spec, table, _ = campaign(tmp_path, GRID)
    classes = classify_runs(table, spec.metrics)
    delay = np.asarray(table.column("sensor_delay_s").to_pylist())
    table_hz = np.asarray(table.column("table_response_hz").to_pylist())
    comps = np.asarray(table.column("compensator").to_pylist())
    for comp in ("none", "SDMDC"):
        m = comps == comp
        truth = known_cor(delay[m], table_hz[m], comp) <= STABLE_COR
        assert 0 < truth.sum() < m.sum()  # the boundary crosses the grid
        assert np.array_equal(classes[m] == 1.0, truth)
        gx, gy, frac = stability_map(table_hz[m], delay[m], classes[m], True, False)
        assert frac.shape == (8, 9) and np.isfinite(frac).all()
        expected = known_cor(gy[:, None], gx[None, :], comp) <= STABLE_COR
        assert np.array_equal(frac == 1.0, expected) and set(np.unique(frac)) <= {0.0, 1.0}


def test_the_stability_classifier_of_scattered_runs_finds_the_known_boundary():
    rng = np.random.default_rng(1)
    delay = rng.uniform(0.0005, 0.006, 600)
    table_hz = np.exp(rng.uniform(np.log(10.0), np.log(200.0), 600))
    cor = known_cor(delay, table_hz)
    classes = (cor <= STABLE_COR).astype(float)
    classes[cor > 1.2] = 0.0  # diverged runs count as unstable
    gx, gy, frac = stability_map(delay, table_hz, classes, False, True)
    assert frac.shape == (80, 80) and gx[0] >= 0.0005 and gy[-1] <= 200.0
    truth = known_cor(gx[None, :], gy[:, None]) <= STABLE_COR
    agree = np.mean((frac > 0.5) == truth)
    assert agree > 0.95, agree


def test_the_worst_runs_are_the_diverged_then_the_highest_cor(tmp_path):
    spec, table, summary = campaign(tmp_path, GRID)
    status = np.asarray(table.column("status").to_pylist())
    n_div = int(np.sum(status == "diverged"))
    assert 0 < n_div < 10
    worst = worst_runs(table, "cor")
    assert [status[i] for i in worst] == ["diverged"] * n_div + ["ok"] * (10 - n_div)
    cors = [table.column("cor")[i].as_py() for i in worst[n_div:]]
    assert cors == sorted(cors, reverse=True)
    assert max(cors) == pytest.approx(np.nanmax(table.column("cor").to_numpy()))
    _, text = report(tmp_path, spec, table, summary)
    section = text.split("## The worst runs", 1)[1]
    rows = [line for line in section.splitlines() if re.match(r"\| \d+ \|", line)]
    assert len(rows) == 10
    assert [r.split(" | ")[5] for r in rows] == [status[i] for i in worst]
    assert [int(r.split(" | ")[0][2:]) for r in rows] == [
        table.column("run")[i].as_py() for i in worst
    ]
    counts = summary["status"]
    assert f"| all | 144 | {counts['ok']} | {counts['diverged']} |" in text
    assert "First diverged run (run " in text


def test_a_margins_only_spec_maps_the_margins(tmp_path, axes_seen):
    raw = {
        "name": "margins",
        "metrics": ["stable", "phase_margin_deg"],
        "compensators": ["none", "SDMDC"],
        "grid": {"sensor_delay_s": [0.001, 0.005, 0.02], "table_response_hz": [25.0, 100.0]},
    }
    spec = parse_spec(raw)
    rows = [run_one(spec, i) for i in range(spec.n_runs)]  # the linear loop: ~1 ms each
    spec, table, summary = campaign(tmp_path, raw, rows=rows)
    paths, text = report(tmp_path, spec, table, summary)
    captions = figures_with_captions(text)
    assert set(captions) == {"cor_map.png", "cor_cdf.png", "stability_boundary.png"}
    assert captions["cor_map.png"].startswith("*phase margin [deg] over")
    assert (
        "stable here: the linearized loop in contact is stable"
        in (captions["stability_boundary.png"])
    )
    # Without compensation the contact loop gains energy: never stable.
    none = np.asarray(table.column("compensator").to_pylist()) == "none"
    assert not np.any(classify_runs(table, spec.metrics)[none] == 1.0)
    assert ("cor_map.png", "", "phase margin [deg]", "linear", "linear") in axes_seen
    assert "| phase margin [deg] | stable | status | message |" in text


def test_a_spec_measuring_only_stable_gives_a_map_and_says_why_no_cdf(tmp_path):
    raw = {
        "name": "stable_only",
        "metrics": ["stable"],
        "grid": {"sensor_delay_s": [0.001, 0.005], "table_response_hz": [25.0, 100.0]},
    }
    spec = parse_spec(raw)
    spec, table, summary = campaign(tmp_path, raw, rows=[run_one(spec, i) for i in range(4)])
    paths, text = report(tmp_path, spec, table, summary)
    assert [p.name for p in paths][:2] == ["cor_map.png", "stability_boundary.png"]
    assert "No CDF: the campaign measures only whether the loop is stable." in text


def test_a_campaign_whose_runs_all_diverged_is_reported(tmp_path):
    spec, table, summary = campaign(tmp_path, GRID, lambda row, v: ("diverged", "diverged"))
    paths, text = report(tmp_path, spec, table, summary)
    assert [p.name for p in paths][:2] == ["cor_map.png", "stability_boundary.png"]
    assert "No CDF: no run gave a value of CoR [1]." in text
    assert "no run gave a value" in figures_with_captions(text)["cor_map.png"]
    assert "| all | 144 | 0 | 144 |" not in text  # no ok column when no run is ok
    assert "| all | 144 | 144 |" in text


def test_a_campaign_whose_runs_are_all_invalid_is_reported(tmp_path):
    def invalid(row, values):
        return "invalid", "sensor_delay_s: not a whole number of ticks"

    spec, table, summary = campaign(tmp_path, GRID, invalid)
    paths, text = report(tmp_path, spec, table, summary)
    assert [p.name for p in paths] == ["cor_map.png", "report.md", "report.html"]
    assert "No stability boundary: no run finished or diverged." in text
    assert r"First invalid run (run 0): sensor\_delay\_s: not a whole number of ticks" in text


def test_only_text_inputs_swept_gives_no_map_and_says_why(tmp_path):
    raw = {
        "name": "gates",
        "metrics": ["cor"],
        "compensators": ["SDMDC", "none"],
        "grid": {"table_initial_state": ["tracking", "rest"]},
    }
    spec = parse_spec(raw)
    spec, table, summary = campaign(tmp_path, raw, rows=[run_one(spec, i) for i in range(4)])
    assert plane_inputs(spec, table) is None
    paths, text = report(tmp_path, spec, table, summary)
    assert [p.name for p in paths] == ["cor_cdf.png", "report.md", "report.html"]
    assert (
        "No map over two parameters and no stability boundary: the campaign varies fewer "
        "than two numeric inputs." in text
    )


def test_a_one_run_campaign_through_the_diagram_is_reported(tmp_path):
    raw = {"name": "table1", "engine": "diagram", "metrics": ["cor", "peak_force_n"]}
    spec = parse_spec(raw)
    spec, table, summary = campaign(tmp_path, raw, rows=[run_one(spec, 0)])
    paths, text = report(tmp_path, spec, table, summary)
    assert [p.name for p in paths] == ["cor_cdf.png", "report.md", "report.html"]
    # The paper's Table 1 point without compensation: CoR 1.161.
    assert re.search(r"\| 0 \| none \| 1\.161\d \| ok \| - \|", text)
    assert "base parameters: none (the paper Table 1 values)" in text


def test_real_runs_put_the_worst_cor_at_the_longest_delay_and_slowest_table(tmp_path):
    raw = {
        "name": "real",
        "engine": "diagram",
        "grid": {"sensor_delay_s": [0.001, 0.005], "table_response_hz": [25.0, 100.0]},
    }
    spec = parse_spec(raw)
    spec, table, summary = campaign(tmp_path, raw, rows=[run_one(spec, i) for i in range(4)])
    worst = table.take(worst_runs(table, "cor")).to_pylist()
    assert (worst[0]["sensor_delay_s"], worst[0]["table_response_hz"]) == (0.005, 25.0)
    assert all(a["cor"] > b["cor"] > 1.0 for a, b in zip(worst, worst[1:], strict=False))
    paths, text = report(tmp_path, spec, table, summary)
    assert len(figures_with_captions(text)) == 3
    # Every run creates energy: none is stable, and no CoR = 1 line can be drawn.
    assert not np.any(classify_runs(table, spec.metrics) == 1.0)
    assert "black line: CoR" not in figures_with_captions(text)["cor_map.png"]


def test_axis_labels_carry_the_unit():
    assert axis_label("sensor_delay_s") == "sensor delay [s]"
    assert axis_label("cor") == "CoR [1]"
    assert axis_label("initial_velocity_m_per_s") == "initial velocity [m/s]"
    assert axis_label("contact_damping_n_s_per_m") == "contact damping [N s/m]"
    assert axis_label("growth_rate_per_s") == "growth rate [1/s]"
    assert axis_label("table_response_hz", unit=False) == "table response"


def test_a_spec_without_cor_or_margins_maps_its_first_metric(tmp_path):
    def fill(row, values):
        row["peak_force_n"] = 1000.0 + 1e5 * values["sensor_delay_s"]
        row["contact_duration_s"] = 0.5
        return "ok", ""

    raw = dict(GRID, metrics=["peak_force_n", "contact_duration_s"])
    spec, table, summary = campaign(tmp_path, raw, fill)
    paths, text = report(tmp_path, spec, table, summary)
    captions = figures_with_captions(text)
    assert captions["cor_map.png"].startswith("*peak force [N] over table response [Hz]")
    assert "stable here: the run finished" in captions["stability_boundary.png"]
    # No CoR: the worst runs are the largest peak force, the longest delay.
    worst = table.take(worst_runs(table, "peak_force_n")).to_pylist()
    assert {r["sensor_delay_s"] for r in worst} == {0.006}
