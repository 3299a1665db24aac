"""The report of ``compare --report DIR`` on 6-DoF runs: ``report.md`` and,
per run, the twelve compared components measured against the replay (and the
replay with the fitted effects, with ``--add``), and their residuals in noise
levels, the contact shaded (:mod:`hybridtable.six_dof.compare6`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridtable.reports.compare_figures import figure_stem  # noqa: E402
from hybridtable.six_dof.compare6 import (  # noqa: E402
    COMPONENTS,
    Comparison6,
    measured_block,
)

__all__ = ["write_report6"]

#: Display scale of each unit: (factor, unit shown).
_SHOWN = {"N": (1.0, "N"), "N m": (1.0, "N m"), "m": (1e3, "mm"), "rad": (1e3, "mrad")}


def _shade(ax, c: Comparison6) -> None:
    start, end = c.contact_s
    if np.isfinite(start):
        ax.axvspan(start, end, color="0.9", zorder=0)


def _panels(title: str):
    fig, axes = plt.subplots(4, 3, figsize=(13, 10), sharex=True)
    fig.suptitle(title)
    return fig, axes.T.ravel()  # columns: force, moment, position, attitude in rows of 3


def _save(fig, axes, path: Path) -> Path:
    """Label the bottom row's time axes, the legend, and write the figure."""
    for ax in axes[3::4]:
        ax.set_xlabel("time [s]")
    axes[0].legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_components(c: Comparison6, path: Path, fitted: Comparison6 | None = None) -> Path:
    """The twelve components over time: measured, replay, replay with the fit."""
    run = c.run
    t = run.time_s
    fig, axes = _panels(f"{c.run_id}: measured and replayed components (contact shaded)")
    for ax, (name, block, j, unit) in zip(axes, COMPONENTS, strict=True):
        k, shown = _SHOWN[unit]
        _shade(ax, c)
        ax.plot(t, k * measured_block(run, block)[:, j], color="0.4", lw=0.8, label="measured")
        ax.plot(t, k * c.replayed[block][: run.n, j], color="C0", lw=1.0, label="replay")
        if fitted is not None:
            ax.plot(t, k * fitted.replayed[block][: run.n, j], "--", color="C1", lw=1.0,
                    label="replay with the fit")  # fmt: skip
        ax.set_ylabel(f"{name} [{shown}]")
    return _save(fig, axes, path)


def plot_residuals(c: Comparison6, path: Path, fitted: Comparison6 | None = None) -> Path:
    """Each component's replay residual in its noise levels (+-3 marked)."""
    run = c.run
    t = run.time_s
    fig, axes = _panels(f"{c.run_id}: replay residuals in noise levels (contact shaded)")
    for ax, (name, block, j, _), error in zip(axes, COMPONENTS, c.components, strict=True):
        sigma = error.noise
        measured = measured_block(run, block)[:, j]
        _shade(ax, c)
        ax.axhline(3.0, color="0.6", lw=0.6, ls=":")
        ax.axhline(-3.0, color="0.6", lw=0.6, ls=":")
        ax.plot(t, (measured - c.replayed[block][: run.n, j]) / sigma, color="C0", lw=0.8,
                label="nominal")  # fmt: skip
        if fitted is not None:
            r = (measured - fitted.replayed[block][: run.n, j]) / sigma
            ax.plot(t, r, color="C1", lw=0.8, label="with the fit")
        ax.set_ylabel(f"{name} [noise levels]")
    return _save(fig, axes, path)


def write_report6(
    comparisons: Sequence[Comparison6],
    folder: str | Path,
    fitted: Sequence[Comparison6] | None = None,
    fit_text: str = "",
    preface: Sequence[str] = (),
    title: str = "A six-axis rig's model against its recorded runs",
) -> list[Path]:
    """Write ``report.md`` and two figures a run into ``folder``; returns the
    files written. ``preface``: markdown lines after the title (a diagnosis's
    verdict and rounds, the audit of the rig computer)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    md = [
        f"# {title}",
        "",
        *preface,
        *(f"**{c.verdict()}**" for c in comparisons),
        "",
        "Replay: the recorded commands through the model's table, contact and F/T sensor; "
        "closed loop: the scenario's whole loop, without the F/T noise. Errors are RMS over "
        "the record in each component's noise level (its spread over the ticks out of "
        "contact, as the 1-D comparison takes it). Definitions: "
        "`docs/run6-format.md`.",
        "",
    ]
    if fitted is not None:
        md += ["## With the fitted effects", "", fit_text, ""]
        md += [f"**{c.verdict()}**" for c in fitted] + [""]
    for i, c in enumerate(comparisons):
        after = fitted[i] if fitted is not None else None
        stem = figure_stem(i, c.run_id)
        comp = plot_components(c, folder / f"{stem}_components.png", after)
        res = plot_residuals(c, folder / f"{stem}_residuals.png", after)
        written += [comp, res]
        header = "| component | noise | replay | closed loop |" + (" with the fit |" * bool(after))
        md += [
            f"## {c.run_id}",
            "",
            f"`{c.run.csv_path}`, {c.n_ticks} ticks; contact {c.contact_s[0]:.4g} to "
            f"{c.contact_s[1]:.4g} s; CoR along the normal {c.cor_measured:.5f} measured, "
            f"{c.cor_model:.5f} modelled; energy ratio {c.energy_ratio_measured:.5f} measured, "
            f"{c.energy_ratio_model:.5f} modelled.",
            "",
            header,
            "| --- | --- | --- | --- |" + (" --- |" * bool(after)),
        ]
        for k, (e, loop) in enumerate(zip(c.components, c.closed_loop, strict=True)):
            row = f"| {e.name} | {e.noise:.4g} {e.unit} | {e.error_sigma:.3g} | {loop.error_sigma:.3g} |"
            if after is not None:
                row += f" {after.components[k].error_sigma:.3g} |"
            md.append(row)
        md += [
            "",
            f"![the twelve components, measured and replayed]({comp.name})",
            "",
            "*The measured components (grey) and the replay (blue"
            + (", dashed orange: with the fitted effects" if after else "")
            + "); forces in N, moments in N m, positions in mm, attitude (rotation vector) in "
            "mrad, against time in s; the contact, as the sensor read it, shaded.*",
            "",
            f"![the replay's residuals in noise levels]({res.name})",
            "",
            "*Each component's replay residual (measured minus replay) in its noise levels, "
            "against time in s; dotted: +-3.*",
            "",
        ]
    report = folder / "report.md"
    report.write_text("\n".join(md) + "\n", encoding="utf-8")
    return [report, *written]
