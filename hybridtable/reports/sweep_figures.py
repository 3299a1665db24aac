"""The figures of a campaign's report (:mod:`hybridtable.reports.sweep`): a
metric over the two swept numeric inputs with the most distinct values, a
panel per compensator (a heat map on a grid, a scatter for Monte Carlo
points), its CDF, the boundary where runs stop being stable (a classifier
over the plane), and a 6-DoF campaign's envelope (a map of each metric, the
capture boundary).
"""

from __future__ import annotations

import math

import numpy as np
import pyarrow as pa

from hybridtable.reports.colour_scale import colour_scale, crosses, ticks_both_sides
from hybridtable.reports.figure_text import literal
from hybridtable.reports.sweep_summary import COR_GAIN_TOLERANCE
from hybridtable.six_dof.metrics import ENERGY_MATCH_TOLERANCE
from hybridtable.sweeps.metrics import METRICS
from hybridtable.sweeps.plan import SweepSpec, input_for

__all__ = ["STABLE_COR", "MAPPABLE", "axis_label", "plane_inputs", "classify_runs"]
__all__ += ["stability_map", "worst_runs", "plane_figure", "cdf_figure", "envelope_figures"]
__all__ += ["numbers", "texts", "log_axis", "on_grid", "cells", "rules_for"]

#: A run whose CoR is at most this created no energy (the paper's four digits).
STABLE_COR = 1.0 + COR_GAIN_TOLERANCE

#: The metrics a map shows first, in this order (else the spec's first), with the
#: level that separates gain from loss (a contour; None: none), higher-is-worse.
MAPPABLE: dict[str, tuple[float | None, bool]] = {
    **dict.fromkeys(("cor", "predicted_cor", "energy_ratio"), (1.0, True)),
    **{"phase_margin_deg": (0.0, False), "growth_rate_per_s": (0.0, True)},
    **{"damping_ratio": (0.0, False), "critical_sensor_delay_s": (None, False)},
    **dict.fromkeys(("energy_gain_j", "energy_created"), (0.0, True)),
    "stable": (0.5, False),
    "cor_normal": (1.0, True),
    "energy_excess": (0.0, True),
    "captured": (0.5, False),
}
#: Every metric's level (None) and direction (higher is worse), those above apart.
_LOOK = {**dict.fromkeys(METRICS, (None, True)), **MAPPABLE}
#: How a finished run is judged stable: the first of these metrics the spec has.
_RULES = (
    ("stable", lambda v: v > 0.5, "the linearized loop in contact is stable (the stable margin)"),
    ("cor", lambda v: v <= STABLE_COR, f"CoR <= {STABLE_COR:g} (the loop created no energy)"),
    ("predicted_cor", lambda v: v <= STABLE_COR, f"the predicted CoR <= {STABLE_COR:g}"),
    ("growth_rate_per_s", lambda v: v <= 0.0, "no pole of the loop grows (growth rate <= 0 1/s)"),
)
#: How a 6-DoF campaign's finished run is judged energy-honest: the first of
#: these metrics the spec has.
_DOCKING_RULES = (
    (
        "energy_excess",
        lambda v: np.abs(v) <= ENERGY_MATCH_TOLERANCE,
        f"the energy ratio within {ENERGY_MATCH_TOLERANCE:g} of the ideal rig's (no delay, an "
        "ideal table): the rig returned the energy the contact alone would",
    ),
    (
        "energy_ratio",
        lambda v: v <= 1.0 + ENERGY_MATCH_TOLERANCE,
        f"energy ratio <= {1.0 + ENERGY_MATCH_TOLERANCE:g}, the loop created at most "
        f"{100 * ENERGY_MATCH_TOLERANCE:g} % of the approach's energy (one-sided: measure "
        "energy_excess to judge a loop that takes energy out)",
    ),
)


def rules_for(loop: str) -> tuple:
    """The rules that judge a run of ``loop``: (metric, test, words), first
    match wins."""
    return _DOCKING_RULES if loop == "six_dof" else _RULES


_WORDS = {"cor": "CoR", "predicted_cor": "predicted CoR", "growth_rate_per_s": "growth rate"}
_WORDS["stable"] = "stable (1: yes, 0: no)"
_WORDS["captured"] = "captured (1: yes, 0: no)"
_WORDS["cor_normal"] = "CoR along the normal"


def axis_label(name: str, unit: bool = True) -> str:
    """An input or metric in words, with its unit unless not ``unit``
    (``sensor_delay_s`` -> ``sensor delay [s]``, ``cor`` -> ``CoR [1]``)."""
    found = input_for(name, None)
    si = found.unit if found is not None else METRICS[name].unit
    words = _WORDS.get(name)
    if words is None:
        suffix = "_" + si.lower().replace("/", "_per_").replace(" ", "_")
        words = (name[: -len(suffix)] if si and name.endswith(suffix) else name).replace("_", " ")
    return f"{words} [{si or '1'}]" if unit else words


def numbers(table: pa.Table, name: str) -> np.ndarray:
    """A column as floats (NaN: missing; a flag as 1.0 / 0.0)."""
    return np.asarray(table.column(name).cast(pa.float64()).to_numpy(), dtype=float)


def texts(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_pylist(), dtype=object)


