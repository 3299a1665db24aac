"""The margins figures' legends name only the curves they draw."""

from __future__ import annotations

import dataclasses

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from hybridtable.reports.margin_plots import plot_critical  # noqa: E402
from hybridtable.studies.paper import table1_params  # noqa: E402
from hybridtable.sweeps.margins_grid import sweep_margins  # noqa: E402


@pytest.fixture(scope="module")
def damped_grid():
    base = table1_params("none").with_contact_damping_ratio(0.05)
    return sweep_margins(base, [0.002, 0.006, 0.01], [20.0, 40.0, 80.0], ("none", "SDMDC"))


def _legend(monkeypatch, result, path) -> list[str]:
    from matplotlib.figure import Figure

    seen: list[str] = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        for ax in self.axes:
            legend = ax.get_legend()
            if legend is not None:
                seen.extend(t.get_text() for t in legend.get_texts())
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    plot_critical(result, path)
    return seen


def test_every_curve_drawn_is_in_the_legend(damped_grid, monkeypatch, tmp_path):
    labels = _legend(monkeypatch, damped_grid, tmp_path / "a.png")
    assert {"none", "SDMDC", "stability boundary"} <= set(labels)


def test_a_kind_of_curve_with_nothing_to_draw_is_not_in_the_legend(
    damped_grid, monkeypatch, tmp_path
):
    """No critical delay or table frequency known (NaN) for any compensator:
    no solid curve is drawn, so the legend promises no stability boundary; the
    CoR-limit curves still are, and are named."""
    sweeps = {
        c: dataclasses.replace(
            cs,
            critical_delay_s=np.full_like(cs.critical_delay_s, np.nan, dtype=float),
            critical_table_hz=np.full_like(cs.critical_table_hz, np.nan, dtype=float),
        )
        for c, cs in damped_grid.compensators.items()
    }
    result = dataclasses.replace(damped_grid, compensators=sweeps)
    labels = _legend(monkeypatch, result, tmp_path / "b.png")
    assert "stability boundary" not in labels
    assert {"none", "SDMDC", "CoR = 1.01"} <= set(labels)
