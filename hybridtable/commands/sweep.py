"""``hybridtable sweep SPEC.toml``: a grid and/or Monte Carlo campaign on Dask
(:mod:`hybridtable.sweeps`), a row per run in one Parquet file."""

from __future__ import annotations

import argparse
import math
import sys

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._common import integer_type

    p = sub.add_parser(
        "sweep",
        help="run a campaign (grid and/or Monte Carlo) from a spec, on Dask",
        description="Run every run of a sweep spec (a TOML file: fixed parameters, grid axes, "
        "explicit points, Monte Carlo draws, compensators, metrics; see docs/sweeps.md and "
        "examples/sweeps/) on Dask distributed: a local cluster of worker processes, or an "
        "existing scheduler. Writes one Parquet file, a row per run (the swept inputs, "
        "compensator, the metrics, status, message, engine, seconds), sorted by run; results "
        "do not depend on the cluster, the number of workers or the order of completion. A run "
        "that diverges or fails is a row with its status; the file is rewritten every few "
        "seconds, so a killed campaign leaves the runs it finished and --resume runs the rest.",
    )
    p.add_argument("spec", metavar="SPEC.toml", help="the campaign's spec")
    p.add_argument(
        "--out", metavar="FILE.parquet", required=True, help="the results (a row per run)"
    )
    p.add_argument("--report", metavar="DIR", help="write figures and report.md to DIR")
    p.add_argument("--json", metavar="FILE", help="write the summary as JSON (- for stdout)")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a local cluster)",
    )
    p.add_argument(
        "--workers",
        type=integer_type(1, 256),
        default=None,
        metavar="N",
        help="local cluster: its worker processes, 1 to 256 (default: the cores); with "
        "--scheduler: wait until this many workers have joined",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="keep the runs FILE.parquet already holds (it must be this spec's) and run the rest",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _check_outputs(args: argparse.Namespace, spec) -> None:
    from pathlib import Path

    from hybridtable.commands._common import check_outputs, check_suffix
    from hybridtable.errors import CommandError

    check_suffix("--out", args.out, [".parquet"])
    inputs = [Path(args.spec)] + ([Path(spec.model_path)] if spec.model_path else [])
    if args.resume and args.force:
        raise CommandError("--resume keeps FILE.parquet's runs, --force replaces it: give one")
    if args.resume and Path(args.out).exists():
        # Resuming writes the file over on purpose: check it as --force would.
        check_outputs(
            argparse.Namespace(**{**vars(args), "force": True}), inputs, files={"--out": args.out}
        )
        if args.json not in (None, "-") and Path(args.json).resolve() == Path(args.out).resolve():
            raise CommandError(f"--json {args.json} and --out {args.out} name the same file")
        check_outputs(args, inputs, files={"--json": args.json}, folders={"--report": args.report})
    else:
        check_outputs(
            args,
            inputs,
            files={"--json": args.json, "--out": args.out},
            folders={"--report": args.report},
        )


def _json_document(args, spec, summary, result, figures) -> dict:
    """The ``--json`` document, every null or infinity with a note saying why."""
    from hybridtable.commands._common import note_unset
    from hybridtable.reports.sweep_summary import verdict

    doc_spec = note_unset(
        spec.to_json(),
        {
            "model": "model null: no model file; the runs have the nominal physics"
            if spec.loop == "1d"
            else "model null: a 6-DoF campaign runs its scenario's physics",
            "model_path": "model_path null: no model file",
        },
    )
    for comp, entry in summary["compensators"].items():
        for name, stats in entry.items():
            if isinstance(stats, dict) and set(stats) == {"min", "median", "max"}:
                note_unset(
                    stats,
                    {
                        "min": f"null: no run of {comp} gave a finite {name}",
                        "max": f"inf: {name} is infinite in a run of {comp}"
                        + (" (stable at every delay searched)" if "delay" in name else ""),
                    },
                )
    for row in summary["worst"]:
        unset = [
            m
            for m in spec.metrics
            if row[m] is None or (isinstance(row[m], float) and not math.isfinite(row[m]))
        ]
        if unset:
            row["note"] = f"{', '.join(unset)} null: the run {row['status']} ({row['message']})"
    idle = {  # a resume with every row already in the file starts no cluster
        "dashboard": "dashboard null: no Dask cluster ran (nothing was left to run)",
        "scheduler": "scheduler null: no Dask cluster ran (nothing was left to run)",
    }
    return note_unset(
        {
            "verdict": verdict(spec.name, summary),
            "spec": doc_spec,
            "out": str(args.out),
            "complete": result.complete,
            "interrupted": result.interrupted,
            "resumed": result.resumed,
            "rerun": [{"run": run, "why": why} for run, why in result.rerun],
            "workers": result.workers,
            "scheduler": result.scheduler,
            "dashboard": result.dashboard,
            "wall_time_s": result.wall_time_s,
            "compute_time_s": result.compute_time_s,
            "retried_runs": result.retried,
            "figures": figures,
            **summary,
        },
        idle if result.written == result.resumed else {},
    )


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import write_json
    from hybridtable.reports.sweep_summary import format_summary, summarize
    from hybridtable.sweeps.engine import run_campaign
    from hybridtable.sweeps.spec import load_spec
    from hybridtable.sweeps.store import read_results

    spec = load_spec(args.spec)
    _check_outputs(args, spec)
    quiet = args.json == "-"

    def started(result) -> None:
        if not quiet:
            where = f"scheduler {args.scheduler}" if args.scheduler else "a local cluster"
            print(
                f"sweep {spec.name}: {spec.n_runs} runs on {result.workers} Dask "
                f"worker{'s' if result.workers != 1 else ''} "
                f"({where}); dashboard {result.dashboard}",
                file=sys.stderr,
            )

    result = run_campaign(
        spec,
        args.out,
        scheduler=args.scheduler,
        workers=args.workers,
        resume=args.resume,
        progress=not args.no_progress and not quiet,
        on_start=started,
    )
    table = read_results(args.out, spec)
    summary = summarize(table, spec.n_runs, spec.metrics, spec.loop)
    figures: list[str] = []
    if args.report and table.num_rows:
        from hybridtable._files import staged_folder
        from hybridtable.errors import WriteError
        from hybridtable.reports.sweep import write_report

        try:
            with staged_folder(args.report) as stage:
                written = write_report(table, spec, summary, stage.path)
        except WriteError as err:  # the campaign's rows are written: say where they are
            raise WriteError(
                f"{err}; the campaign's {table.num_rows} rows are complete in {args.out} "
                "(--resume --report writes the report once there is room)"
            ) from None
        figures = [str(stage.final(f)) for f in written]
    if not quiet:
        print(format_summary(spec.name, summary, spec.metrics))
        print(f"wrote {args.out}")
        for f in figures:
            print(f"wrote {f}")
        new = result.written - result.resumed
        rate = new / result.wall_time_s if result.wall_time_s > 0 else 0.0
        print(
            f"{new} runs in {result.wall_time_s:.1f} s "
            f"({rate:.1f} runs/s on {result.workers} worker{'s' if result.workers != 1 else ''})"
            + (f"; {result.resumed} were already in the file" if result.resumed else "")
        )
        if result.rerun:
            run, why = result.rerun[0]
            print(
                f"ran {len(result.rerun)} run(s) of the file again, whose rows could not be "
                f"kept (run {run}: {why}"
                + (f"; and {len(result.rerun) - 1} more" if len(result.rerun) > 1 else "")
                + ")"
            )
    if args.json:
        write_json(args.json, _json_document(args, spec, summary, result, figures), args)
    if result.interrupted:
        print(
            f"hybridtable sweep: interrupted: {result.written} of {spec.n_runs} runs are in "
            f"{args.out}; run again with --resume to finish",
            file=sys.stderr,
        )
        return 130
    return 0
