"""The Stewart platform (a MultibodyPlant) as the table of the Table 1 loop.

1. `check_stewart_loop` refuses a loop the platform cannot run; `tune_table`
   tunes its legs' reference model until the identified step response is the
   loop's table (25 Hz, damping ratio 0.8) and returns that identification.
2. `add_stewart_loop` adds the loop with the platform as table and its F/T
   sensor as contact to our own DiagramBuilder; a pydrake Simulator runs it.
3. The same loop with the second-order table identified from the platform,
   and with an ideal table (`add_hybrid_loop`), for comparison.
4. Prints a verdict, then the three CoRs for each compensator, and writes
   `--out`/force.png (contact force against time) and `--out`/cor.csv.
`hybridtable.stewart.run.simulate_stewart` does steps 1-3 in one call.
"""

from __future__ import annotations

import argparse
import csv
import math
from functools import partial
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import hybridtable
from hybridtable.stewart import StewartParams
from hybridtable.stewart.backend import add_stewart_loop, stewart_params_for_loop
from hybridtable.stewart.identify import tune_table
from hybridtable.stewart.run import check_stewart_loop
from hybridtable.studies import paper


def run(params: hybridtable.HybridLoopParams, add_loop=hybridtable.add_hybrid_loop):
    """Build the loop with ``add_loop`` in a new diagram and simulate it through the contact."""
    builder = DiagramBuilder()
    loop = add_loop(builder, params)
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    simulator.AdvanceTo(1.0 / params.contact_frequency_hz)  # the contact lasts about half
    # collect_result refuses a record that ends while a force acts.
    result = hybridtable.collect_result(loop, context)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--rate-hz", type=float, default=1000.0, help="rig and plant rate [Hz]")
    parser.add_argument("--quick", action="store_true", help="only none, at 500 Hz (not --rate-hz)")
    parser.add_argument(
        "--out", type=Path, default=Path("out/diagrams/stewart_loop"), help="output folder"
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    figure_path, csv_path = args.out / "force.png", args.out / "cor.csv"
    for path in (figure_path, csv_path):
        if path.exists() and not args.force:
            parser.exit(2, f"refusing to replace {path} (give --force)\n")
    names = ("none",) if args.quick else ("none", "SDC", "MDC", "SDMDC")
    rate_hz = 500.0 if args.quick else args.rate_hz
    table1 = paper.table1_params("none", sample_rate_hz=rate_hz)
    try:
        check_stewart_loop(table1)
    except hybridtable.ParameterError as err:
        parser.error(str(err))
    stewart = stewart_params_for_loop(table1, StewartParams())  # the plant steps at the rig's tick
    tuned, step = tune_table(stewart, table1.table_response_hz, table1.table_damping_ratio)
    f_hz, zeta = step.response_frequency_hz, step.damping_ratio

    rows, runs = [], {}
    for name in names:
        params = table1.with_(compensator=name)
        runs[name] = run(params, partial(add_stewart_loop, stewart=tuned))
        second = run(params.with_(table_response_hz=f_hz, table_damping_ratio=zeta))
        ideal = run(params.with_(table_response_hz=math.inf))
        runs[name, "2nd"] = second
        rows.append((name, runs[name].metrics.cor, second.metrics.cor, ideal.metrics.cor))

    name, stewart_cor, second_cor, ideal_cor = rows[0]
    print(
        f"The Stewart table (identified {f_hz:.2f} Hz, zeta {zeta:.3f}) gives {name} a CoR "
        f"of {stewart_cor:.4f}, its second-order model {second_cor:.4f} (ideal table "
        f"{ideal_cor:.4f}; {rate_hz:g} Hz rig)"
    )
    print(f"{'compensator':<12}{'Stewart':>9}{'2nd order':>11}{'ideal':>9}")
    for row in rows:
        print(f"{row[0]:<12}{row[1]:>9.4f}{row[2]:>11.4f}{row[3]:>9.4f}")

    args.out.mkdir(parents=True, exist_ok=True)
    with open(csv_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["compensator", "cor_stewart", "cor_second_order", "cor_ideal_table"])
        writer.writerows(rows)
    fig, (ax, diff) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 5.6))
    for name in names:
        stew, second = runs[name], runs[name, "2nd"]
        ax.plot(stew.time_s, stew.f_act_n, label=name)
        f_second_n = np.interp(stew.time_s, second.time_s, second.f_act_n)
        diff.plot(stew.time_s, stew.f_act_n - f_second_n, label=name)
    ax.set_ylabel("Stewart contact force [N]")
    ax.set_title(f"Table 1 point on the Stewart platform, {rate_hz:g} Hz rig")
    ax.legend(fontsize="small")
    diff.set_xlabel("time [s]")
    diff.set_ylabel("Stewart - 2nd-order model [N]")
    fig.tight_layout()
    fig.savefig(figure_path, dpi=120)
    print(f"wrote {figure_path} and {csv_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
