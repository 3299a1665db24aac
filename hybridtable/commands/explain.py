"""``hybridtable explain TABLE.csv``: what a measured CoR table says about the rig."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run"]

#: The condition flags: (field, unit); their ranges are those of limits.LIMITS.
_CONDITIONS = (
    ("contact_stiffness_n_per_m", "N/m"),
    ("contact_frequency_hz", "Hz"),
    ("initial_velocity_m_per_s", "m/s"),
    ("sensor_delay_s", "s"),
    ("lead_time_s", "s"),
    ("table_response_hz", "Hz"),
    ("table_damping_ratio", "1"),
    ("sample_rate_hz", "Hz"),
)
#: The paper's Table 1, the default of every condition (kept here so --help needs no import).
_PAPER = {
    "contact_stiffness_n_per_m": "1e5",
    "contact_frequency_hz": "1",
    "initial_velocity_m_per_s": "0.1",
    "sensor_delay_s": "0.005",
    "lead_time_s": "the sensor delay",
    "table_response_hz": "25",
    "table_damping_ratio": "0.8",
    "sample_rate_hz": "none: a continuous rig computer",
}


def register(sub) -> None:
    from hybridtable.commands._common import integer_type, number_type
    from hybridtable.commands._model_options import add_plugin_argument

    p = sub.add_parser(
        "explain",
        help="say which loop a measured CoR table is consistent with, and what it cannot decide",
        description="Read a table of measured CoRs (CSV: a row per run or per compensator; "
        "columns compensator (none, SDC, MDC, SDMDC) and cor, optional cor_std and the "
        "conditions below, SI units; an empty cell: not stated). Fit the stated loop and "
        "every model of 1 to --max-effects effects (by default contact_damping, extra_delay, "
        "contact_frequency_error, lead_time_error, table_response, table_damping, "
        "compensator_stiffness_error, contact_damping_ratio, and the effects of installed "
        "packages and --plugin; any effect that hybridtable effects lists with --effects) by "
        "least squares in ln CoR, with the "
        "cor_std, the scatter of repeated rows or the rounding as the noise; rank them by BIC; "
        "state what the table determines (SVD of its sensitivities) and what it cannot "
        "resolve; flag the interaction of the four compensators and trends with stiffness or "
        "velocity that no model produces ('not explained by the loop model'); and name the run "
        "that would separate models that fit equally well. The console opens with one "
        "sentence; --json gives every figure. See docs/explain.md.",
    )
    p.add_argument("table", metavar="TABLE.csv", help="the measured CoR table")
    for field, unit in _CONDITIONS:
        p.add_argument(
            "--" + field.replace("_", "-"),
            dest=field,
            type=number_type(field, unit),  # the plausible range of limits.LIMITS
            metavar="VALUE",
            help=f"{field} for the rows that do not state it [{unit}] (default: "
            f"{_PAPER[field]}, the paper's Table 1)",
        )
    p.add_argument(
        "--cor-std",
        type=number_type(">0"),
        metavar="STD",
        help="the CoR's std for rows without cor_std (default: the scatter of repeated rows, "
        "else the rounding of the cor column)",
    )
    p.add_argument(
        "--model-error",
        type=number_type(">=0"),
        default=1e-3,
        metavar="LN",
        help="the loop model's own error in ln CoR, added to every row's noise (default: 0.001)",
    )
    p.add_argument(
        "--max-rows",
        type=integer_type(1, 100_000),
        default=200,
        metavar="N",
        help="the most rows of distinct conditions the table may have; each costs seconds "
        "on two cores (default: 200)",
    )
    p.add_argument(
        "--max-effects",
        type=integer_type(1, 3),
        default=3,
        metavar="N",
        help="the most effects in one model (default: 3)",
    )
    p.add_argument(
        "--effects",
        metavar="NAME[,NAME...]",
        help="the candidate effects (default: those hybridtable effects marks as explain's "
        "default, plug-ins included); an effect the fast engine cannot carry (a nonlinear "
        "law, a filter, a user's system) runs through the Drake diagram, about 0.1 s a row "
        "and evaluation",
    )
    add_plugin_argument(p)
    p.add_argument(
        "--workers",
        "--jobs",
        dest="workers",
        type=integer_type(1, 256),
        default=None,
        metavar="N",
        help="processes fitting models in parallel, 1 to 256 (default: 2, as diagnose; "
        "--jobs is its older name)",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--plot",
        metavar="FILE.png",
        help="plot each row's measured CoR [1] against the best models",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import (
        check_outputs,
        check_suffix,
        figure_suffixes,
        write_json,
    )
    from hybridtable.commands._model_options import load_plugins
    from hybridtable.effects.registry import get_effect
    from hybridtable.errors import CommandError, ParameterError
    from hybridtable.explain.explain import explain_table
    from hybridtable.explain.table import read_cor_table
    from hybridtable.reports.explain import format_explanation, plot_explanation

    check_outputs(args, [args.table], files={"--json": args.json, "--plot": args.plot})
    if args.plot:
        check_suffix("--plot", args.plot, figure_suffixes())
    defaults = {f: getattr(args, f) for f, _ in _CONDITIONS if getattr(args, f) is not None}
    table = read_cor_table(args.table, defaults)
    if args.cor_std is not None:
        table = table.with_cor_std(args.cor_std)
    effects = None
    load_plugins(args)
    if args.effects is not None:
        try:
            effects = [get_effect(n.strip()) for n in args.effects.split(",") if n.strip()]
        except ParameterError as err:
            raise CommandError(f"--effects: {err}") from None
        if not effects:
            raise CommandError("--effects: give at least one effect name (hybridtable effects)")
        for e in effects:
            if e.apply is None:
                raise CommandError(
                    f"--effects {e.name}: the effect acts on a six-axis rig only (hybridtable "
                    "effects, column loops): a CoR table is the 1-D loop's"
                )
    quiet = args.json == "-"
    bar = None
    if not args.no_progress and not quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(unit=" models", leave=False, file=sys.stderr, desc="explain")
    try:
        expl = explain_table(
            table,
            effects=effects,
            max_effects=args.max_effects,
            model_error_ln=args.model_error,
            workers=args.workers,
            max_rows=args.max_rows,
            progress=(lambda name: (bar.set_postfix_str(name[:40]), bar.update())) if bar else None,
        )
    finally:
        if bar is not None:
            bar.close()
    out = expl.to_dict()
    if not quiet:
        print(expl.verdict)
        print(format_explanation(expl))
    if args.plot:
        plot_explanation(expl, args.plot)
        out["plot"] = str(args.plot)
        if not quiet:
            print(f"wrote {args.plot}")
    if args.json:
        write_json(args.json, out, args)
    return 0
