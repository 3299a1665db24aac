"""The verdict and the console summary of a campaign (``hybridtable sweep``).

Read from the results table alone (:mod:`hybridtable.sweeps.store`), so a
resumed or interrupted campaign is summarized the same way as a whole one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["COR_GAIN_TOLERANCE", "summarize", "verdict", "format_summary"]

#: A CoR above 1 + this counts as energy created by the loop (the paper's
#: four digits).
COR_GAIN_TOLERANCE = 1e-4


def _column(table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_pylist(), dtype=object)


def _stats(values: np.ndarray) -> dict[str, Any]:
    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if x.size == 0:
        return {"min": None, "median": None, "max": None}
    return {"min": float(x.min()), "median": float(np.median(x)), "max": float(x.max())}


def summarize(table, n_runs: int, metrics: tuple[str, ...]) -> dict[str, Any]:
    """Counts by status, and per compensator the runs, their statuses and the
    spread of each metric; the worst runs (highest CoR, diverged first).

    Parameters
    ----------
    table : pyarrow.Table
        The campaign's rows.
    n_runs : int
        Runs in the spec (the table may hold fewer: interrupted).
    metrics : tuple of str
        The spec's metrics.
    """
    status = _column(table, "status")
    comps = _column(table, "compensator")
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
            if m == "stable":
                entry["stable"] = int(sum(1 for v in col if v is True))
                continue
            entry[m] = _stats(col)
        if "cor" in metrics:
            cor = _column(table, "cor")[mask]
            ok = [float(c) for c in cor if c is not None and math.isfinite(c)]
            entry["cor_above_1"] = int(sum(1 for c in ok if c > 1.0 + COR_GAIN_TOLERANCE))
        per[comp] = entry
    worst = []
    if "cor" in metrics and table.num_rows:
        cor = np.asarray(
            [c if c is not None and math.isfinite(c) else -math.inf for c in _column(table, "cor")]
        )
        rank = sorted(
            range(table.num_rows),
            key=lambda i: (status[i] != "diverged", -cor[i], i),
        )
        rows = table.to_pylist()
        worst = [rows[i] for i in rank[:5] if status[i] in ("ok", "diverged")]
    return {
        "runs": n_runs,
        "written": table.num_rows,
        "status": counts,
        "compensators": per,
        "worst": worst,
    }


def _range(stats: dict[str, Any], digits: int = 4) -> str:
    if stats["min"] is None:
        return "no value"
    if stats["min"] == stats["max"]:
        return f"{stats['min']:.{digits}f}"
    return f"{stats['min']:.{digits}f} to {stats['max']:.{digits}f}"


def verdict(name: str, summary: dict[str, Any]) -> str:
    """One plain sentence: how many runs finished, the compensators whose CoR
    stays closest to and goes furthest from 1 (an energy-neutral bounce), and
    how many runs diverged or failed."""
    n, written = summary["runs"], summary["written"]
    counts = summary["status"]
    ok = counts.get("ok", 0)
    head = f"sweep {name}: {ok} of {n} runs finished"
    if written < n:
        head += f" ({n - written} not run yet)"
    bad = [f"{counts[s]} {s}" for s in ("diverged", "failed", "invalid", "error") if counts.get(s)]
    per = summary["compensators"]
    cors = {c: e["cor"] for c, e in per.items() if "cor" in e and e["cor"]["max"] is not None}
    if cors:
        if len(per) == 1:
            (comp, stats), *_ = cors.items()
            head += f"; {comp} gives CoR {_range(stats)}"
        else:
            # Distance from an energy-neutral bounce (CoR 1), the worst run of
            # each compensator: a loop that takes energy out is no better
            # than one that puts it in. Diverged runs count first.
            def far(c: str) -> tuple[int, float]:
                lo, hi = cors[c]["min"], cors[c]["max"]
                return per[c]["status"].get("diverged", 0), max(
                    abs(math.log(lo)) if lo > 0 else math.inf, abs(math.log(hi))
                )

            near, away = min(cors, key=far), max(cors, key=far)
            diverged = per[away]["status"].get("diverged", 0)
            head += (
                f"; closest to CoR 1: {near} ({_range(cors[near])}), furthest: {away} "
                f"({_range(cors[away])}{f', {diverged} diverged' if diverged else ''})"
            )
    elif any("stable" in e for e in per.values()):
        stable = sum(e.get("stable", 0) for e in per.values())
        head += f"; the linear loop is stable in {stable} of {written}"
    if bad:
        head += "; " + ", ".join(bad)
    return head


def format_summary(name: str, summary: dict[str, Any], metrics: tuple[str, ...]) -> str:
    """The verdict, a line per compensator and the worst runs, as text."""
    lines = [verdict(name, summary), ""]
    shown = [m for m in metrics if m != "stable"][:4]
    header = f"{'compensator':<14}{'runs':>6}{'ok':>6}{'diverged':>9}"
    if "cor" in metrics:
        header += f"{'CoR>1':>7}"
    if "stable" in metrics:
        header += f"{'stable':>7}"
    header += "".join(f"  {m + ' (min..max)':<28}" for m in shown)
    lines.append(header)
    for comp, e in summary["compensators"].items():
        line = (
            f"{comp:<14}{e['runs']:>6}{e['status'].get('ok', 0):>6}"
            f"{e['status'].get('diverged', 0):>9}"
        )
        if "cor" in metrics:
            line += f"{e.get('cor_above_1', 0):>7}"
        if "stable" in metrics:
            line += f"{e.get('stable', 0):>7}"
        line += "".join(f"  {_range(e[m], 4 if m == 'cor' else 3):<28}" for m in shown)
        lines.append(line)
    if summary["worst"]:
        lines += ["", "worst runs (highest CoR, diverged first):"]
        for row in summary["worst"]:
            inputs = [
                f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                for k, v in row.items()
                if k not in _NOT_INPUTS and k not in metrics
            ]
            cor = row.get("cor")
            what = row["status"] if row["status"] != "ok" else f"CoR {cor:.4f}"
            lines.append(f"  run {row['run']}: {what}; {', '.join(inputs)}")
    return "\n".join(lines)


_NOT_INPUTS = ("run", "point", "sample", "seed", "status", "message", "engine", "seconds")
