"""Critical sensor delay of the Table 1 rig against the contact damping ratio, per compensator.

The paper's Table 1 rig (25 Hz table, lead time = sensor delay) with a contact damping ratio
c / (2 sqrt(k m)) from 0 to --max-damping-ratio: for each compensator, the smallest sensor
delay at which the Drake-linearized loop (Pade delay) is unstable, searched up to a quarter
contact period. Reference: an ideal table without compensation, whose critical delay is
atan(c w / k) / w in closed form.
Writes ``critical_delay_vs_damping.png``, ``.csv`` and ``report.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

NAME = Path(__file__).stem
FILES = (f"{NAME}.png", f"{NAME}.csv", "report.md")
ALL = "none,SDC,MDC,SDMDC"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    p.add_argument("--compensator", default=ALL, help="comma-separated (--quick: none,SDMDC)")
    p.add_argument("--max-damping-ratio", type=float, default=0.3, help="largest ratio [1]")
    p.add_argument("--table-response-hz", type=float, default=25.0, help="Table 1's [Hz]")
    p.add_argument("--quick", action="store_true", help="7 damping ratios instead of 31")
    p.add_argument("--out", default=f"out/analysis/{NAME}", help="output folder")
    p.add_argument("--force", action="store_true", help="replace existing output files")
    args = p.parse_args(argv)
    out = Path(args.out)
    if not args.force and any((out / f).exists() for f in FILES):
        print(f"{NAME}: {out} holds {' or '.join(FILES)}; give --force to replace", file=sys.stderr)
        return 2

    import matplotlib.pyplot as plt
    import numpy as np

    from hybridtable.analysis import ContactLoopLinearizer, critical_sensor_delay, growth_of
    from hybridtable.studies.paper import table1_params

    quick_default = args.quick and args.compensator == ALL
    comps = ("none,SDMDC" if quick_default else args.compensator).split(",")
    damping_ratios = np.linspace(0.0, args.max_damping_ratio, 7 if args.quick else 31)
    growth = growth_of(ContactLoopLinearizer(pade_order=3).open_loop)
    rig = {c: table1_params(c).with_(table_response_hz=args.table_response_hz) for c in comps}
    rig["ideal table, none"] = table1_params("none").with_(table_response_hz=math.inf)
    search_s = 0.25 / rig[comps[0]].contact_frequency_hz  # the searches' default limit
    critical_s = {
        name: np.array(
            [critical_sensor_delay(growth, q.with_contact_damping_ratio(z)) for z in damping_ratios]
        )
        for name, q in rig.items()
    }

    def ms(x_s: float) -> str:  # a critical delay [s] as text [ms]
        if x_s == 0 or math.isinf(x_s):
            return "0" if x_s == 0 else f"> {search_s * 1e3:g}"
        return f"{x_s * 1e3:.3g}"

    top_ratio, table1_delay_s = damping_ratios[-1], rig[comps[0]].sensor_delay_s
    table1_delay_ms = table1_delay_s * 1e3
    order = sorted(comps, key=lambda c: -critical_s[c][-1])
    need = {
        c: damping_ratios[np.argmax(critical_s[c] > table1_delay_s)]
        for c in comps
        if (critical_s[c] > table1_delay_s).any()
    }
    verdict = f"At contact damping ratio {top_ratio:g}, {order[0]} keeps the Table 1 rig stable "
    verdict += f"up to {ms(critical_s[order[0]][-1])} ms of sensor delay"
    verdict += "".join(f", {c} up to {ms(critical_s[c][-1])} ms" for c in order[1:])
    if damping_ratios[0] == 0 and all(critical_s[c][0] == 0 for c in comps):
        verdict += "; an undamped contact (ratio 0) is stable at no delay (marginal at best)"
    header = ["damping ratio [1]", *(f"{name} [ms]" for name in critical_s)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += [
        f"| {z:.3g} | " + " | ".join(ms(v[i]) for v in critical_s.values()) + " |"
        for i, z in enumerate(damping_ratios)
    ]
    print(verdict)
    print("\n".join(lines[:2] + lines[2 :: max(1, len(damping_ratios) // 6)]))  # about 6 rows

    out.mkdir(parents=True, exist_ok=True)
    csv = [
        "contact_damping_ratio,"
        + ",".join(f"critical_delay_s_{n.replace(', ', '_').replace(' ', '_')}" for n in critical_s)
    ]
    csv += [
        f"{z:.6g}," + ",".join(f"{v[i]:.9g}" for v in critical_s.values())
        for i, z in enumerate(damping_ratios)
    ]
    (out / f"{NAME}.csv").write_text("\n".join(csv) + "\n")

    fig, ax = plt.subplots(figsize=(7.5, 5))
    for name, crit in critical_s.items():
        finite = np.isfinite(crit)
        style = dict(color="0.4", ls="--") if name.startswith("ideal") else {}
        if finite.any():
            ax.plot(
                damping_ratios[finite], crit[finite] * 1e3, marker="o", ms=3, label=name, **style
            )
        if not finite.all():
            ax.plot(
                damping_ratios[~finite], np.full((~finite).sum(), search_s * 1e3), "^", color="k"
            )
    ax.axhline(table1_delay_ms, color="0.6", lw=0.8)
    ax.text(
        top_ratio, table1_delay_ms, f"Table 1 delay {table1_delay_ms:g} ms", ha="right", va="bottom"
    )
    ax.set(xlabel="contact damping ratio [1]", ylabel="critical sensor delay [ms]")
    ax.set_title(
        f"Table 1 rig, table {args.table_response_hz:g} Hz: stable below the curve", fontsize=10
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / f"{NAME}.png", dpi=120)
    plt.close(fig)

    md = [f"# {NAME}", "", verdict + ".", ""]
    md += [
        f"- {c} is stable at the Table 1 delay ({table1_delay_ms:g} ms) from damping ratio {r:.3g} on (grid)"
        for c, r in need.items()
    ]
    md += [
        "",
        f"Critical sensor delay [ms]: the smallest delay with an unstable linear loop (0: unstable "
        f"at zero delay; '> {search_s * 1e3:g}': stable up to the search's quarter contact period).",
        "",
        *lines,
        "",
        f"![Critical sensor delay against contact damping ratio]({NAME}.png)",
        "*Critical sensor delay [ms] against contact damping ratio [1] per compensator; dashed: an "
        "ideal table without compensation; grey line: the Table 1 delay; triangles: stable over the "
        "whole search.*",
        "",
    ]
    (out / "report.md").write_text("\n".join(md))
    print(f"wrote {', '.join(str(out / f) for f in FILES)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
