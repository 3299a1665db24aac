"""The text and figures of ``hybridtable compare`` (hybridtable.reports.compare,
.compare_figures):
run ids whole with the columns widening to them, the verdict sentence, the
whiteness in words, figures whose every axis has a unit and whose tick labels
do not overlap."""

from __future__ import annotations

import itertools
import json
import re
import shutil

import pytest

import hybridtable.reports.compare as report
import hybridtable.reports.compare_figures as figures
from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.run_reader import read_run
from tests.examples import EXAMPLES
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record, write_run

LONG_ID = "nominal-run2-recorded-on-rig-B-2024-6-12"  # 40 characters


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """run2 of the examples under a 40-character id, and a damped rig's run."""
    folder = tmp_path_factory.mktemp("runs")
    shutil.copy(EXAMPLES / "run2.csv", folder / "long.csv")
    info = json.loads((EXAMPLES / "run2.json").read_text())
    info["run_id"] = LONG_ID
    (folder / "long.json").write_text(json.dumps(info))
    damped = dict(NOMINAL, run_id="damped")
    contact = damped_spring(NOMINAL["contact_stiffness_n_per_m"], 600.0)
    write_run(folder, "damped", damped, simulate_record(damped, contact))
    return {
        "long": compare_run(read_run(folder / "long.csv")),
        "damped": compare_run(read_run(folder / "damped.csv")),
    }


def test_run_ids_whole_and_columns_aligned(runs):
    assert len(LONG_ID) == 40
    long, damped = runs["long"], runs["damped"]
    lines = report.format_table([damped, long]).splitlines()
    head, rows = lines[0], lines[2:]
    assert rows[1].startswith(LONG_ID + " ") and rows[0].startswith("damped ")
    for row in rows:  # the compensator under "comp", the ratio under its header
        assert row.index("SDMDC") == head.index("comp")
        assert len(row.split()[0]) <= 40
    fall = report.format_error_fall([damped, long], [damped, long], "nothing").splitlines()
    assert fall[-1].startswith(LONG_ID + " ")
    assert fall[-2].index("->") == fall[-1].index("->")
    whiteness = report.format_whiteness([damped, long]).splitlines()
    assert any(line.startswith(f"  {LONG_ID}  force:") for line in whiteness)


def test_verdict_sentences(runs):
    long, damped = runs["long"], runs["damped"]
    ok = report.verdict([long])
    ratio_f, ratio_p = long.error_to_noise("f_mea_n"), long.error_to_noise("p_act_m")
    fit_f = long.replay_errors["f_mea_n"].fit_percent
    shaped = {
        ch: not (long.whiteness[ch].auto_white and long.whiteness[ch].cross_white)
        for ch in ("f_mea_n", "p_act_m")
    }
    assert ok == (
        f"The model matches the run within the noise (force error {ratio_f:.2f}x, position "
        f"{ratio_p:.2f}x the noise; fit {fit_f:.1f} % force, "
        f"{report._fit(long.replay_errors['p_act_m'].fit_percent)} % position)"
        + "".join(
            f"; the {word} residual still has structure in the run (a systematic effect too "
            f"small to matter: error at most {long.error_to_noise(ch):.2f}x the noise)"
            for ch, word in (("f_mea_n", "force"), ("p_act_m", "position"))
            if shaped[ch]
        )
    )
    missed = report.verdict([long, damped])
    assert missed.startswith("The model misses something in 1 of 2 runs: force error ")
    assert f"{damped.error_to_noise('f_mea_n'):.2f}x the noise, worst in compression" in missed
    assert report.verdict([damped, damped]).startswith("The model misses something in both runs")
    assert report.verdict([long], "The model with contact_damping").startswith(
        "The model with contact_damping matches"
    )


def test_fit_never_prints_a_perfect_100_for_an_imperfect_fit():
    assert report._fit(99.991) == "99.99"
    assert report._fit(100.0) == "100.0"
    assert report._fit(97.14) == "97.1"
    assert report._fit(float("nan")) == "n/a"


def test_whiteness_in_words(runs):
    damped = runs["damped"]
    text = report.whiteness_sentence(damped, "f_mea_n")
    assert text.startswith("the residual is not noise")
    assert "lie outside the 99 % band" in text and "try hybridtable diagnose" in text
    assert report.whiteness_sentence(damped, "p_act_m").startswith(
        "the residual is white: what is left is sensor noise"
    )


def _overlap(a, b, gap_px: float = 3.0) -> bool:
    """True if two boxes overlap or lie closer than ``gap_px`` (labels that
    touch read as one word)."""
    g = gap_px
    return a.x0 < b.x1 + g and b.x0 < a.x1 + g and a.y0 < b.y1 + g and b.y0 < a.y1 + g


@pytest.mark.parametrize(
    "plot", ["plot_overlay", "plot_residuals", "plot_correlation", "plot_force_deflection"]
)
def test_figures_units_on_every_axis_and_no_overlapping_ticks(runs, plot, tmp_path, monkeypatch):
    axes = []  # (axis label, tick texts, tick boxes) of every axis, as drawn
    save = figures._save

    def keep(fig, path):
        fig.tight_layout()
        renderer = fig.canvas.get_renderer()
        fig.canvas.draw()
        for ax in fig.axes:
            for axis, label in ((ax.xaxis, ax.get_xlabel()), (ax.yaxis, ax.get_ylabel())):
                ticks = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
                boxes = [t.get_window_extent(renderer) for t in ticks]
                axes.append((label, [t.get_text() for t in ticks], boxes))
        return save(fig, path)

    monkeypatch.setattr(figures, "_save", keep)
    getattr(figures, plot)(runs["long"], tmp_path / "f.png")
    assert axes
    unit = re.compile(r"\[[^\]]+\]$")
    number = re.compile(r"^[\u2212+-]?[0-9.]+$")  # matplotlib's minus is U+2212
    for label, texts, boxes in axes:
        for a, b in itertools.combinations(boxes, 2):
            assert not _overlap(a, b), (plot, texts)
        # A numeric axis carries its unit; a shared one shows its label once,
        # the phase names label themselves.
        if texts and all(number.match(t) for t in texts):
            assert unit.search(label), (plot, label)
    assert (tmp_path / "f.png").stat().st_size > 1000
