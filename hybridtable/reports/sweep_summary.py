"""The verdict and the console summary of a campaign (``hybridtable sweep``).

Read from the results table alone (:mod:`hybridtable.sweeps.store`), so a
resumed or interrupted campaign is summarized the same way as a whole one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["COR_GAIN_TOLERANCE", "energy_metric"]
__all__ += ["summarize", "verdict", "format_summary"]

#: A CoR above 1 + this counts as energy created by the loop (the paper's
#: four digits).
COR_GAIN_TOLERANCE = 1e-4


def energy_metric(metrics: tuple[str, ...], loop: str = "1d") -> tuple | None:
    """How a campaign says whether a run created energy: ``(metric, words,
    is_gain, distance)``: the 1-D loop's CoR (a gain above 1 + the
    tolerance, the distance from 1 in decades); a 6-DoF campaign's energy
    excess over the ideal rig (a gain above the 6-DoF tolerance, the
    distance from 0), else its energy ratio; None: none of them measured."""
    if loop == "1d":
        if "cor" not in metrics:
            return None
        return "cor", "CoR", lambda v: v > 1.0 + COR_GAIN_TOLERANCE, _decades
    from hybridtable.six_dof.metrics import ENERGY_MATCH_TOLERANCE as tol

    if "energy_excess" in metrics:
        return "energy_excess", "energy excess over the ideal rig", lambda v: v > tol, abs
    if "energy_ratio" in metrics:
        return "energy_ratio", "energy ratio", lambda v: v > 1.0 + tol, _decades
    return None


def _decades(v: float) -> float:
    return abs(math.log(v)) if v > 0 else math.inf


def _column(table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_pylist(), dtype=object)


def _stats(values: np.ndarray) -> dict[str, Any]:
    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if x.size == 0:
        return {"min": None, "median": None, "max": None}
    return {"min": float(x.min()), "median": float(np.median(x)), "max": float(x.max())}


def summarize(table, n_runs: int, metrics: tuple[str, ...], loop: str = "1d") -> dict[str, Any]:
    """Counts by status, and per compensator the runs, their statuses and the
    spread of each metric; the worst runs (diverged first, then by the
    :func:`energy_metric`: the highest CoR; in 6-DoF the furthest from an
    energy-honest docking). A 6-DoF campaign's summary says ``"loop"``.

    Parameters
    ----------
    table : pyarrow.Table
        The campaign's rows.
    n_runs : int
        Runs in the spec (the table may hold fewer: interrupted).
    metrics : tuple of str
        The spec's metrics.
    loop : str
        The spec's loop (``1d`` or ``six_dof``).
    """
    from hybridtable.sweeps.metrics import METRICS

    status = _column(table, "status")
    comps = _column(table, "compensator")
    energy = energy_metric(metrics, loop)
    gained = "cor_above_1" if loop == "1d" else "energy_gained"
    counts = {s: int(np.sum(status == s)) for s in dict.fromkeys(status.tolist())}
    per: dict[str, Any] = {}
    for comp in dict.fromkeys(comps.tolist()):
        mask = comps == comp
        entry: dict[str, Any] = {
            "runs": int(mask.sum()),
            "status": {s: int(np.sum(status[mask] == s)) for s in dict.fromkeys(status[mask])},
        }
        for m in metrics:
            col = _column(table, m)[mask]
            if METRICS[m].kind == "bool":  # stable, captured: how many runs
                entry[m] = int(sum(1 for v in col if v is True))
                continue
            entry[m] = _stats(col)
        if energy is not None:
            values = _column(table, energy[0])[mask]
            ok = [float(c) for c in values if c is not None and math.isfinite(c)]
            entry[gained] = int(sum(1 for c in ok if energy[2](c)))
        per[comp] = entry
    worst = []
    if energy is not None and table.num_rows:
        badness = (lambda c: c) if loop == "1d" else energy[3]  # 1-D: the highest CoR
        cor = np.asarray(
            [
                badness(c) if c is not None and math.isfinite(c) else -math.inf
                for c in _column(table, energy[0])
            ]
        )
        rank = sorted(
            range(table.num_rows),
            key=lambda i: (status[i] != "diverged", -cor[i], i),
        )
        rows = table.to_pylist()
        worst = [rows[i] for i in rank[:5] if status[i] in ("ok", "diverged")]
    out = {
        "runs": n_runs,
        "written": table.num_rows,
        "status": counts,
        "compensators": per,
        "worst": worst,
    }
    return out if loop == "1d" else {"loop": loop, **out}


def _range(stats: dict[str, Any], digits: int = 4) -> str:
    if stats["min"] is None:
        return "no value"
    if stats["min"] == stats["max"]:
        return f"{stats['min']:.{digits}f}"
    return f"{stats['min']:.{digits}f} to {stats['max']:.{digits}f}"


def verdict(name: str, summary: dict[str, Any]) -> str:
    """One plain sentence: how many runs finished, the compensators whose CoR
    stays closest to and goes furthest from 1 (an energy-neutral bounce; in a
    6-DoF campaign the energy excess over the ideal rig from 0, else the
    energy ratio from 1), how many captured, and how many diverged or failed."""
    n, written = summary["runs"], summary["written"]
    counts = summary["status"]
    ok = counts.get("ok", 0)
    head = f"sweep {name}: {ok} of {n} runs finished"
    if written < n:
        head += f" ({n - written} not run yet)"
    bad = [f"{counts[s]} {s}" for s in ("diverged", "failed", "invalid", "error") if counts.get(s)]
    per = summary["compensators"]
    loop = summary.get("loop", "1d")
    first = next(iter(per.values()), {})
    energy = energy_metric(tuple(first), loop) or ("cor", "CoR", None, _decades)
    key, words, distance = energy[0], energy[1], energy[3]
    centre = 0.0 if key == "energy_excess" else 1.0
    cors = {c: e[key] for c, e in per.items() if key in e and e[key]["max"] is not None}
    if cors:
        if len(per) == 1:
            (comp, stats), *_ = cors.items()
            head += f"; {comp} gives {words} {_range(stats)}"
        else:
            # Distance from an energy-neutral bounce (CoR 1), the worst run of
            # each compensator: a loop that takes energy out is no better
            # than one that puts it in. Diverged runs count first.
            def far(c: str) -> tuple[int, float]:
                lo, hi = cors[c]["min"], cors[c]["max"]
                return per[c]["status"].get("diverged", 0), max(distance(lo), distance(hi))

            near, away = min(cors, key=far), max(cors, key=far)
            diverged = per[away]["status"].get("diverged", 0)
            head += (
                f"; closest to {words} {centre:g}: {near} ({_range(cors[near])}), furthest: "
                f"{away} ({_range(cors[away])}{f', {diverged} diverged' if diverged else ''})"
            )
    elif any("stable" in e for e in per.values()):
        stable = sum(e.get("stable", 0) for e in per.values())
        head += f"; the linear loop is stable in {stable} of {written}"
    if any("captured" in e for e in per.values()):
        captured = sum(e.get("captured", 0) for e in per.values())
        head += f"; captured in {captured} of {written}"
    if bad:
        head += "; " + ", ".join(bad)
    return head


def format_summary(name: str, summary: dict[str, Any], metrics: tuple[str, ...]) -> str:
    """The verdict, a line per compensator and the worst runs, as text."""
    from hybridtable.sweeps.metrics import METRICS

    lines = [verdict(name, summary), ""]
    counted = [m for m in metrics if METRICS[m].kind == "bool"]  # stable, captured
    shown = [m for m in metrics if m not in counted][:4]
    loop = summary.get("loop", "1d")
    energy = energy_metric(metrics, loop)
    gained = "cor_above_1" if loop == "1d" else "energy_gained"
    header = f"{'compensator':<14}{'runs':>6}{'ok':>6}{'diverged':>9}"
    if energy is not None:
        header += f"{'CoR>1' if loop == '1d' else 'gained':>7}"
    header += "".join(f"{m:>{max(7, len(m) + 1)}}" for m in counted)
    header += "".join(f"  {m + ' (min..max)':<28}" for m in shown)
    lines.append(header)
    for comp, e in summary["compensators"].items():
        line = (
            f"{comp:<14}{e['runs']:>6}{e['status'].get('ok', 0):>6}"
            f"{e['status'].get('diverged', 0):>9}"
        )
        if energy is not None:
            line += f"{e.get(gained, 0):>7}"
        line += "".join(f"{e.get(m, 0):>{max(7, len(m) + 1)}}" for m in counted)
        line += "".join(f"  {_range(e[m], 4 if m == 'cor' else 3):<28}" for m in shown)
        lines.append(line)
    if summary["worst"]:
        worst = f"highest {energy[1]}" if loop == "1d" else f"{energy[1]} furthest from honest"
        lines += ["", f"worst runs ({worst}, diverged first):"]
        for row in summary["worst"]:
            inputs = [
                f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                for k, v in row.items()
                if k not in _NOT_INPUTS and k not in metrics
            ]
            cor = row.get(energy[0])
            what = row["status"] if row["status"] != "ok" else f"{energy[1]} {cor:.4f}"
            lines.append(f"  run {row['run']}: {what}; {', '.join(inputs)}")
    return "\n".join(lines)


_NOT_INPUTS = ("run", "point", "sample", "seed", "status", "message", "engine", "seconds")
