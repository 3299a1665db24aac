"""Benchmark: wall time of ``explain`` on the paper's tables, serial against parallel.

Explains each example table (``examples/explain/``) with ``workers=1`` and with
``workers=N`` in one run, the engine's cache cleared before each, and prints the
wall and process CPU time, the number of models fitted and the ratio serial /
parallel. Target: Table 3 (4 rows, continuous rig computer) under 30 s serial
on a 2-core machine; the parallel ratio close to the number of cores.

Usage: python benchmarks/bench_explain.py [--jobs N] [--tables NAME ...] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from hybridtable.explain.explain import explain_table
from hybridtable.explain.model import _ln_cor_of
from hybridtable.explain.table import read_cor_table

ROOT = Path(__file__).resolve().parents[1] / "examples" / "explain"


def _time(table, jobs: int) -> tuple[float, float, int]:
    _ln_cor_of.cache_clear()
    wall, cpu = time.perf_counter(), time.process_time()
    expl = explain_table(table, workers=jobs)
    return time.perf_counter() - wall, time.process_time() - cpu, len(expl.fits)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--tables", nargs="*", default=["table3_experiment", "table1_simulation"])
    ap.add_argument("--json")
    args = ap.parse_args()
    out = {}
    for name in args.tables:
        table = read_cor_table(ROOT / f"{name}.csv")
        serial = _time(table, 1)
        parallel = _time(table, args.jobs)
        out[name] = {
            "rows": len(table.rows),
            "models": serial[2],
            "serial_wall_s": serial[0],
            "serial_cpu_s": serial[1],
            "parallel_wall_s": parallel[0],
            "jobs": args.jobs,
            "speed_up": serial[0] / parallel[0],
        }
        print(
            f"{name}: {len(table.rows)} rows, {serial[2]} models: serial {serial[0]:.1f} s "
            f"(CPU {serial[1]:.1f} s), {args.jobs} jobs {parallel[0]:.1f} s, "
            f"speed-up {serial[0] / parallel[0]:.2f}"
        )
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
