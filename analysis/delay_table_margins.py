"""Stability margins of the paper's Table 1 rig over sensor delay x table response frequency.

Per compensator, the in-contact loop linearized by Drake (Pade delay, SDC lead = delay) on a
grid: growth rate (largest closed-loop pole real part), phase margin at the contact crossover,
stable or not, the critical sensor delay per table frequency and table frequency per delay
(the stability boundary), python-control's margins at the Table 1 point (5 ms, 25 Hz). The
paper's undamped contact is marginal at every delay (no boundary): the default contact
damping ratio 0.05 gives the map one. Writes ``report.md`` and ``margins_map.png`` to --out.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

NAME = Path(__file__).stem
FILES = ("report.md", "margins_map.png")
ALL = "none,SDC,MDC,SDMDC"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    p.add_argument("--compensator", default=ALL, help="comma-separated (--quick: none,SDMDC)")
    p.add_argument("--contact-damping-ratio", type=float, default=0.05, help="0: the paper's [1]")
    p.add_argument("--max-delay-s", type=float, default=0.02, help="grid's largest delay [s]")
    p.add_argument("--max-table-hz", type=float, default=200.0, help="grid's fastest table [Hz]")
    p.add_argument("--quick", action="store_true", help="an 11 x 10 grid instead of 41 x 40")
    p.add_argument("--out", default=f"out/analysis/{NAME}", help="output folder")
    p.add_argument("--force", action="store_true", help="replace existing output files")
    args = p.parse_args(argv)
    out = Path(args.out)
    if not args.force and any((out / f).exists() for f in FILES):
        print(f"{NAME}: {out} holds {' or '.join(FILES)}; give --force to replace", file=sys.stderr)
        return 2

    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.colors import TwoSlopeNorm

    from hybridtable.reports.margin_point import point_margins, point_markdown
    from hybridtable.studies.paper import table1_params
    from hybridtable.sweeps.margins_grid import sweep_margins

    quick_default = args.quick and args.compensator == ALL
    comps = ("none,SDMDC" if quick_default else args.compensator).split(",")
    base = table1_params("none").with_contact_damping_ratio(args.contact_damping_ratio)
    op_delay_s, op_table_hz = base.sensor_delay_s, base.table_response_hz
    delays_s = np.linspace(0.0, args.max_delay_s, 11 if args.quick else 41)
    delays_ms = delays_s * 1e3
    tables_hz = np.linspace(5.0, args.max_table_hz, 10 if args.quick else 40)
    result = sweep_margins(base, delays_s, tables_hz, comps)
    point = point_margins(base, comps, op_delay_s, op_table_hz)  # python-control's margins
    crit_s, search_s = point.critical_delay_s, point.max_delay_s

    def ms(x_s: float) -> str:  # a critical delay [s] as text [ms]
        if x_s == 0 or math.isinf(x_s):
            return "never" if x_s == 0 else f"> {search_s * 1e3:g}"
        return f"{x_s * 1e3:.3g}"

    rig = f"the Table 1 rig (contact damping ratio {args.contact_damping_ratio:g})"
    stable = sorted((c for c in comps if crit_s[c] > 0), key=lambda c: -crit_s[c])
    never = [c for c in comps if crit_s[c] == 0]
    verdict = f"No compensator keeps {rig} stable at {op_table_hz:g} Hz at any sensor delay"
    if stable:
        best, others = stable[0], "".join(f", {c} up to {ms(crit_s[c])} ms" for c in stable[1:])
        verdict = f"{best} keeps {rig} stable up to {ms(crit_s[best])} ms of sensor delay at "
        verdict += f"{op_table_hz:g} Hz{others}"
        verdict += f"; {', '.join(never)} unstable at any delay" if never else ""
    rows = [
        f"| compensator | critical delay at {op_table_hz:g} Hz [ms] | at Table 1: phase margin [deg] "
        "| delay margin [ms] | stable grid points |",
        "|---|---|---|---|---|",
    ]
    for c, cs in result.compensators.items():
        g = point.robust[c]  # python-control's stability_margins of L = -G
        rows.append(
            f"| {c} | {ms(crit_s[c])} | {g.phase_margin_deg:+.3g} | {g.delay_margin_s * 1e3:+.3g} | "
            f"{cs.stable.sum()}/{cs.stable.size} |"
        )
    print(verdict)
    print("\n".join(rows))

    fig, axes = plt.subplots(2, len(comps), figsize=(4.3 * len(comps), 7.5), squeeze=False)
    maps = [
        ("growth_rate_per_s", "growth rate [1/s]", "RdBu_r"),
        ("phase_margin_deg", "phase margin [deg]", "RdBu"),
    ]
    for k, c in enumerate(comps):
        cs = result.compensators[c]
        in_grid = (cs.critical_delay_s > 0) & (cs.critical_delay_s <= delays_s[-1])
        edge_ms = np.where(in_grid, cs.critical_delay_s * 1e3, np.nan)  # the library's searches
        in_grid_hz = (cs.critical_table_hz >= tables_hz[0]) & (
            cs.critical_table_hz <= tables_hz[-1]
        )
        edge_hz = np.where(in_grid_hz, cs.critical_table_hz, np.nan)
        for row, (field, label, cmap) in enumerate(maps):
            ax, z = axes[row][k], getattr(cs, field)
            norm = TwoSlopeNorm(0.0, min(np.nanmin(z), -1e-6), max(np.nanmax(z), 1e-6))
            mesh = ax.pcolormesh(tables_hz, delays_ms, z, cmap=cmap, norm=norm, shading="nearest")
            fig.colorbar(mesh, ax=ax, label=label)
            if in_grid.any():
                ax.plot(tables_hz, edge_ms, "k-", lw=2, label="critical sensor delay")
            if in_grid_hz.any():
                ax.plot(edge_hz, delays_ms, "k--", lw=1.5, label="critical table frequency")
            ax.plot(op_table_hz, op_delay_s * 1e3, "*", mfc="gold", mec="k", ms=12, label="Table 1")
            ax.set(xlabel="table response frequency [Hz]", ylabel="sensor delay [ms]")
            ax.set_title(f"{c}: {label} ({cs.stable.sum()}/{cs.stable.size} stable)", fontsize=9)
            ax.legend(fontsize=7, loc="upper right")
    out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out / "margins_map.png", dpi=110)
    plt.close(fig)
    b = result.base
    md = [f"# {NAME}", "", verdict + ".", "", *rows, ""]
    md += [
        f"Rig: the paper's Table 1 (contact {b.contact_stiffness_n_per_m:g} N/m at "
        f"{b.contact_frequency_hz:g} Hz, table damping ratio {b.table_damping_ratio:g}) with a contact "
        f"damping of {b.contact_damping_n_s_per_m:.4g} N s/m; lead time = sensor delay; continuous "
        f"model, Pade order {result.pade_order}. Critical delays searched up to {search_s * 1e3:g} ms "
        "('never': unstable at zero delay).",
        "",
        *point_markdown(point),
        "## Critical sensor delay per table frequency [ms]",
        "",
        "| table [Hz] | " + " | ".join(comps) + " |",
        "|---|" + "---|" * len(comps),
    ]
    for j, f_hz in enumerate(tables_hz):
        crit = [ms(result.compensators[c].critical_delay_s[j]) for c in comps]
        md.append(f"| {f_hz:.4g} | " + " | ".join(crit) + " |")
    md += [
        "",
        "![Growth rate and phase margin maps](margins_map.png)",
        "*Top: growth rate [1/s] (largest closed-loop pole real part; blue: stable); bottom: phase "
        "margin [deg] at the contact crossover; over table response frequency [Hz] and sensor delay "
        "[ms]. The stability boundary where it lies in the grid: black line, the critical sensor "
        "delay per table frequency; dashed, the critical table frequency per delay; star: Table 1.*",
        "",
    ]
    (out / "report.md").write_text("\n".join(md))
    print(f"wrote {out / 'report.md'} and {out / 'margins_map.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
