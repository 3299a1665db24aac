"""Figures and report of a campaign (``hybridtable sweep SPEC.toml --report DIR``),
from the results table alone: ``cor_map.png`` (the CoR, or a margin when the
spec has no CoR, over the two swept numeric inputs with the most distinct
values, a panel per compensator: a heat map on a grid, a scatter for Monte Carlo
points), ``cor_cdf.png`` (its CDF per compensator), ``stability_boundary.png``,
``report.md`` and ``report.html``; a figure that cannot be drawn is a sentence
in ``report.md`` saying why.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from hybridtable.reports.colour_scale import colour_scale, crosses, ticks_both_sides
from hybridtable.reports.figure_text import literal
from hybridtable.reports.sweep_summary import COR_GAIN_TOLERANCE, verdict
from hybridtable.sweeps.inputs import input_of
from hybridtable.sweeps.metrics import METRICS
from hybridtable.sweeps.runner import STATUSES
from hybridtable.sweeps.spec import SweepSpec

__all__ = ["STABLE_COR", "axis_label", "plane_inputs", "classify_runs", "stability_map"]
__all__ += ["worst_runs", "write_report"]

#: A run whose CoR is at most this created no energy (the paper's four digits).
STABLE_COR = 1.0 + COR_GAIN_TOLERANCE

#: The metrics a map shows first, in this order (else the spec's first), with the
#: level that separates gain from loss (a contour; None: none), higher-is-worse.
_MAPPABLE: dict[str, tuple[float | None, bool]] = {
    **dict.fromkeys(("cor", "predicted_cor", "energy_ratio"), (1.0, True)),
    **{"phase_margin_deg": (0.0, False), "growth_rate_per_s": (0.0, True)},
    **{"damping_ratio": (0.0, False), "critical_sensor_delay_s": (None, False)},
    **dict.fromkeys(("energy_gain_j", "energy_created"), (0.0, True)),
    "stable": (0.5, False),
}
#: Every metric's level (None) and direction (higher is worse), those above apart.
_LOOK = {**dict.fromkeys(METRICS, (None, True)), **_MAPPABLE}
#: How a finished run is judged stable: the first of these metrics the spec has.
_RULES = (
    ("stable", lambda v: v > 0.5, "the linearized loop in contact is stable (the stable margin)"),
    ("cor", lambda v: v <= STABLE_COR, f"CoR <= {STABLE_COR:g} (the loop created no energy)"),
    ("predicted_cor", lambda v: v <= STABLE_COR, f"the predicted CoR <= {STABLE_COR:g}"),
    ("growth_rate_per_s", lambda v: v <= 0.0, "no pole of the loop grows (growth rate <= 0 1/s)"),
)
_WORDS = {"cor": "CoR", "predicted_cor": "predicted CoR", "growth_rate_per_s": "growth rate"}
_WORDS["stable"] = "stable (1: yes, 0: no)"


def axis_label(name: str, unit: bool = True) -> str:
    """An input or metric in words, with its unit unless not ``unit``
    (``sensor_delay_s`` -> ``sensor delay [s]``, ``cor`` -> ``CoR [1]``)."""
    si = input_of(name).unit if input_of(name) is not None else METRICS[name].unit
    words = _WORDS.get(name)
    if words is None:
        suffix = "_" + si.lower().replace("/", "_per_").replace(" ", "_")
        words = (name[: -len(suffix)] if si and name.endswith(suffix) else name).replace("_", " ")
    return f"{words} [{si or '1'}]" if unit else words


def _numbers(table: pa.Table, name: str) -> np.ndarray:
    """A column as floats (NaN: missing; a flag as 1.0 / 0.0)."""
    return np.asarray(table.column(name).cast(pa.float64()).to_numpy(), dtype=float)


def _texts(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_pylist(), dtype=object)


def plane_inputs(spec: SweepSpec, table: pa.Table) -> tuple[str, str] | None:
    """The two swept numeric inputs with the most distinct values in ``table``
    (ties: the spec's order), x first; None if fewer than two are swept."""
    names = [n for n in spec.swept if n != "compensator" and input_of(n).kind == "number"]
    if len(names) < 2:
        return None
    return tuple(sorted(names, key=lambda n: -np.unique(_numbers(table, n)).size)[:2])


def _cells(x, y, values, reduce=np.median):
    """The distinct finite ``(x, y)`` pairs, ``reduce`` of the finite ``values``
    at each (NaN: none) and their count."""
    keep = np.isfinite(x) & np.isfinite(y)
    pairs, inverse = np.unique(np.column_stack([x[keep], y[keep]]), axis=0, return_inverse=True)
    out, count = np.full(len(pairs), np.nan), np.zeros(len(pairs), dtype=int)
    good = np.isfinite(values[keep])
    order = np.argsort(inverse.ravel()[good], kind="stable")
    keys, vals = inverse.ravel()[good][order], values[keep][good][order]
    if keys.size:
        starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
        ends = np.r_[starts[1:], keys.size]
        count[keys[starts]] = ends - starts
        for s, e in zip(starts, ends, strict=True):
            out[keys[s]] = vals[s] if e - s == 1 else reduce(vals[s:e])
    return pairs[:, 0], pairs[:, 1], out, count


def _on_grid(px, py, values):
    """Values at pairs ``(px, py)`` over the distinct x and y (None: not a grid,
    more than 50 values on an axis or fewer than half the combinations present)."""
    gx, gy = np.unique(px), np.unique(py)
    if not 0 < gx.size <= 50 or gy.size > 50 or px.size < 0.5 * gx.size * gy.size:
        return gx, gy, None
    z = np.full((gy.size, gx.size), np.nan)
    z[np.searchsorted(gy, py), np.searchsorted(gx, px)] = values
    return gx, gy, z


def classify_runs(table: pa.Table, metrics: tuple[str, ...]) -> np.ndarray:
    """Per run 1.0 (stable), 0.0 (not stable, or diverged) or NaN (failed,
    invalid, error, no value). Stable: ``stable`` true when the spec measures
    that margin, else CoR <= :data:`STABLE_COR` (or the predicted CoR, the
    energy ratio, the growth rate), else: did not diverge."""
    status = _texts(table, "status")
    name, rule, _ = next((r for r in _RULES if r[0] in metrics), ("", None, ""))
    v = _numbers(table, name) if name else np.zeros(table.num_rows)
    out = np.where((status == "ok") & np.isfinite(v), rule(v) if rule else True, np.nan)
    out[status == "diverged"] = 0.0
    return out


def _log_axis(values) -> bool:
    v = values[np.isfinite(values)]
    return bool(v.size) and v.min() > 0.0 and v.max() / v.min() > 10.0


def _to(v, log, back=False):
    """``v`` in decades on a log axis (``back``: from decades)."""
    return (10.0**v if back else np.log10(v)) if log else np.asarray(v, dtype=float)


def stability_map(x, y, classes, log_x=False, log_y=False, size=80):
    """The fraction [1] of stable runs (``classes``, :func:`classify_runs`)
    over the plane: per cell on a grid, else the mean class of the nearest
    runs (7, or a fifth of fewer than 35; coordinates scaled to their range, in
    decades on a log axis; at most 3000 runs) on a ``size`` x ``size`` mesh.

    Returns
    -------
    gx, gy : ndarray
        The cells' or the mesh's x and y.
    fraction : ndarray, shape (len(gy), len(gx))
        NaN where no classified run is.
    """
    x, y, c = (np.asarray(a, dtype=float) for a in (x, y, classes))
    gx, gy, frac = _on_grid(*_cells(x, y, c, reduce=np.mean)[:3])
    if frac is not None:
        return gx, gy, frac
    keep = np.isfinite(x) & np.isfinite(y) & np.isfinite(c) & (x > 0 if log_x else True)
    keep &= y > 0 if log_y else True
    tx, ty, c = _to(x[keep], log_x), _to(y[keep], log_y), c[keep]
    if tx.size > 3000:
        pick = np.random.default_rng(0).choice(tx.size, 3000, replace=False)
        tx, ty, c = tx[pick], ty[pick], c[pick]
    ends = [(a.min(), a.max()) if a.size else (0.0, 1.0) for a in (tx, ty)]
    spans = [hi - lo if hi > lo else 1.0 for lo, hi in ends]
    mx, my = (np.linspace(lo, hi, size) for lo, hi in ends)
    frac = np.full(size * size, np.nan)
    if c.size:
        k = min(7, max(1, c.size // 5))
        train = np.column_stack([tx / spans[0], ty / spans[1]])
        qx, qy = np.meshgrid(mx / spans[0], my / spans[1])
        query = np.column_stack([qx.ravel(), qy.ravel()])
        for s in range(0, len(query), 500):
            dist = ((query[s : s + 500, None, :] - train[None, :, :]) ** 2).sum(axis=2)
            frac[s : s + 500] = c[np.argpartition(dist, k - 1, axis=1)[:, :k]].mean(axis=1)
    return _to(mx, log_x, True), _to(my, log_y, True), frac.reshape(size, size)


def worst_runs(table: pa.Table, metric: str, n: int = 10) -> list[int]:
    """Row indices of the ``n`` worst runs: diverged first, then the finished
    ones from the worst ``metric`` (the highest CoR), then the other statuses."""
    status = _texts(table, "status")
    v = _numbers(table, metric)
    score = np.where(np.isfinite(v), v if _LOOK[metric][1] else -v, -np.inf)
    group = np.where(status == "diverged", 0, np.where(status == "ok", 1, 2))
    return [int(i) for i in np.lexsort((np.arange(len(v)), -score, group))[:n]]


# -- figures -------------------------------------------------------------------
def _edges(centres, log):
    """Cell edges around sorted ``centres``: halfway between (in decades on a
    log axis), not below 0 on a linear axis of values >= 0."""
    v = _to(centres, log)
    one = np.array([0.1 if log else (0.1 * abs(v[0]) or 0.5)])
    half = (v[1:] - v[:-1]) / 2 if v.size > 1 else one
    first = v[0] - half[0] if log or v[0] < 0 else max(v[0] - half[0], 0.0)
    return _to(np.r_[first, v[:-1] + half, v[-1] + half[-1]], log, True)


def _panels(d, plt):
    """A figure with a panel per compensator (up to three a row), axes set."""
    n = len(d["comps"])
    cols, rows = min(n, 3), math.ceil(n / 3)
    size = (4.3 * cols + 1.2, 3.7 * rows)
    fig, axes = plt.subplots(rows, cols, figsize=size, squeeze=False, layout="constrained")
    flat = list(axes.ravel())
    for ax in flat[n:]:
        fig.delaxes(ax)
    from matplotlib.ticker import NullFormatter

    for ax, comp in zip(flat, d["comps"], strict=False):
        ax.set(xscale="log" if d["log_x"] else "linear", yscale="log" if d["log_y"] else "linear")
        for axis, log in ((ax.xaxis, d["log_x"]), (ax.yaxis, d["log_y"])):
            if log:  # decades only: the minor labels overlap
                axis.set_minor_formatter(NullFormatter())
        ax.set(xlabel=axis_label(d["xname"]), ylabel=axis_label(d["yname"]))
        ax.set_title(literal(comp), fontsize=10)
    return fig, flat[:n]


def _plane_figure(path, d, stability: bool = False) -> str:
    """The metric (or the fraction of stable runs) over the plane; returns the caption."""
    import matplotlib.pyplot as plt

    metric, level = d["metric"], 0.5 if stability else _LOOK[d["metric"]][0]
    ok = d["status"] == "ok"
    finite = d["v"][ok & np.isfinite(d["v"])]
    norm, cmap = None, ""
    if stability or finite.size:
        norm, cmap = (
            colour_scale(finite, fraction=True)
            if stability
            else colour_scale(finite, *_LOOK[metric])
        )
    fig, axes = _panels(d, plt)
    drawn, most, contour = None, 0, False
    for ax, comp in zip(axes, d["comps"], strict=True):
        m = d["comp"] == comp
        x, y, status = d["x"][m], d["y"][m], d["status"][m]
        if stability:
            c = d["class"][m]
            gx, gy, z = stability_map(x, y, c, d["log_x"], d["log_y"])
            for cls, marker, colour in ((1.0, "o", "darkgreen"), (0.0, "^", "darkred")):
                s = (c == cls) & (status == "ok")
                ax.scatter(x[s], y[s], marker=marker, s=12, facecolors="none", edgecolors=colour)
        else:
            vals = np.where(ok[m], d["v"][m], np.nan)
            px, py, med, n = _cells(x, y, vals)
            gx, gy, z = _on_grid(px, py, med) if d["grid"] and finite.size else (px, py, None)
            most = max(most, int(n.max(initial=0)))
            for xi, yi, ni in zip(px, py, n, strict=True):
                if d["grid"] and ni > 1 and z is not None and z.size <= 144:
                    ax.text(xi, yi, f"{ni}", ha="center", va="center", fontsize=6)
            s = np.isfinite(vals) & (not d["grid"])
            if s.any():
                drawn = ax.scatter(x[s], y[s], c=vals[s], s=10, norm=norm, cmap=cmap)
            # Scattered runs get no contour: through points that differ in the
            # inputs not drawn, it traces noise (the stability figure draws
            # the boundary with a classifier).
        if z is not None and np.isfinite(z).any():
            ex, ey = (_edges(gx, d["log_x"]), _edges(gy, d["log_y"])) if d["grid"] else (gx, gy)
            z, look = np.ma.masked_invalid(z), {"alpha": 0.6 if stability else None, "zorder": 0}
            look["shading"] = "flat" if d["grid"] else "nearest"
            drawn = ax.pcolormesh(ex, ey, z, norm=norm, cmap=cmap, **look)
            if min(z.shape) > 1 and crosses(level, z.filled(np.nan)):
                ax.contour(gx, gy, z, levels=[level], colors="k")
                contour = True
        s = status == "diverged"
        ax.scatter(x[s], y[s], marker="x", color="k", s=30, zorder=3)
    label = "fraction of runs stable [1]" if stability else axis_label(metric)
    if drawn is not None:
        bar = fig.colorbar(drawn, ax=axes, label=label, shrink=0.9)
        ticks_both_sides(bar, norm)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    plane = f"over {axis_label(d['xname'])} and {axis_label(d['yname'])}, one panel per compensator"
    if stability:
        rule = next((w for n, _, w in _RULES if n in d["metrics"]), "the run finished")
        how = "of its runs" if d["grid"] else "of the nearest runs (up to 7, a classifier)"
        return (
            f"Stability {plane}; stable here: {rule}, unstable: not, or diverged; colour: the "
            f"fraction {how} stable [1] (green: stable, red: not); black line: the boundary (half "
            "stable); circles: stable runs, triangles: finished runs that are not, black crosses: "
            "diverged runs."
        )
    how = "each run a dot coloured by its value"
    if d["grid"]:
        how = "each cell the median over the other inputs and samples"
        how += f" (numbers: the runs of a cell, up to {most})" if most > 1 else ""
    parts = [f"{axis_label(metric)} {plane}; {how}; black crosses: diverged runs"]
    parts.append(f"black line: {axis_label(metric, False)} = {level:g}" if contour else "")
    parts.append("" if finite.size else "no run gave a value")
    parts.append(f"not drawn: {d['hidden']} runs at an infinite value" if d["hidden"] else "")
    return "; ".join(p for p in parts if p) + "."


def _cdf_figure(path, d) -> str:
    import matplotlib.pyplot as plt

    metric, level = d["metric"], _LOOK[d["metric"]][0]
    ok = d["status"] == "ok"
    finite = d["v"][ok & np.isfinite(d["v"])]
    lo, hi, log = float(finite.min()), float(finite.max()), _log_axis(finite)
    right = hi * 1.5 if log else hi + 0.05 * ((hi - lo) or abs(hi) or 1.0)
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    for i, comp in enumerate(d["comps"]):
        m = d["comp"] == comp
        v = np.sort(d["v"][m & ok & np.isfinite(d["v"])])
        n_div = int(np.sum(m & (d["status"] == "diverged")))
        if not v.size + n_div:
            continue
        ys = np.arange(1, v.size + 1) / (v.size + n_div)
        tail = f", {n_div} diverged at the right end" if n_div else ""
        label = f"{comp} ({v.size} run{'s' * (v.size != 1)}{tail})"
        xs, ys = (np.r_[v, right], np.r_[ys, 1.0]) if n_div else (v, ys)
        style = {"ls": ("-", "--", "-.", ":")[i % 4], "label": literal(label)}
        ax.step(np.r_[xs[0], xs], np.r_[0.0, ys], where="post", **style)
    if level is not None:
        ax.axvline(level, color="0.3", lw=0.9, ls="--")
    ax.set(xscale="log" if log else "linear", ylim=(0.0, 1.02), xlabel=axis_label(metric))
    ax.set(ylabel="fraction of runs [1]", title="Empirical CDF per compensator")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    others = int(np.sum(~ok & (d["status"] != "diverged")))
    text = (
        f"Empirical CDF of {axis_label(metric)} per compensator (fraction of its finished and "
        "diverged runs [1]); diverged runs counted at the right end, their count in the legend"
    )
    text += f"; dashed: {level:g}" if level is not None else ""
    text += f"; {others} runs that failed or were invalid are not counted" if others else ""
    return text + "."


# -- report.md -----------------------------------------------------------------
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
    unit = input_of(name).unit
    return f" {unit}" if unit not in ("", "1") else ""


def _values_text(name: str, values) -> str:
    values = list(dict.fromkeys(values))
    if len(values) > 6 and input_of(name).kind == "number":
        return f"{min(values):g} to {max(values):g}{_unit(name)}"
    return ", ".join(_value(v) for v in values) + _unit(name)


def _spec_lines(spec: SweepSpec, table: pa.Table) -> list[str]:
    lines = ["## The campaign", "", f"- name: {_md(spec.name)}"]
    lines += [f"- description: {_md(spec.description)}"] * bool(spec.description)
    lines += [f"- runs: {spec.n_runs} in the spec, {table.num_rows} in the file"]
    names = ", ".join(f"`{m}`" for m in spec.metrics)
    lines += [f"- seed: {spec.seed}; engine: {spec.engine}; metrics: {names}"]
    lines += [f"- model: {_md(spec.model_path)}"] * bool(spec.model_path)
    base = ", ".join(f"`{k}` = {_value(v)}{_unit(k)}" for k, v in spec.base)
    lines.append(f"- base parameters: {base or 'none (the paper Table 1 values)'}")
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
    status, message, runs = _texts(table, "status"), _texts(table, "message"), _texts(table, "run")
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
    metric = next((m for m in _MAPPABLE if m in spec.metrics), spec.metrics[0])
    d: dict[str, Any] = {"metric": metric, "metrics": spec.metrics, "v": _numbers(table, metric)}
    d.update(status=_texts(table, "status"), comp=_texts(table, "compensator"))
    d["comps"] = list(dict.fromkeys(d["comp"].tolist()))
    written: list[Path] = []
    body: list[str] = ["## Figures", ""]

    def figure(name: str, title: str, draw, *args) -> None:
        caption = draw(folder / name, d, *args)
        written.append(folder / name)
        body.extend([f"![{title}]({name})", f"*{caption}*", ""])

    plane = plane_inputs(spec, table) if table.num_rows else None
    if plane is not None:
        x, y = (_numbers(table, n) for n in plane)
        shown = np.isfinite(x) & np.isfinite(y)
        plane = plane if shown.any() else None
    if plane is None:
        why = "no run has finite values of both" if table.num_rows else "no run is in the file"
        if plane_inputs(spec, table) is None:
            why = "the campaign varies fewer than two numeric inputs"
        body += [f"No map over two parameters and no stability boundary: {why}.", ""]
    else:
        d.update(xname=plane[0], yname=plane[1], x=x, y=y, hidden=int(np.sum(~shown)))
        d.update(
            log_x=_log_axis(x),
            log_y=_log_axis(y),
            grid=_on_grid(*_cells(x, y, x * 0)[:3])[2] is not None,
        )
        d["class"] = classify_runs(table, spec.metrics)
        title = "{} over {} and {}".format(*(axis_label(n, False) for n in (metric, *plane)))
        figure("cor_map.png", title, _plane_figure)
    if metric == "stable":
        body += ["No CDF: the campaign measures only whether the loop is stable.", ""]
    elif not np.isfinite(d["v"][d["status"] == "ok"]).any():
        body += [f"No CDF: no run gave a value of {axis_label(metric)}.", ""]
    else:
        figure("cor_cdf.png", f"CDF of {axis_label(metric, False)}", _cdf_figure)
    if plane is not None and np.isfinite(d["class"]).any():
        figure("stability_boundary.png", "Stability boundary", _plane_figure, True)
    elif plane is not None:
        body += ["No stability boundary: no run finished or diverged.", ""]

    lines = [f"# Sweep {_md(spec.name)}", "", f"**{_md(verdict(spec.name, summary))}.**", ""]
    lines += _spec_lines(spec, table) + [""] + body + _tables(table, spec, summary, metric)
    report = folder / "report.md"
    report.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return [*written, report, Path(write_html_report(report))]
