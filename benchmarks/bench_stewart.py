"""Benchmark: real-time factor of the hybrid loop closed around the Stewart plant.

The loop (spacecraft model, sensor delay, compensator at 1 kHz; Stewart
MultibodyPlant with a 1 ms step, leg servo, F/T sensor) runs the paper's
Table 1 point for each compensator, over a fixed horizon that includes the
whole contact. Reported: the real-time factor (simulated time / wall time of
``Simulator.AdvanceTo``, median of ``--repeat`` runs; and simulated time /
process CPU time, which other jobs on the machine do not inflate), the CoR, and the same
for the table alone driven by a recorded command (to show the loop's own
overhead). Tuning and diagram construction are timed separately.

Target (issue 4): real-time factor >= 2 on a 2-core machine.

Usage: python benchmarks/bench_stewart.py [--json FILE] [--repeat N] [--horizon-s T]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

from hybridtable.loop.simulation import run_loop
from hybridtable.stewart.backend import build_stewart_loop
from hybridtable.stewart.identify import drive_table, tune_table
from hybridtable.stewart.params import StewartParams
from hybridtable.studies.paper import table1_params


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", metavar="FILE", help="write the figures as JSON")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--horizon-s", type=float, default=1.5, help="simulated time per run")
    args = parser.parse_args()

    t0 = time.perf_counter()
    stewart, step = tune_table(StewartParams(), 25.0, 0.8)
    tune_s = time.perf_counter() - t0
    print(
        f"tuned in {tune_s:.2f} s: identified {step.response_frequency_hz:.3f} Hz, "
        f"zeta {step.damping_ratio:.4f}; cores: {os.cpu_count()}"
    )
    figures = {"cpu_count": os.cpu_count(), "tune_s": tune_s, "runs": {}}
    for compensator in ("none", "SDC", "MDC", "SDMDC"):
        params = table1_params(compensator, sample_rate_hz=1000.0)
        rtf, rtf_cpu, build = [], [], []
        cor = None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            loop = build_stewart_loop(params, stewart)
            build.append(time.perf_counter() - t0)
            t0, c0 = time.perf_counter(), time.process_time()
            result = run_loop(loop, t_max_s=args.horizon_s, stop_at_separation=False)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            rtf.append(args.horizon_s / wall)
            rtf_cpu.append(args.horizon_s / cpu)
            cor = result.metrics.cor
        figures["runs"][compensator] = {
            "real_time_factor_median": statistics.median(rtf),
            "real_time_factor_min": min(rtf),
            "cpu_real_time_factor_median": statistics.median(rtf_cpu),
            "build_s_median": statistics.median(build),
            "steps": int(result.steps),
            "cor": cor,
        }
        print(
            f"{compensator:>6}: real-time factor {statistics.median(rtf):5.2f} "
            f"(min {min(rtf):.2f}, CPU {statistics.median(rtf_cpu):.2f})  "
            f"build {statistics.median(build):.3f} s  CoR {cor:.5f}"
        )

    # The table alone, driven by a smooth command over the same horizon.
    h = stewart.time_step_s
    n = int(round(args.horizon_s / h))
    t = h * np.arange(n)
    command = -0.005 + 0.004 * np.sin(2 * np.pi * 2.0 * t)
    walls = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        drive_table(stewart, command, -0.005)
        walls.append(time.perf_counter() - t0)
    figures["table_alone_real_time_factor"] = args.horizon_s / statistics.median(walls)
    print(
        f" table alone (incl. build): real-time factor "
        f"{figures['table_alone_real_time_factor']:.2f}"
    )
    worst = min(r["real_time_factor_median"] for r in figures["runs"].values())
    figures["worst_real_time_factor"] = worst
    print(f"worst median real-time factor {worst:.2f} (target >= 2)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(figures, fh, indent=2)


if __name__ == "__main__":
    main()
