"""Figures and report of a campaign (``hybridtable sweep SPEC.toml --report DIR``),
from the results table alone: ``cor_map.png`` (the CoR, or a margin when the
spec has no CoR, over the two swept numeric inputs with the most distinct
values, a panel per compensator: a heat map on a grid, a scatter for Monte Carlo
points), ``cor_cdf.png`` (its CDF per compensator), ``stability_boundary.png``,
``report.md`` and ``report.html``; a figure that cannot be drawn is a sentence
in ``report.md`` saying why. The figures are drawn by
:mod:`hybridtable.reports.sweep_figures`.

A 6-DoF campaign's report is its docking envelope: a map of every metric it
measured (``METRIC_map.png``), the CDF of its energy ratio, the boundary
where the rig stops being energy-honest (``energy_boundary.png``: the energy
ratio above 1 + :data:`~hybridtable.reports.sweep_summary.ENERGY_GAIN_TOLERANCE`)
and where the docking stops capturing (``capture_boundary.png``).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from hybridtable.reports.sweep_figures import (
    MAPPABLE,
    STABLE_COR,
    axis_label,
    cdf_figure,
    cells,
    classify_runs,
    envelope_figures,
    log_axis,
    numbers,
    on_grid,
    plane_figure,
    plane_inputs,
    stability_map,
    texts,
    worst_runs,
)
from hybridtable.reports.sweep_summary import energy_metric, verdict
from hybridtable.sweeps.plan import input_for
from hybridtable.sweeps.runner import STATUSES
from hybridtable.sweeps.spec import SweepSpec

__all__ = ["STABLE_COR", "axis_label", "plane_inputs", "classify_runs", "stability_map"]
__all__ += ["worst_runs", "write_report"]


def _md(text: Any) -> str:
    """User text in Markdown, shown as written."""
    return "".join("\\" + c if c in "\\`*_[]|<>" else c for c in str(text))


def _value(v: Any, name: str = "") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4f}" if name in ("cor", "predicted_cor") else f"{v:.4g}"
    return _md(v)


def _unit(name: str) -> str:
    unit = input_for(name, None).unit
    return f" {unit}" if unit not in ("", "1") else ""


def _values_text(name: str, values) -> str:
    values = list(dict.fromkeys(values))
    if len(values) > 6 and input_for(name, None).kind == "number":
        return f"{min(values):g} to {max(values):g}{_unit(name)}"
    return ", ".join(_value(v) for v in values) + _unit(name)


def _spec_lines(spec: SweepSpec, table: pa.Table) -> list[str]:
    lines = ["## The campaign", "", f"- name: {_md(spec.name)}"]
    lines += [f"- description: {_md(spec.description)}"] * bool(spec.description)
    lines += [f"- runs: {spec.n_runs} in the spec, {table.num_rows} in the file"]
    names = ", ".join(f"`{m}`" for m in spec.metrics)
    engine = spec.engine if spec.loop == "1d" else "the 6-DoF loop's Drake diagram"
    lines += [f"- seed: {spec.seed}; engine: {engine}; metrics: {names}"]
    lines += [f"- model: {_md(spec.model_path)}"] * bool(spec.model_path)
    base = ", ".join(f"`{k}` = {_value(v)}{_unit(k)}" for k, v in spec.base)
    if spec.scenario_path:
        lines += [f"- the 6-DoF docking loop on the scenario {_md(spec.scenario_path)}"]
    defaults = "none (the scenario's)" if spec.scenario_path else "none (the paper Table 1 values)"
    lines.append(f"- base parameters: {base or defaults}")
    lines.append("- swept inputs:" if spec.swept else "- swept inputs: none")
    for k, axis in spec.grid:
        lines.append(f"  - `{k}` (grid, {len(axis)} values): {_values_text(k, axis)}")
    for i, (k, _) in enumerate(spec.points[0]):
        values = [p[i][1] for p in spec.points]
        lines.append(f"  - `{k}` ({len(values)} points): {_values_text(k, values)}")
    for k, dist in spec.draws:
        j = dist.to_json()
        what = ", ".join(f"{a} {_value(b)}" for a, b in j.items() if a != "distribution")
        kind = f"Monte Carlo, {spec.samples} samples"
        lines.append(f"  - `{k}` ({kind}): {j['distribution']} ({what}){_unit(k)}")
    return lines


def _tables(table: pa.Table, spec: SweepSpec, summary: dict, metric: str) -> list[str]:
    """The status counts, the first message of each failure, the worst runs."""
    rank = {s: i for i, s in enumerate(STATUSES)}
    statuses = sorted(summary["status"], key=lambda s: rank.get(s, len(rank)))
    lines = ["## Status of the runs", "", "| compensator | runs | " + " | ".join(statuses) + " |"]
    lines.append("| --- | ---: |" + " ---: |" * len(statuses))
    for comp, e in summary["compensators"].items():
        counts = " | ".join(str(e["status"].get(s, 0)) for s in statuses)
        lines.append(f"| {_md(comp)} | {e['runs']} | {counts} |")
    total = " | ".join(str(summary["status"][s]) for s in statuses)
    lines.append(f"| all | {summary['written']} | {total} |")
    status, message, runs = texts(table, "status"), texts(table, "message"), texts(table, "run")
    for s in statuses:
        hits = np.flatnonzero(status == s)
        if s != "ok" and hits.size:
            lines += ["", f"First {s} run (run {runs[hits[0]]}): {_md(message[hits[0]])}"]
    inputs = [n for n in spec.swept if n != "compensator"]
    shown = [metric] + (["stable"] if "stable" in spec.metrics and metric != "stable" else [])
    rows = table.take(worst_runs(table, metric)).to_pylist()
    head = ["run", "compensator", *(axis_label(n) for n in inputs + shown), "status", "message"]
    head = [h.replace(" (1: yes, 0: no) [1]", "") for h in head]
    lines += ["", "## The worst runs", "", f"The {len(rows)} worst of {table.num_rows} runs: "]
    lines[-1] += f"diverged first, then by {axis_label(metric, False)}, the worst first.\n"
    lines += ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in rows:
        cells = [str(r["run"]), _md(r["compensator"])]
        cells += [_value(r[n], n) for n in inputs + shown]
        cells += [_md(r["status"]), _md(r["message"]) or "-"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def write_report(table: pa.Table, spec: SweepSpec, summary: dict, folder: Path) -> list[Path]:
    """Write the figures, ``report.md`` and ``report.html`` of a campaign.

    Parameters
    ----------
    table : pyarrow.Table
        The campaign's rows (:func:`hybridtable.sweeps.store.read_results`).
    spec : SweepSpec
    summary : dict
        :func:`hybridtable.reports.sweep_summary.summarize` of ``table``.
    folder : Path
        An existing folder (the command staged it and applied the overwrite policy).

    Returns
    -------
    list of Path
        The figures, ``report.md`` and ``report.html``.
    """
    import matplotlib

    matplotlib.use("Agg")
    from hybridtable.reports.html import write_html_report

    folder = Path(folder)
    metric = next((m for m in MAPPABLE if m in spec.metrics), spec.metrics[0])
    d: dict[str, Any] = {"metric": metric, "metrics": spec.metrics, "v": numbers(table, metric)}
    d["loop"] = spec.loop
    d.update(status=texts(table, "status"), comp=texts(table, "compensator"))
    d["comps"] = list(dict.fromkeys(d["comp"].tolist()))
    written: list[Path] = []
    body: list[str] = ["## Figures", ""]

    def figure(name: str, title: str, draw, *args, look: dict | None = None) -> None:
        caption = draw(folder / name, d if look is None else {**d, **look}, *args)
        written.append(folder / name)
        body.extend([f"![{title}]({name})", f"*{caption}*", ""])

    six = spec.loop == "six_dof"  # the docking envelope (the module docstring)
    files = (f"{metric}_map.png", f"{metric}_cdf.png", "energy_boundary.png")
    files = files if six else ("cor_map.png", "cor_cdf.png", "stability_boundary.png")
    honest = {"word": "energy-honest", "negation": "not energy-honest", "title": "Energy-honesty"}

    plane = plane_inputs(spec, table) if table.num_rows else None
    if plane is not None:
        x, y = (numbers(table, n) for n in plane)
        shown = np.isfinite(x) & np.isfinite(y)
        plane = plane if shown.any() else None
    if plane is None:
        why = "no run has finite values of both" if table.num_rows else "no run is in the file"
        if plane_inputs(spec, table) is None:
            why = "the campaign varies fewer than two numeric inputs"
        boundary = "energy-honesty or capture boundary" if six else "stability boundary"
        body += [f"No map over two parameters and no {boundary}: {why}.", ""]
    else:
        d.update(xname=plane[0], yname=plane[1], x=x, y=y, hidden=int(np.sum(~shown)))
        d.update(
            log_x=log_axis(x),
            log_y=log_axis(y),
            grid=on_grid(*cells(x, y, x * 0)[:3])[2] is not None,
        )
        d["class"] = classify_runs(table, spec.metrics, spec.loop)
        title = "{} over {} and {}".format(*(axis_label(n, False) for n in (metric, *plane)))
        figure(files[0], title, plane_figure)
    if metric == "stable":
        body += ["No CDF: the campaign measures only whether the loop is stable.", ""]
    elif not np.isfinite(d["v"][d["status"] == "ok"]).any():
        body += [f"No CDF: no run gave a value of {axis_label(metric)}.", ""]
    else:
        figure(files[1], f"CDF of {axis_label(metric, False)}", cdf_figure)
    judged = not six or energy_metric(spec.metrics, spec.loop) is not None
    if plane is not None and np.isfinite(d["class"]).any() and judged:
        title = "Energy-honesty boundary" if six else "Stability boundary"
        figure(files[2], title, plane_figure, True, look=honest if six else None)
    elif plane is not None and not judged:
        body += [
            "No energy-honesty boundary: the campaign measures neither energy_excess "
            "nor energy_ratio.",
            "",
        ]
    elif plane is not None:
        boundary = "energy-honesty" if six else "stability"
        body += [f"No {boundary} boundary: no run finished or diverged.", ""]
    if six and plane is not None:
        said = envelope_figures(table, spec, metric, figure)
        body += [line for s in said for line in (s, "")]

    lines = [f"# Sweep {_md(spec.name)}", "", f"**{_md(verdict(spec.name, summary))}.**", ""]
    lines += _spec_lines(spec, table) + [""] + body + _tables(table, spec, summary, metric)
    report = folder / "report.md"
    report.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return [*written, report, Path(write_html_report(report))]
