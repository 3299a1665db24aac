"""Benchmark: margins over a 40 x 40 (delay, table frequency) grid, four compensators.

Times :func:`hybridtable.sweeps.margins_grid.sweep_margins` (Drake block linearization, assembly,
closed-loop poles, phase margin at the contact crossover, critical delay per
table frequency and critical table frequency per delay, and the check of the
assembled model against a direct ``Linearize`` of the full diagram) for:

- the paper's contact (undamped, 1 Hz, 1e5 N/m), continuous, Pade order 3;
- the same contact with damping ratio 0.05 (the critical searches then scan);
- the paper's contact with a rig computer at 1 kHz (sampled-data model, a
  40 x 21 grid: delays of whole samples, 0-20 ms).

Usage: python benchmarks/bench_margins.py [--json FILE] [--size N]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time

import numpy as np

from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.studies.paper import paper_params
from hybridtable.sweeps.margins_grid import sweep_margins


def run_case(name: str, base, delays, tables) -> dict:
    t0 = time.perf_counter()
    r = sweep_margins(base, delays, tables, COMPENSATORS)
    wall = time.perf_counter() - t0
    n = len(delays) * len(tables) * len(COMPENSATORS)
    print(
        f"{name:34s} {len(delays):3d} x {len(tables):3d} x {len(COMPENSATORS)}: "
        f"{wall:6.2f} s  ({1e3 * wall / n:.3f} ms per point, verification "
        f"{r.verification_error:.1e})"
    )
    return {
        "case": name,
        "delays": len(delays),
        "tables": len(tables),
        "compensators": len(COMPENSATORS),
        "wall_time_s": wall,
        "verification_error": r.verification_error,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", metavar="FILE", help="write the timings as JSON")
    ap.add_argument("--size", type=int, default=40, help="grid size per axis (default 40)")
    args = ap.parse_args()
    n = args.size
    delays = np.linspace(0.0, 0.02, n)
    tables = np.linspace(5.0, 200.0, n)
    base = paper_params(sensor_delay_s=0.0)
    c = 2 * 0.05 * math.sqrt(base.contact_stiffness_n_per_m * base.spacecraft_mass_kg)
    print(f"cores available: {os.cpu_count()}")
    rows = [
        run_case("continuous, undamped contact", base, delays, tables),
        run_case(
            "continuous, contact damping 0.05",
            base.with_(contact_damping_n_s_per_m=c),
            delays,
            tables,
        ),
        run_case(
            "sampled 1 kHz, undamped contact",
            base.with_(sample_rate_hz=1000.0),
            np.arange(21) * 1e-3,
            tables,
        ),
    ]
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=2)


if __name__ == "__main__":
    main()
