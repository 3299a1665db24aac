"""Benchmark of the compensator plug-ins: cost per run, step convergence, and
the passivity guard's energy tolerance.

Prints, for every registered compensator at the Table 1 point and at the
Table 2 point with a 5 Hz contact (the believed stiffness 50 % low):

- the wall time of one run (continuous loop; with and without the guard), and
  of the sampled loop at 1 kHz;
- the CoR at the default step and at half of it (the sweep's numbers are
  converged when the two agree);
- with the guard, the CoR for energy tolerances 0 (strict, the default),
  1e-3 and 1e-2 of the peak absorbed energy (bound sqrt(1 + tol)).

Usage: python benchmarks/bench_compensators.py [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import time

from hybridtable.compensators.passivity import passivity_guarded
from hybridtable.compensators.registry import compensator_names, make_compensator
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import run_loop, simulate
from hybridtable.studies.paper import table1_params, table2_params, table2_rows


def timed(params, **kw):
    t0 = time.perf_counter()
    result = simulate(params, **kw)
    return result.metrics.cor, time.perf_counter() - t0


def guarded_cor(params, tolerance: float) -> float:
    loop0 = build_hybrid_loop(params, log=False)
    h = loop0.computer_period_s
    comp = passivity_guarded(make_compensator(params, h), params, h, energy_tolerance=tolerance)
    return run_loop(build_hybrid_loop(params, compensator=comp)).metrics.cor


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    row5 = next(r for r in table2_rows() if r["contact_frequency_hz"] == 5)
    points = {
        "table1": lambda name, **kw: table1_params(name, **kw),
        "5Hz": lambda name, **kw: table2_params(row5).with_(compensator=name, **kw),
    }
    out = []
    head = (
        f"{'point':<7}{'compensator':<14}{'s/run':>7}{'+guard':>8}{'1kHz':>7}"
        f"{'CoR':>9}{'half step':>10}{'guarded':>9}{'tol 1e-3':>9}{'tol 1e-2':>9}"
    )
    print(head)
    for point, make in points.items():
        for name in compensator_names():
            base = make(name)
            k = base.contact_stiffness_n_per_m
            p = base.with_(compensator_stiffness_n_per_m=0.5 * k)
            cor, wall = timed(p)
            half, _ = timed(p.with_(time_step_s=p.step_s / 2))
            g_cor, g_wall = timed(p.with_(passivity=True))
            _, s_wall = timed(p.with_(sample_rate_hz=1e3, clamp_nonnegative=True))
            tol3 = guarded_cor(p, 1e-3)
            tol2 = guarded_cor(p, 1e-2)
            row = dict(
                point=point,
                compensator=name,
                wall_s=wall,
                guarded_wall_s=g_wall,
                sampled_wall_s=s_wall,
                cor=cor,
                cor_half_step=half,
                cor_guarded=g_cor,
                cor_guarded_tol_1e3=tol3,
                cor_guarded_tol_1e2=tol2,
            )
            out.append(row)
            print(
                f"{point:<7}{name:<14}{wall:>7.2f}{g_wall:>8.2f}{s_wall:>7.2f}{cor:>9.5f}"
                f"{half:>10.5f}{g_cor:>9.5f}{tol3:>9.5f}{tol2:>9.5f}"
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
