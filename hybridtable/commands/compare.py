"""``hybridtable compare``: the rig model against recorded runs."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

__all__ = ["register", "run", "check_outputs"]


def register(sub) -> None:
    from hybridtable.cli import parse_float

    p = sub.add_parser(
        "compare",
        help="compare the rig model with recorded runs (replay and closed loop)",
        description="Read recorded runs (hybridtable-run/1 CSV + JSON pairs, or folders of "
        "them), replay each recorded command through the model's table, contact and force "
        "sensor, re-run the whole loop, and report the errors against the noise floor, by "
        "phase, with whiteness tests and force-deflection loops. Any defect of an input "
        "file is reported in one line (exit code 2).",
    )
    p.add_argument("runs", nargs="+", metavar="RUN", help="a run's .csv or .json, or a folder")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--report", metavar="DIR", help="write report.md with PNG figures into this folder"
    )
    p.add_argument(
        "--column-map",
        metavar="FORMAT=LOG",
        action="append",
        default=[],
        help="read the format's column FORMAT from the log's column LOG (repeatable, or "
        "comma separated), e.g. --column-map f_mea_n=force,time_s=t",
    )
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


def _inputs(runs) -> list[Path]:
    return [p.resolve() for r in runs for p in (r.csv_path, r.json_path) if p is not None]


def check_outputs(
    json_path: str | None,
    report_dir: str | None,
    inputs: list[Path],
    command: str = "compare",
    report_marker: str | None = None,
) -> None:
    """Refuse outputs that would write over an input or a user's folder.

    ``report_marker`` is the file by which ``command``'s reports mark their
    folders (default: the compare report's).

    Raises
    ------
    CommandError
        If ``json_path`` is an input file or a folder, or ``report_dir`` is a
        file, holds an input, or is a non-empty folder not written by an
        earlier ``command --report``.
    """
    from hybridtable.cli import CommandError
    from hybridtable.compare_report import REPORT_MARKER

    marker = report_marker or REPORT_MARKER

    if json_path and json_path != "-":
        target = Path(json_path).resolve()
        if target in inputs:
            raise CommandError(f"--json {json_path} is one of the input files; not writing over it")
        if target.is_dir():
            raise CommandError(f"--json {json_path} is a folder")
    if report_dir:
        d = Path(report_dir).resolve()
        if d.exists() and not d.is_dir():
            raise CommandError(f"--report {report_dir} is a file, not a folder")
        if any(d == p.parent or d in p.parents for p in inputs):
            raise CommandError(f"--report {report_dir} holds input runs; choose another folder")
        if d.is_dir() and any(d.iterdir()) and not (d / marker).is_file():
            raise CommandError(
                f"--report {report_dir} is not empty and not an earlier {command} report; "
                "choose a new or empty folder"
            )


def _write_json_atomic(path: str, data) -> None:
    from hybridtable.cli import write_json

    if path == "-":
        write_json(path, data)
        return
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    os.close(fd)
    try:
        write_json(tmp, data)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def run(args: argparse.Namespace) -> int:
    from hybridtable.compare_report import format_table, write_report
    from hybridtable.comparison import check_comparable, compare_run
    from hybridtable.measurement import parse_column_map, read_runs

    if args.max_lag_s is not None:
        from hybridtable._validation import check_positive

        check_positive("--max-lag-s", args.max_lag_s)
    column_map = parse_column_map(args.column_map)
    runs = read_runs(args.runs, column_map)
    for r in runs:  # every defect before any work
        check_comparable(r)
    check_outputs(args.json, args.report, _inputs(runs))
    if args.add:  # a malformed --add before any work
        from hybridtable.effects import parse_effect_spec

        parse_effect_spec(args.add)
    quiet = args.json == "-"
    iterator = runs
    if len(runs) > 1 and not args.no_progress and not quiet:
        from tqdm import tqdm

        iterator = tqdm(runs, desc="compare", unit="run", file=sys.stderr, leave=False)
    comparisons = [compare_run(r, max_lag_s=args.max_lag_s) for r in iterator]
    document = {"runs": [c.to_json() for c in comparisons]}
    if args.add:
        from hybridtable.commands.diagnose import compare_with_effect

        comparisons, added = compare_with_effect(runs, comparisons, args.add, args.max_lag_s, quiet)
        document = {
            "runs": [c.to_json() for c in comparisons],
            "nominal_runs": document["runs"],
            "added_effect": added,
        }
    elif not quiet:
        print(format_table(comparisons))
    if args.json:
        _write_json_atomic(args.json, document)
    if args.report:
        files = write_report(comparisons, args.report)
        if not quiet:
            print(f"wrote {files[0]} and {len(files) - 1} figures")
    return 0
