"""Benchmark: one Table 1 run in Drake against a plain Python loop.

The plain loop integrates the same equations (spacecraft, second-order table,
unilateral spring, sensor delay, SDMDC with a backward-difference lead) with
fixed-step RK4 and a delay line on the integration grid. Its step is refined
until its CoR error against a fine reference is no larger than the Drake
run's; both are timed in this one process and reported as a ratio.

Accuracy is the CoR error against a Drake run at 1/8 of the default step,
required of both to be within ``--tolerance`` (default 1e-4, the paper's four
digits) or the Drake run's own error if larger.

Usage: python benchmarks/bench_simulate.py [--json FILE] [--tolerance TOL]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params


def plain_loop(params, dt: float) -> float:
    """CoR of one contact, integrated by hand with RK4 at step ``dt``."""
    m = params.spacecraft_mass_kg
    k = params.contact_stiffness_n_per_m
    w = 2 * math.pi * params.table_response_hz
    z = params.table_damping_ratio
    T = params.sensor_delay_s
    comp = params.compensator_params()
    lead = comp.lead_time_s if comp.uses_lead else 0.0
    mdc = comp.uses_motion_correction
    n_delay = int(round(T / dt))
    v0 = params.initial_velocity_m_per_s
    x, v = -params.initial_gap_m, v0
    pa, va = x - 2 * z / w * v0, v0
    hist = [0.0] * (n_delay + 2)  # f_act on the grid, oldest first
    f_prev = 0.0
    started, quiet = False, 0.0

    def deriv(s, f_comp):
        x, v, pa, va = s
        return np.array([v, -f_comp / m, va, w * w * (x - pa) - 2 * z * w * va])

    s = np.array([x, v, pa, va])
    t = 0.0
    while True:
        f_act = k * s[2] if s[2] > 0 else 0.0
        hist.append(f_act)
        hist.pop(0)
        # The delayed force at the middle of the step (second order, like the
        # Drake delay line's half-sample centring): mean of f_act(t - T) and
        # f_act(t + dt - T), both on the grid.
        f_mea = 0.5 * (hist[-1 - n_delay] + hist[-n_delay]) if n_delay else f_act
        if f_mea > 0:
            f_comp = f_mea + lead * (f_mea - f_prev) / dt
            if mdc:
                f_comp += k * (s[0] - s[2])
        else:
            f_comp = 0.0
        f_prev = f_mea
        k1 = deriv(s, f_comp)
        k2 = deriv(s + 0.5 * dt * k1, f_comp)
        k3 = deriv(s + 0.5 * dt * k2, f_comp)
        k4 = deriv(s + dt * k3, f_comp)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += dt
        if f_act > 0 or f_comp != 0:
            started, quiet = True, 0.0
        elif started:
            quiet += dt
            if quiet > T + 5 / (z * w):
                return abs(s[1]) / v0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", metavar="FILE")
    ap.add_argument(
        "--tolerance",
        type=float,
        default=1e-4,
        help="CoR accuracy both must reach (the paper reports 4 digits)",
    )
    args = ap.parse_args()
    comps = ("none", "SDC", "MDC", "SDMDC")
    params = {c: table1_params(c) for c in comps}
    reference = {
        c: simulate(p.with_(time_step_s=p.step_s / 8)).metrics.cor for c, p in params.items()
    }
    drake = {}
    for c, p in params.items():
        t0 = time.perf_counter()
        cor = simulate(p).metrics.cor
        drake[c] = {
            "cor": cor,
            "error": abs(cor - reference[c]),
            "wall_s": time.perf_counter() - t0,
        }
    tol = max(args.tolerance, max(d["error"] for d in drake.values()))
    rows = []
    dt = 1e-3
    while True:
        entry = {"dt_s": dt, "runs": {}}
        for c, p in params.items():
            t0 = time.perf_counter()
            cor = plain_loop(p, dt)
            wall = time.perf_counter() - t0
            entry["runs"][c] = {"cor": cor, "error": abs(cor - reference[c]), "wall_s": wall}
        entry["max_error"] = max(r["error"] for r in entry["runs"].values())
        entry["wall_s"] = sum(r["wall_s"] for r in entry["runs"].values())
        rows.append(entry)
        print(
            f"plain loop dt {dt:.2e} s: max CoR error {entry['max_error']:.1e}, "
            f"4 runs in {entry['wall_s']:.2f} s"
        )
        if entry["max_error"] <= tol or dt < 4e-6:
            break
        dt /= 2
    t_drake = sum(d["wall_s"] for d in drake.values())
    t_plain = rows[-1]["wall_s"]
    max_err = max(d["error"] for d in drake.values())
    print(f"Drake (default step): max CoR error {max_err:.1e}, 4 runs in {t_drake:.2f} s")
    print(f"accuracy both reach: {tol:.1e}")
    print(f"ratio plain-loop time / Drake time at the same accuracy: {t_plain / t_drake:.2f}")
    result = {
        "tolerance": tol,
        "reference_cor": reference,
        "drake": drake,
        "drake_wall_s": t_drake,
        "plain_loop": rows,
        "plain_wall_s_at_same_accuracy": t_plain,
        "ratio_plain_over_drake": t_plain / t_drake,
    }
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)


if __name__ == "__main__":
    main()
