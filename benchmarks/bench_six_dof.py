"""Benchmark: real-time factor of the 6-DoF docking loop, Stewart plant vs table model.

The 6-DoF loop (rigid spacecraft, F/T sensor delay, wrench compensator at
1 kHz) runs the paper's Table 1 point on axis (2533 kg, 1e5 N/m, 0.1 m/s,
5 ms) over a fixed horizon that includes the whole contact, with the table
back-end either the Stewart platform (MultibodyPlant at the 1 ms tick, full-pose
inverse kinematics, leg servo, payload-compensated F/T sensor) or the table
model (25 Hz, 0.8, Drake's contact of the devices), for: no compensation, and
SDMDC with the 6x6 stiffness given (the docked pose's, a constant) or
linearized at the table's pose at every tick of the contact, and (table
model) sdmdc-online, whose identifier evaluates the contact model once more
per tick of contact.

Reported per case: the real-time factor (simulated time / wall time of the
simulation, the diagram built beforehand, median of ``--repeat`` runs; and
simulated time / process CPU time, which other jobs on the machine do not
inflate) and the CoR; then the cost of one linearized stiffness per tick of
contact (closed form from one contact evaluation), against one contact wrench
and against the twelve wrenches of central differences it replaced, and how
far the closed form is from those central differences (largest difference /
largest entry) at offset, tilted, moving poses with damping and friction.

Target: real-time factor >= 2 on a 2-core machine.

Usage: python benchmarks/bench_six_dof.py [--json FILE] [--repeat N] [--horizon-s T]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time

import numpy as np

from hybridtable.six_dof.builder import build_docking_loop
from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.params import (
    ApproachParams,
    DockingContactParams,
    DockingLoopParams,
    RigidBodyParams,
)
from hybridtable.six_dof.simulation import simulate6

#: (label, table back-end, compensator, stiffness model)
CASES = (
    ("stewart none", "stewart", "none", "linearized"),
    ("stewart SDMDC given", "stewart", "SDMDC", "given"),
    ("stewart SDMDC linearized", "stewart", "SDMDC", "linearized"),
    ("model none", "model", "none", "linearized"),
    ("model SDMDC given", "model", "SDMDC", "given"),
    ("model SDMDC linearized", "model", "SDMDC", "linearized"),
    ("model sdmdc-online", "model", "sdmdc-online", "linearized"),
)


def table1_docking(table: str, compensator: str, stiffness_model: str, horizon_s: float):
    """The Table 1 point on a 6-DoF rig (on axis)."""
    mass = 1e5 / (2.0 * math.pi) ** 2
    contact = DockingContactParams(1e5)
    base = DockingLoopParams(
        spacecraft=RigidBodyParams(mass, (1689.0, 1689.0, 1689.0), 1.5),
        contact=contact,
        approach=ApproachParams(0.1, 0.001),
        sample_rate_hz=1000.0,
        sensor_delay_s=0.005,
        duration_s=horizon_s,
    )
    K = DockingContact(contact).stiffness(base.nominal_pose())[0]
    return base.with_(
        table=table,
        table_response_hz=25.0 if table == "model" else math.inf,
        compensator=compensator,
        stiffness_model=stiffness_model,
        compensator_stiffness_matrix=K if stiffness_model == "given" else None,
    )


def closed_form_agreement(poses: int = 20) -> tuple[float, float]:
    """The worst relative difference of the closed-form K and C from central
    differences of the contact wrench, at random offset, tilted, moving poses of
    a damped contact with friction (sliding above the stiction tolerance)."""
    contact = DockingContact(
        DockingContactParams(1e5, contact_dissipation_s_per_m=0.5, friction_coefficient=0.3)
    )
    rng = np.random.default_rng(5)
    worst = [0.0, 0.0]
    step = 1e-7
    for _ in range(poses):
        q = np.concatenate(
            [rng.uniform(-0.05, 0.05, 2), [rng.uniform(0.002, 0.02)], rng.uniform(-0.2, 0.2, 3)]
        )
        qd = rng.uniform(-0.1, 0.1, 6)
        K, C = contact.stiffness(q, qd)
        for i, (closed, vary) in enumerate(((K, 0), (C, 1))):
            numeric = np.zeros((6, 6))
            for j in range(6):
                e = np.zeros(6)
                e[j] = step
                args_plus = (q + e, qd) if vary == 0 else (q, qd + e)
                args_minus = (q - e, qd) if vary == 0 else (q, qd - e)
                numeric[:, j] = -(contact.wrench(*args_plus) - contact.wrench(*args_minus)) / (
                    2.0 * step
                )
            worst[i] = max(worst[i], float(np.abs(closed - numeric).max() / np.abs(numeric).max()))
    return worst[0], worst[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", metavar="FILE", help="write the figures as JSON")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--horizon-s", type=float, default=1.0, help="simulated time per run")
    args = parser.parse_args()

    print(
        f"6-DoF loop, Table 1 point on axis, 1 kHz, {args.horizon_s:g} s; cores: {os.cpu_count()}"
    )
    figures = {"cpu_count": os.cpu_count(), "horizon_s": args.horizon_s, "runs": {}}
    for label, table, compensator, stiffness_model in CASES:
        params = table1_docking(table, compensator, stiffness_model, args.horizon_s)
        rtf, rtf_cpu, build = [], [], []
        cor = None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            loop = build_docking_loop(params)
            build.append(time.perf_counter() - t0)
            t0, c0 = time.perf_counter(), time.process_time()
            run = simulate6(params, loop=loop)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            simulated = float(run.time_s[-1])
            rtf.append(simulated / wall)
            rtf_cpu.append(simulated / cpu)
            cor = run.metrics.cor_normal
        row = {
            "real_time_factor": statistics.median(rtf),
            "real_time_factor_cpu": statistics.median(rtf_cpu),
            "build_s": statistics.median(build),
            "cor_normal": cor,
        }
        figures["runs"][label] = row
        print(
            f"{label:26s} real-time factor {row['real_time_factor']:5.2f} (CPU "
            f"{row['real_time_factor_cpu']:5.2f})  CoR {cor:.5f}  build {row['build_s']:.2f} s"
        )

    # The linearized stiffness: its cost per tick of contact.
    params = table1_docking("model", "SDMDC", "linearized", args.horizon_s)
    contact = DockingContact(params.contact)
    q = params.nominal_pose()
    n = 200
    contact.stiffness(q, np.zeros(6))  # compiled before it is timed
    t0 = time.perf_counter()
    for _ in range(n):
        contact.stiffness(q, np.zeros(6))
    k_ms = (time.perf_counter() - t0) / n * 1e3
    t0 = time.perf_counter()
    for _ in range(n):
        contact.wrench(q, np.zeros(6))
    w_ms = (time.perf_counter() - t0) / n * 1e3
    figures["linearized_stiffness_ms"] = k_ms
    figures["contact_wrench_ms"] = w_ms
    print(
        f"linearized K: {k_ms:.3f} ms per tick of contact in closed form (one contact "
        f"wrench {w_ms:.3f} ms; central differences take 12: {12 * w_ms:.2f} ms), "
        f"against a 1 ms tick"
    )
    figures["closed_form_vs_central_differences"] = worst = closed_form_agreement()
    print(
        f"closed form against central differences (step 1e-7), largest difference / "
        f"largest entry over 20 poses: K {worst[0]:.1e}, C {worst[1]:.1e}"
    )
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(figures, fh, indent=2)


if __name__ == "__main__":
    main()
