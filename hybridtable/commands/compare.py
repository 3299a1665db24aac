"""``hybridtable compare``: the rig model against recorded runs."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._common import add_run_arguments, parse_float

    p = sub.add_parser(
        "compare",
        help="compare the rig model with recorded runs (replay and closed loop)",
        description="Read recorded runs (hybridtable-run/1 CSV + JSON pairs, or folders of "
        "them), replay each recorded command through the model's table, contact and force "
        "sensor, re-run the whole loop, and report the errors against the noise floor, by "
        "phase, with whiteness tests and force-deflection loops. Any defect of an input "
        "file is reported in one line (exit code 2).",
    )
    add_run_arguments(p, report="write report.md with PNG figures into this folder")
    p.add_argument(
        "--max-lag-s",
        type=parse_float,
        default=None,
        help="longest lag of the whiteness tests (default: 50 ticks)",
    )
    p.add_argument(
        "--add",
        metavar="EFFECT[:param=value,...]",
        help="also compare a model with this effect added (hybridtable diagnose's "
        "effects) and show the error fall; parameters not given are fitted to the runs",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import check_outputs, input_paths, write_json_atomic
    from hybridtable.measurement.comparison import check_comparable, compare_run
    from hybridtable.measurement.run_reader import parse_column_map, read_runs
    from hybridtable.reports.compare import REPORT_MARKER, format_table, write_report

    if args.max_lag_s is not None:
        from hybridtable._validation import check_positive

        check_positive("--max-lag-s", args.max_lag_s)
    column_map = parse_column_map(args.column_map)
    runs = read_runs(args.runs, column_map)
    for r in runs:  # every defect before any work
        check_comparable(r)
    check_outputs(args.json, args.report, input_paths(runs), "compare", REPORT_MARKER)
    if args.add:  # a malformed --add before any work
        from hybridtable.diagnosis.registry import parse_effect_spec

        parse_effect_spec(args.add)
    quiet = args.json == "-"
    iterator = runs
    if len(runs) > 1 and not args.no_progress and not quiet:
        from tqdm import tqdm

        iterator = tqdm(runs, desc="compare", unit="run", file=sys.stderr, leave=False)
    comparisons = [compare_run(r, max_lag_s=args.max_lag_s) for r in iterator]
    document = {"runs": [c.to_json() for c in comparisons]}
    if args.add:
        comparisons, added = _compare_with_effect(
            runs, comparisons, args.add, args.max_lag_s, quiet
        )
        document = {
            "runs": [c.to_json() for c in comparisons],
            "nominal_runs": document["runs"],
            "added_effect": added,
        }
    elif not quiet:
        print(format_table(comparisons))
    if args.json:
        write_json_atomic(args.json, document)
    if args.report:
        files = write_report(comparisons, args.report)
        if not quiet:
            print(f"wrote {files[0]} and {len(files) - 1} figures")
    return 0


def _compare_with_effect(runs, nominal, text: str, max_lag_s, quiet: bool):
    """``compare --add``: the comparisons with the effect of ``text`` added
    (parameters not given fitted), printed beside the nominal ones."""
    from hybridtable.diagnosis.add_effect import compare_with_effect
    from hybridtable.reports.compare import format_error_fall, format_table
    from hybridtable.reports.diagnose import format_parameters

    def notify(message: str) -> None:
        if not quiet:
            print(message, file=sys.stderr)

    comparisons, added = compare_with_effect(runs, text, max_lag_s, notify)
    if not quiet:
        fitted = added["fitted"]
        label = f"{added['effect']}: {format_parameters(added['effect'], added['parameters'])}"
        print("nominal model:")
        print(format_table(nominal))
        print()
        print(f"with {label}" + (f" (fitted: {', '.join(fitted)})" if fitted else ""))
        print(format_table(comparisons))
        print()
        print(format_error_fall(nominal, comparisons, added["effect"]))
    return comparisons, added
