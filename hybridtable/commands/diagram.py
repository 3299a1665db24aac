"""``hybridtable diagram NAME``: the hybrid loop as a Drake diagram and small
tables of the paper's scenarios (:mod:`hybridtable.reports.diagrams`)."""

from __future__ import annotations

import argparse

__all__ = ["register", "run", "DEFAULT_OUT_DIR"]

#: Where the diagrams go unless ``--out-dir`` is given.
DEFAULT_OUT_DIR = "out/diagrams"


def register(sub) -> None:
    from hybridtable.commands._common import number_list
    from hybridtable.reports.diagrams import DEFAULT_SAMPLE_RATES_HZ, DIAGRAMS

    names = ", ".join(DIAGRAMS)
    p = sub.add_parser(
        "diagram",
        help="draw the hybrid loop's Drake diagram, or run one of the paper's small scenarios",
        description=f"Write one diagram into an output folder: {names}. "
        "hybrid-loop writes the loop's Graphviz .dot (and .svg when Graphviz is installed); "
        "the others print a table and write it as NAME.txt.",
    )
    p.add_argument("name", nargs="?", metavar="NAME", help=f"one of: {names}")
    p.add_argument("--list", action="store_true", help="list the diagrams and what they show")
    p.add_argument(
        "--out-dir",
        metavar="DIR",
        default=DEFAULT_OUT_DIR,
        help=f"write the files here (default {DEFAULT_OUT_DIR})",
    )
    p.add_argument(
        "--sample-rates-hz",
        type=number_list(">0", "Hz"),
        default=None,
        metavar="R1,R2",
        help="rig computer rates of sampled-rig [Hz], each > 0 (default "
        + ",".join(f"{r:g}" for r in DEFAULT_SAMPLE_RATES_HZ)
        + ")",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from hybridtable.commands._common import check_outputs, write_json
    from hybridtable.errors import CommandError
    from hybridtable.reports.diagrams import DIAGRAMS, diagram_files, draw

    if args.list:
        width = max(len(n) for n in DIAGRAMS)
        print(f"{len(DIAGRAMS)} diagrams; draw one with: hybridtable diagram NAME")
        for name, what in DIAGRAMS.items():
            print(f"  {name:<{width}}  {what}")
        return 0
    if args.name is None:
        raise CommandError(f"give a diagram NAME ({', '.join(DIAGRAMS)}) or --list")
    if args.name not in DIAGRAMS:
        raise CommandError(f"no diagram {args.name!r}; choose one of {', '.join(DIAGRAMS)}")
    if args.sample_rates_hz is not None and args.name != "sampled-rig":
        raise CommandError("--sample-rates-hz is for sampled-rig only")
    if Path(args.out_dir).exists() and not Path(args.out_dir).is_dir():
        raise CommandError(f"--out-dir {args.out_dir} is a file, not a folder")
    for path in diagram_files(args.name, args.out_dir):
        check_outputs(args, files={"--out-dir": path})
    check_outputs(args, files={"--json": args.json})
    out = draw(args.name, args.out_dir, sample_rates_hz=args.sample_rates_hz or ())
    if args.json != "-":
        print(out.verdict)
        for line in out.lines:
            print(line)
        for path in out.files:
            print(f"wrote {path}")
    if args.json:
        data = {
            "diagram": args.name,
            "verdict": out.verdict,
            "files": [str(p) for p in out.files],
            **out.data,
        }
        write_json(args.json, data, args)
    return 0
