"""The paper's hybrid loop at its Table 1 point, once per compensator.

1. For each compensator, a new DiagramBuilder gets the loop (`add_hybrid_loop`).
2. A pydrake Simulator runs it from the approach (`set_initial_conditions`)
   for one contact period, through the contact.
3. `collect_result` reads the run back from the loop's log (CoR, peak force).
4. Prints a verdict, then each CoR beside the paper's Table 1 CoR.
5. Writes `--out`/velocity.png (the spacecraft model's velocity in each run)
   and `--out`/cor.csv (the table printed).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib.pyplot as plt
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import hybridtable
from hybridtable.studies import paper


def run_table1(compensator: str) -> hybridtable.SimulationResult:
    """One Table 1 run in its own diagram, simulated through the contact."""
    params = paper.table1_params(compensator)
    builder = DiagramBuilder()
    loop = hybridtable.add_hybrid_loop(builder, params)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)  # 0.1 m/s from a 1 mm gap
    t_end_s = 1.0 / params.contact_frequency_hz  # the contact lasts about half of it
    simulator.AdvanceTo(t_end_s)
    # collect_result refuses a record that ends while a force acts.
    result = hybridtable.collect_result(loop, context, simulator.get_num_steps_taken())
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--quick", action="store_true", help="only none and SDMDC")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("out/diagrams/paper_loop"),
        help="folder for velocity.png and cor.csv",
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    figure_path, csv_path = args.out / "velocity.png", args.out / "cor.csv"
    for path in (figure_path, csv_path):
        if path.exists() and not args.force:
            parser.exit(2, f"refusing to replace {path} (give --force)\n")

    names = ("none", "SDMDC") if args.quick else hybridtable.COMPENSATORS
    paper_cor = paper.load_tables()["table1_simulation"]["cor"]
    results = {name: run_table1(name) for name in names}
    cor = {name: r.metrics.cor for name, r in results.items()}

    print(
        f"SDMDC brings the Table 1 CoR from {cor['none']:.4f} to {cor['SDMDC']:.4f} "
        f"(paper: {paper_cor['none']:.4f} to {paper_cor['SDMDC']:.4f}; ideal 1)"
    )
    rows = [(n, cor[n], paper_cor[n], results[n].metrics.peak_force_n) for n in names]
    print(f"{'compensator':<12}{'CoR':>8}{'paper':>8}{'peak force [N]':>16}")
    for name, ours, theirs, peak_n in rows:
        print(f"{name:<12}{ours:>8.4f}{theirs:>8.4f}{peak_n:>16.1f}")

    args.out.mkdir(parents=True, exist_ok=True)
    with open(csv_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["compensator", "cor", "cor_paper", "peak_force_n"])
        writer.writerows(rows)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name, r in results.items():
        ax.plot(r.time_s, r.v_des_m_per_s, label=f"{name} (CoR {cor[name]:.4f})")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("spacecraft model velocity [m/s]")
    ax.set_title("Table 1 point: k = 1e5 N/m, f_con = 1 Hz, T_fms = 5 ms, table 25 Hz")
    ax.legend()
    fig.tight_layout()
    fig.savefig(figure_path, dpi=120)
    print(f"wrote {figure_path} and {csv_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
