"""Numeric parameters in the Drake Context against numbers in the primitives.

Drake's idiom for "one diagram, many parameter sets" is a system whose
numbers are Context parameters: build once, then per set
``CreateDefaultContext``, set the parameters, simulate. The loop's
spacecraft and table are ``LinearSystem`` s, whose matrices are constructor
numbers, so a new mass or table response is a new diagram. This script
measures both ways on the paper's Table 1 point (SDMDC, continuous rig
computer), over parameter sets that change the spacecraft's mass and the
table's response, alternating A and B:

- A, the library: ``build_hybrid_loop`` per set (``LinearSystem`` s), simulate;
- B, built once: the spacecraft and the table as ``SymbolicVectorSystem`` s
  whose mass, omega and zeta are Context numeric parameters; per set a new
  context with the parameters set, simulate.

Both run the same Runge-Kutta 3 (accuracy 1e-8, the loop's step bound) to
the same horizon, and the script checks that their final states agree. It
prints the per-run medians, the build time of A, and B / A. On the 2-core
machine (2026-11-27, 7 sets x 3 rounds, quiet): A 200.8 ms a run (build
4.7 ms), B 246.9 ms: B / A = 1.23, the simulator's cost per step of the
symbolic systems (1.2x) and 4 % more steps (the error control sees other
round-off near the contact's switch: final states differ by up to 6e-6).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
from pydrake.symbolic import MakeVectorVariable
from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
from pydrake.systems.primitives import SymbolicVectorSystem

import hybridtable.loop.builder as loop_builder
from hybridtable._components import Block
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.studies.paper import table1_params
from hybridtable.systems.spacecraft import Spacecraft
from hybridtable.systems.table import SecondOrderTable

HORIZON_S = 0.7


class ParameterSpacecraft(Spacecraft):
    """The continuous spacecraft, its mass a Context parameter."""

    def _add(self, builder, name):
        x, f, m = MakeVectorVariable(2, "x"), MakeVectorVariable(1, "f"), MakeVectorVariable(1, "m")
        system = SymbolicVectorSystem(
            state=x, input=f, parameter=m, dynamics=[x[1], -f[0] / m[0]], output=[x[0], x[1]]
        )
        inner = builder.AddNamedSystem(name, system)
        return Block(
            self, {"force": [inner.get_input_port()]}, {"state": inner.get_output_port()}, inner
        )


class ParameterTable(SecondOrderTable):
    """The second-order table, its omega and zeta Context parameters."""

    def _add(self, builder, name):
        x, u = MakeVectorVariable(2, "x"), MakeVectorVariable(2, "u")
        w, z = MakeVectorVariable(2, "theta")
        a = w * w * (u[0] - x[0]) - 2.0 * z * w * x[1]
        system = SymbolicVectorSystem(
            state=x, input=u, parameter=[w, z], dynamics=[x[1], a], output=[x[0], x[1], a]
        )
        inner = builder.AddNamedSystem(name, system)
        return Block(
            self,
            {"commanded_state": [inner.get_input_port()]},
            {"motion": inner.get_output_port()},
            inner,
        )


def _simulate(loop, context) -> tuple[np.ndarray, float]:
    simulator = Simulator(loop.diagram, context)
    loop.set_initial_conditions(simulator.get_mutable_context())
    ResetIntegratorFromFlags(simulator, "runge_kutta3", loop.computer_period_s)
    integ = simulator.get_mutable_integrator()
    integ.set_maximum_step_size(loop.computer_period_s)
    integ.set_target_accuracy(1e-8)
    simulator.Initialize()
    simulator.AdvanceTo(HORIZON_S)
    state = simulator.get_context().get_continuous_state_vector().CopyToVector()
    return state, simulator.get_num_steps_taken()


def _sets(n: int):
    base = table1_params("SDMDC")
    for i in range(n):
        s = i / max(n - 1, 1)
        yield base.with_(
            spacecraft_mass_kg=base.spacecraft_mass_kg * (0.9 + 0.2 * s),
            table_response_hz=20.0 + 10.0 * s,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=7, help="parameter sets (default 7)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds over the sets (default 3)")
    parser.add_argument("--json", metavar="FILE", help="write the figures as JSON")
    args = parser.parse_args()
    sets = list(_sets(args.sets))

    # B: one diagram, its numbers in the Context.
    plain = loop_builder.Spacecraft
    loop_builder.Spacecraft = ParameterSpacecraft
    try:
        shared = build_hybrid_loop(sets[0], table=ParameterTable(sets[0].plant.table))
    finally:
        loop_builder.Spacecraft = plain
    craft = shared.spacecraft.state_system
    table = shared.table.state_system

    times: dict[str, list[float]] = {"A": [], "B": [], "build": []}
    worst = 0.0
    counted: dict[str, list[int]] = {"A": [], "B": []}
    for _ in range(args.rounds):
        for p in sets:
            t0 = time.perf_counter()
            loop = build_hybrid_loop(p)
            t1 = time.perf_counter()
            x_a, n_a = _simulate(loop, loop.diagram.CreateDefaultContext())
            t2 = time.perf_counter()
            times["build"].append(t1 - t0)
            times["A"].append(t2 - t0)

            t0 = time.perf_counter()
            context = shared.diagram.CreateDefaultContext()
            craft.GetMyMutableContextFromRoot(context).get_mutable_numeric_parameter(
                0
            ).SetFromVector([p.spacecraft_mass_kg])
            omega = p.plant.table.omega_rad_per_s
            table.GetMyMutableContextFromRoot(context).get_mutable_numeric_parameter(
                0
            ).SetFromVector([omega, p.table_damping_ratio])
            shared.params = p  # its initial conditions
            x_b, n_b = _simulate(shared, context)
            times["B"].append(time.perf_counter() - t0)
            worst = max(worst, float(np.max(np.abs(x_a - x_b))))
            counted["A"].append(n_a)
            counted["B"].append(n_b)

    med = {k: statistics.median(v) for k, v in times.items()}
    steps = {k: statistics.median(v) for k, v in counted.items()}
    figures = {
        "sets": args.sets,
        "rounds": args.rounds,
        "steps_per_run": steps,
        "median_run_s": {"A_rebuild_per_set": med["A"], "B_built_once": med["B"]},
        "median_build_s": med["build"],
        "B_over_A": med["B"] / med["A"],
        "us_per_step": {
            "A": 1e6 * (med["A"] - med["build"]) / steps["A"],
            "B": 1e6 * med["B"] / steps["B"],
        },
        "largest_state_difference": worst,
    }
    print(
        f"A (build per set, LinearSystems): {1e3 * med['A']:.1f} ms a run "
        f"(of which build {1e3 * med['build']:.1f} ms); "
        f"B (built once, Context parameters): {1e3 * med['B']:.1f} ms a run; "
        f"B / A = {figures['B_over_A']:.2f}; median steps {steps['A']:.0f} / {steps['B']:.0f}, "
        f"{figures['us_per_step']['A']:.1f} / {figures['us_per_step']['B']:.1f} us a step; "
        f"largest state difference {worst:.2g}"
    )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(figures, fh, indent=2)


if __name__ == "__main__":
    main()