def plane_inputs(spec: SweepSpec, table: pa.Table) -> tuple[str, str] | None:
    """The two swept numeric inputs with the most distinct values in ``table``
    (ties: the spec's order), x first; None if fewer than two are swept."""
    names = [n for n in spec.swept if n != "compensator" and spec.input(n).kind == "number"]
    if len(names) < 2:
        return None
    return tuple(sorted(names, key=lambda n: -np.unique(numbers(table, n)).size)[:2])


def cells(x, y, values, reduce=np.median):
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


def on_grid(px, py, values):
    """Values at pairs ``(px, py)`` over the distinct x and y (None: not a grid,
    more than 50 values on an axis or fewer than half the combinations present)."""
    gx, gy = np.unique(px), np.unique(py)
    if not 0 < gx.size <= 50 or gy.size > 50 or px.size < 0.5 * gx.size * gy.size:
        return gx, gy, None
    z = np.full((gy.size, gx.size), np.nan)
    z[np.searchsorted(gy, py), np.searchsorted(gx, px)] = values
    return gx, gy, z


def classify_runs(table: pa.Table, metrics: tuple[str, ...], loop: str = "1d") -> np.ndarray:
    """Per run 1.0 (stable), 0.0 (not stable, or diverged) or NaN (failed,
    invalid, error, no value). Stable: ``stable`` true when the spec measures
    that margin, else CoR <= :data:`STABLE_COR` (or the predicted CoR, the
    energy ratio, the growth rate), else: did not diverge."""
    status = texts(table, "status")
    name, rule, _ = next((r for r in rules_for(loop) if r[0] in metrics), ("", None, ""))
    v = numbers(table, name) if name else np.zeros(table.num_rows)
    out = np.where((status == "ok") & np.isfinite(v), rule(v) if rule else True, np.nan)
    out[status == "diverged"] = 0.0
    return out


def log_axis(values) -> bool:
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
    gx, gy, frac = on_grid(*cells(x, y, c, reduce=np.mean)[:3])
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
    status = texts(table, "status")
    v = numbers(table, metric)
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


def plane_figure(path, d, stability: bool = False) -> str:
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
            px, py, med, n = cells(x, y, vals)
            gx, gy, z = on_grid(px, py, med) if d["grid"] and finite.size else (px, py, None)
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
    label = f"fraction of runs {d.get('word', 'stable')} [1]" if stability else axis_label(metric)
    if drawn is not None:
        bar = fig.colorbar(drawn, ax=axes, label=label, shrink=0.9)
        ticks_both_sides(bar, norm)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    plane = f"over {axis_label(d['xname'])} and {axis_label(d['yname'])}, one panel per compensator"
    if stability:
        rules = rules_for(d.get("loop", "1d"))
        rule = next((w for n, _, w in rules if n in d["metrics"]), "the run finished")
        rule = d.get("rule", rule)
        how = "of its runs" if d["grid"] else "of the nearest runs (up to 7, a classifier)"
        word, title = d.get("word", "stable"), d.get("title", "Stability")
        return (
            f"{title} {plane}; {word} here: {rule}, {d.get('negation', 'unstable')}: not, or "
            f"diverged; colour: the fraction {how} {word} [1] (green: {word}, red: not); black "
            f"line: the boundary (half {word}); circles: {word} runs, triangles: finished runs "
            "that are not, black crosses: diverged runs."
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


def cdf_figure(path, d) -> str:
    import matplotlib.pyplot as plt

    metric, level = d["metric"], _LOOK[d["metric"]][0]
    ok = d["status"] == "ok"
    finite = d["v"][ok & np.isfinite(d["v"])]
    lo, hi, log = float(finite.min()), float(finite.max()), log_axis(finite)
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


def envelope_figures(table: pa.Table, spec: SweepSpec, drawn: str, figure) -> list[str]:
    """A 6-DoF campaign's other maps: each numeric metric but ``drawn``, and
    where the docking captures; returns the report's sentences for what it
    could not draw."""
    said = []
    for name in spec.metrics:
        if name == drawn or METRICS[name].kind != "number":
            continue
        v = numbers(table, name)
        if not np.isfinite(v[texts(table, "status") == "ok"]).any():
            # e.g. the identified stiffness of a campaign without an identifier
            said.append(f"No map of {axis_label(name, False)}: no run gave a value.")
            continue
        plane = (*(axis_label(n, False) for n in plane_inputs(spec, table)),)
        title = "{} over {} and {}".format(axis_label(name, False), *plane)
        figure(f"{name}_map.png", title, plane_figure, look={"metric": name, "v": v})
    if "captured" in spec.metrics:
        status = texts(table, "status")
        captured = numbers(table, "captured")
        classes = np.where((status == "ok") & np.isfinite(captured), captured, np.nan)
        classes[status == "diverged"] = 0.0
        if not np.any(classes == 1.0):
            ok = int(np.sum(status == "ok"))
            said.append(
                f"No capture boundary: none of the {ok} finished runs captured (each contact "
                "returned the spacecraft)."
            )
            return said
        look = {
            "class": classes,
            "word": "captured",
            "negation": "not captured",
            "title": "Capture",
            "rule": "the contact held the spacecraft, its port at rest against the target",
        }
        figure("capture_boundary.png", "Capture boundary", plane_figure, True, look=look)
    return said
