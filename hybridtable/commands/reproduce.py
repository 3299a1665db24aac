"""``hybridtable reproduce``: the paper's Tables 1-2 and Figs. 3-7."""

from __future__ import annotations

import argparse
import time

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._common import number_type
    from hybridtable.compensators.paper import CONTACT_GATES

    p = sub.add_parser(
        "reproduce",
        help="reproduce the paper's simulation tables and figures",
        description="Run Table 1 (four compensators, also at half the step), every row of "
        "Table 2 beside the paper's values, and write Figs. 3-7 as PNGs.",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument("--out-dir", metavar="DIR", help="write the figures here (default: no figures)")
    p.add_argument(
        "--tables", metavar="FILE", help="the paper's tables.json (default: shipped copy)"
    )
    p.add_argument(
        "--time-step-s",
        type=number_type("time_step_s"),
        metavar="SECONDS",
        default=None,
        help="continuous-loop step [s], 1e-09 to 1 (default: min(2e-4, 1/(5000 f_con)))",
    )
    p.add_argument(
        "--contact-gate",
        choices=CONTACT_GATES,
        default="measured_force",
        help="when the compensation acts: while the measured force is above the deadband "
        "(the rig's gate), or while the table position is in contact",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:

    from hybridtable._files import staged_folder
    from hybridtable.commands._common import check_outputs, write_json
    from hybridtable.reports.reproduce import format_tables, reproduce, verdict
    from hybridtable.studies.paper import load_tables

    if args.tables is not None:
        load_tables(args.tables)  # a defect in one line, before any work
    check_outputs(args, files={"--json": args.json}, folders={"--out-dir": args.out_dir})
    t0 = time.perf_counter()
    options = dict(
        tables_path=args.tables,
        time_step_s=args.time_step_s,
        contact_gate=args.contact_gate,
        progress=not args.no_progress,
    )
    if args.out_dir is None:
        rep = reproduce(**options)
    else:
        with staged_folder(args.out_dir) as stage:
            rep = reproduce(out_dir=stage.path, **options)
        rep.figures = [str(stage.final(f)) for f in rep.figures]
    wall = time.perf_counter() - t0
    data = rep.to_json()
    data["wall_time_s"] = wall
    if args.json != "-":
        print(verdict(rep))
        print()
        print(format_tables(rep))
        for f in rep.figures:
            print(f"wrote {f}")
        print(f"wall time {wall:.1f} s")
    if args.json:
        write_json(args.json, data, args)
    return 0
