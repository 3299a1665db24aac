"""Stability margins of the rig a model file describes, against the nominal rig's.

A model file (``hybridtable-model/1``: what ``hybridtable diagnose --save-model`` writes and
``hybridtable margins --model`` reads) holds a rig's nominal parameters and its effects.
Without --model the script makes one from the runs of --runs with the effects of --add, given,
not fitted (the file ``hybridtable compare examples/nominal --add ADD --save-model`` writes).
Per compensator, the sampled linear loop of the nominal rig and of the model (lead time kept):
critical sensor delay per table frequency, critical table frequency and CoR at the rig's point.
Writes ``report.md`` (and ``model.json`` when it makes the model) into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

NAME = Path(__file__).stem
EXAMPLE_RUNS = Path(__file__).resolve().parents[1] / "examples" / "nominal"
ADD = "contact_damping:damping_n_s_per_m=300"
ALL = "none,SDC,MDC,SDMDC"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    p.add_argument("--model", metavar="FILE.json", help="None: make one of --runs and --add")
    p.add_argument("--runs", default=str(EXAMPLE_RUNS), help="runs to make the model of")
    p.add_argument("--add", nargs="+", default=[ADD], metavar="EFFECT:p=v", help="SI values")
    p.add_argument("--compensator", default=ALL, help="comma-separated (--quick: none,SDMDC)")
    p.add_argument("--max-delay-s", type=float, default=0.02, help="grid's largest delay [s]")
    p.add_argument("--quick", action="store_true", help="2 ms x 5 tables instead of 1 ms x 13")
    p.add_argument("--out", default=f"out/analysis/{NAME}", help="output folder")
    p.add_argument("--force", action="store_true", help="replace existing output files")
    args = p.parse_args(argv)
    out = Path(args.out)
    files = ["report.md"] if args.model else ["report.md", "model.json"]
    if not args.force and any((out / f).exists() for f in files):
        print(f"{NAME}: {out} holds {' or '.join(files)}; give --force to replace", file=sys.stderr)
        return 2

    import numpy as np

    from hybridtable.diagnosis import load_model
    from hybridtable.diagnosis.add_effect import model_with_effects
    from hybridtable.effects.registry import parse_effect_specs
    from hybridtable.measurement.rig import rig_params
    from hybridtable.measurement.run_reader import read_runs
    from hybridtable.sweeps.margins_grid import sweep_margins

    model_path = Path(args.model) if args.model else out / "model.json"
    if not args.model:  # the model file `compare --add ... --save-model` writes
        made = model_with_effects(read_runs([args.runs]), parse_effect_specs(args.add))
        out.mkdir(parents=True, exist_ok=True)
        model_path.write_text(json.dumps(made.to_json(), indent=2) + "\n")
    model = load_model(model_path)  # as `hybridtable margins --model` reads it
    base = rig_params(model.nominal, f"{model_path}: nominal")
    op_delay_s, op_table_hz = base.sensor_delay_s, base.table_response_hz
    step_s = (base.sample_period_s or 0.001) * (2 if args.quick else 1)
    delays_s = np.union1d(np.arange(0, round(args.max_delay_s / step_s) + 1) * step_s, [op_delay_s])
    tables_hz = np.union1d(np.geomspace(5.0, 200.0, 4 if args.quick else 12), [op_table_hz])
    i_op = int(np.argmin(abs(delays_s - op_delay_s)))  # the rig's operating point on the grid
    j_op = int(np.argmin(abs(tables_hz - op_table_hz)))
    quick_default = args.quick and args.compensator == ALL
    comps = ("none,SDMDC" if quick_default else args.compensator).split(",")
    nominal = sweep_margins(base, delays_s, tables_hz, comps).compensators
    modelled = sweep_margins(base, delays_s, tables_hz, comps, model=model).compensators
    rigs = {"nominal": nominal, "model": modelled}

    def ms(x_s: float) -> str:  # a critical delay [s] as text [ms]
        return "> 0.25 contact period" if math.isinf(x_s) else f"{x_s * 1e3:.3g}"

    def hz(x_hz: float) -> str:  # a critical table frequency as text [Hz]
        return "none fast enough" if math.isinf(x_hz) else "any" if x_hz == 0 else f"{x_hz:.3g}"

    best = max(comps, key=lambda c: modelled[c].critical_delay_s[j_op])
    crit_ms = {rig: ms(sw[best].critical_delay_s[j_op]) for rig, sw in rigs.items()}
    stable = {rig: [c for c in comps if sw[c].stable[i_op, j_op]] for rig, sw in rigs.items()}
    verdict = (
        f"With its model ({model.describe()}), the rig is stable below {crit_ms['model']} ms of "
        f"sensor delay with {best} at its {op_table_hz:g} Hz table (nominal rig: below "
        f"{crit_ms['nominal']} ms) and at its {op_delay_s * 1e3:g} ms delay with "
        f"{', '.join(stable['model']) or 'none of them'} (nominal rig: "
        f"{', '.join(stable['nominal']) or 'none of them'})"
    )
    rows = [
        f"| compensator: nominal rig -> model | critical delay at {op_table_hz:g} Hz [ms] | critical table at "
        f"{op_delay_s * 1e3:g} ms [Hz] | predicted CoR at ({op_delay_s * 1e3:g} ms, {op_table_hz:g} Hz) |",
        "|---|---|---|---|",
    ]
    for c in comps:
        n, m = nominal[c], modelled[c]
        rows.append(
            f"| {c} | {ms(n.critical_delay_s[j_op])} -> {ms(m.critical_delay_s[j_op])} | "
            f"{hz(n.critical_table_hz[i_op])} -> {hz(m.critical_table_hz[i_op])} | "
            f"{n.predicted_cor[i_op, j_op]:.4f} -> {m.predicted_cor[i_op, j_op]:.4f} |"
        )

    def contradicts(
        sw: dict, c: str
    ) -> bool:  # stable at the operating point, no table fast enough
        return sw[c].stable[i_op, j_op] and math.isinf(sw[c].critical_table_hz[i_op])

    odd = [c for c in comps if contradicts(nominal, c) or contradicts(modelled, c)]
    note = (
        f"{', '.join(odd)}: stable at the operating point, yet no critical table frequency: "
        "the search (`critical_table_frequency`) starts at half the sample rate, where this sampled "
        "loop is unstable, and gives up there."
    )
    print(verdict)
    print("\n".join(rows))

    left_out = model.linear_params(base.with_(sample_rate_hz=None))[1]
    md = [f"# {NAME}", "", verdict + ".", ""]
    md += [
        f"Model file: `{model_path}` ({model.source}, {len(model.runs)} runs): {model.describe()}.",
        f"Rig: m = {base.spacecraft_mass_kg:.4g} kg, k = {base.contact_stiffness_n_per_m:g} N/m "
        f"(contact {base.contact_frequency_hz:.3g} Hz), table {op_table_hz:g} Hz / "
        f"{base.table_damping_ratio:g}, sensor delay {op_delay_s * 1e3:g} ms, lead time "
        f"{base.lead_time_s * 1e3:g} ms (fixed: it does not follow the delay), sampled at "
        f"{base.sample_rate_hz:g} Hz. Left out of the linear model: {'; '.join(left_out) or 'nothing'}.",
        "",
        "Critical sensor delay: the smallest unstable one (0: unstable at zero delay); critical "
        "table frequency: stable above it.",
        "",
        *rows,
        "",
        *([note, ""] if odd else []),
        "## Critical sensor delay per table frequency [ms], nominal rig -> model",
        "",
        "| table [Hz] | " + " | ".join(comps) + " |",
        "|---|" + "---|" * len(comps),
    ]
    for j, f_hz in enumerate(tables_hz):
        crit = [
            f"{ms(nominal[c].critical_delay_s[j])} -> {ms(modelled[c].critical_delay_s[j])}"
            for c in comps
        ]
        md.append(f"| {f_hz:.4g} | " + " | ".join(crit) + " |")
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.md").write_text("\n".join(md) + "\n")
    print(f"wrote {', '.join(str(out / f) for f in files)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
