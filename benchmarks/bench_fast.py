"""Benchmark: the fast path (hybridtable.loop.fast) against the Drake diagram on Table 1.

For each of the four Table 1 runs (none, SDC, MDC, SDMDC) it prints the wall
time per run of the diagram (``simulate``) and of the fast path
(``simulate_fast``) in this one process, their CoR difference, and both CoR
errors against a fine diagram reference (``time_step_s = step_s / 8``); then
the ratio of the times. The fast path's error against the reference is the
continuous delay line's discretization at the default step (the diagram has
the same): the fast path at the fine step meets the reference to the
integrator's accuracy, shown in the last column.

Times are the median of ``--repeat`` runs (the minimum too for the fast path:
on a busy machine the median is the honest figure).

Usage: python benchmarks/bench_fast.py [--repeat N] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from hybridtable.loop.fast import simulate_fast
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")


def _timed(fn, params, repeat: int) -> tuple[float, list[float]]:
    """CoR of ``fn(params)`` and the wall times of ``repeat`` calls (s)."""
    times, cor = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn(params)
        times.append(time.perf_counter() - t0)
        cor = getattr(out, "metrics", out).cor
    return cor, times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20, help="fast-path runs per point")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args()
    rows = {}
    for c in COMPENSATORS:
        p = table1_params(c)
        fine = p.with_(time_step_s=p.step_s / 8)
        reference = simulate(fine).metrics.cor
        simulate_fast(p)  # first call: imports and caches
        cor_d, t_d = _timed(simulate, p, max(3, args.repeat // 5))
        cor_f, t_f = _timed(simulate_fast, p, args.repeat)
        cor_ff, t_ff = _timed(simulate_fast, fine, 3)
        rows[c] = {
            "reference_cor": reference,
            "diagram_cor": cor_d,
            "fast_cor": cor_f,
            "fast_minus_diagram": cor_f - cor_d,
            "diagram_error": abs(cor_d - reference),
            "fast_error": abs(cor_f - reference),
            "fast_fine_step_error": abs(cor_ff - reference),
            "diagram_ms": 1e3 * statistics.median(t_d),
            "fast_ms": 1e3 * statistics.median(t_f),
            "fast_min_ms": 1e3 * min(t_f),
            "fast_fine_step_ms": 1e3 * statistics.median(t_ff),
        }
    total_d = sum(r["diagram_ms"] for r in rows.values())
    total_f = sum(r["fast_ms"] for r in rows.values())
    worst = max(abs(r["fast_minus_diagram"]) for r in rows.values())
    print(
        f"The fast path runs a Table 1 contact in {total_f / 4:.1f} ms against "
        f"{total_d / 4:.0f} ms for the diagram ({total_d / total_f:.0f}x faster), "
        f"with the same CoR to {worst:.1e}."
    )
    print(
        f"{'run':6s} {'diagram':>9s} {'fast':>8s} {'(min)':>7s} {'CoR':>9s} "
        f"{'fast-diag':>10s} {'err diag':>9s} {'err fast':>9s} {'fine fast':>10s}"
    )
    for c, r in rows.items():
        print(
            f"{c:6s} {r['diagram_ms']:7.1f}ms {r['fast_ms']:6.2f}ms {r['fast_min_ms']:5.2f}ms "
            f"{r['fast_cor']:9.6f} {r['fast_minus_diagram']:+10.1e} {r['diagram_error']:9.1e} "
            f"{r['fast_error']:9.1e} {r['fast_fine_step_error']:10.1e}"
        )
    print(
        "errors against the diagram at step_s/8; 'fine fast': the fast path at that step "
        f"({statistics.median(r['fast_fine_step_ms'] for r in rows.values()):.0f} ms a run)"
    )
    print(f"ratio diagram time / fast time: {total_d / total_f:.1f}")
    if args.json:
        result = {
            "runs": rows,
            "diagram_ms_per_run": total_d / 4,
            "fast_ms_per_run": total_f / 4,
            "ratio_diagram_over_fast": total_d / total_f,
            "max_abs_cor_difference": worst,
        }
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)


if __name__ == "__main__":
    main()
