"""The Table 1 loop on a sampled rig computer, against the continuous one.

1. `table1_params(name, sample_rate_hz=R)`: the rig computer (spacecraft model,
   compensator, force sensor) ticks at R Hz with a zero-order-held command;
   `sample_rate_hz=None` is the paper's continuous computer.
2. Each loop is built in its own DiagramBuilder (`add_hybrid_loop`) and run by
   a pydrake Simulator for one contact period; `collect_result` gives its CoR.
3. Prints a verdict at `--rate-hz`, then the CoR of each compensator at each
   rate beside the continuous CoR.
4. Writes `--out`/cor_vs_rate.png (CoR against sample rate) and
   `--out`/cor.csv (one row a run).
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


def cor_of(compensator: str, sample_rate_hz: float | None) -> float:
    """CoR of the Table 1 loop with a rig computer at ``sample_rate_hz`` (None: continuous)."""
    params = paper.table1_params(compensator, sample_rate_hz=sample_rate_hz)
    builder = DiagramBuilder()
    loop = hybridtable.add_hybrid_loop(builder, params)
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    t_end_s = 1.0 / params.contact_frequency_hz  # the contact lasts about half of it
    simulator.AdvanceTo(t_end_s)
    # collect_result refuses a record that ends while a force acts.
    result = hybridtable.collect_result(loop, context)
    return result.metrics.cor


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--rate-hz", type=float, default=1000.0, help="rate of the verdict [Hz]")
    parser.add_argument(
        "--quick", action="store_true", help="none and SDMDC, at 500 Hz and --rate-hz"
    )
    parser.add_argument(
        "--out", type=Path, default=Path("out/diagrams/sampled_rig"), help="output folder"
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    try:  # a rate outside the plausible range: one line, exit 2
        paper.table1_params("none", sample_rate_hz=args.rate_hz)
    except hybridtable.ParameterError as err:
        parser.error(str(err))
    figure_path, csv_path = args.out / "cor_vs_rate.png", args.out / "cor.csv"
    for path in (figure_path, csv_path):
        if path.exists() and not args.force:
            parser.exit(2, f"refusing to replace {path} (give --force)\n")

    names = ("none", "SDMDC") if args.quick else hybridtable.COMPENSATORS
    rates_hz = (500.0,) if args.quick else (250.0, 500.0, 2000.0, 4000.0, 8000.0)
    rates_hz = sorted({*rates_hz, args.rate_hz})
    continuous = {name: cor_of(name, None) for name in names}
    sampled = {(name, r): cor_of(name, r) for name in names for r in rates_hz}

    at = {name: sampled[name, args.rate_hz] for name in names}
    print(
        f"At {args.rate_hz:g} Hz the sampled rig's CoR is "
        + ", ".join(f"{n} {at[n]:.4f}" for n in names)
        + " against the continuous "
        + ", ".join(f"{continuous[n]:.4f}" for n in names)
    )
    print(f"{'compensator':<12}{'continuous':>11}" + "".join(f"{r:>9g} Hz" for r in rates_hz))
    for name in names:
        cells = "".join(f"{sampled[name, r]:>12.4f}" for r in rates_hz)
        print(f"{name:<12}{continuous[name]:>11.4f}{cells}")

    args.out.mkdir(parents=True, exist_ok=True)
    with open(csv_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["compensator", "sample_rate_hz", "cor", "cor_continuous"])
        writer.writerows((n, r, sampled[n, r], continuous[n]) for n in names for r in rates_hz)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name in names:
        line = ax.semilogx(rates_hz, [sampled[name, r] for r in rates_hz], "o-", label=name)[0]
        ax.axhline(continuous[name], color=line.get_color(), ls="--", lw=0.8)
    ax.set_xticks(rates_hz, [f"{r:g}" for r in rates_hz])
    ax.set_xticks([], minor=True)
    ax.set_xlabel("rig computer sample rate [Hz]")
    ax.set_ylabel("coefficient of restitution [1]")
    ax.set_title("Table 1 point, sampled (dots) and continuous (dashed)")
    ax.legend(loc="center", bbox_to_anchor=(0.5, 0.2), ncol=4)
    fig.tight_layout()
    fig.savefig(figure_path, dpi=120)
    print(f"wrote {figure_path} and {csv_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
