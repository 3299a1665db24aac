"""``hybridtable compensators``: every compensator over the paper's Table 2 grid,
under stiffness mismatch, sensor noise and a damped contact, as two campaigns
of :mod:`hybridtable.sweeps` (the references, the cases) on one Dask client;
with ``--model``, every compensator on the rig a model file describes
(:mod:`hybridtable.studies.model_compensators`)."""

from __future__ import annotations

import argparse
import sys
import time

__all__ = ["register", "run"]


#: Defaults of the grid sweep's options (None in the parser, so that
#: ``--model`` can tell an option given from one left alone).
SWEEP_DEFAULTS = {
    "prior_ratios": (0.5, 0.75, 1.0, 1.5, 2.0),
    "force_noise_ratio": 1e-3,
    "position_noise_ratio": 1e-4,
    "contact_damping_ratio": 0.1,
}


def register(sub) -> None:
    from hybridtable.commands._common import (
        SEED_RANGE,
        integer_type,
        number_list,
        number_type,
    )
    from hybridtable.commands._loop_options import add_loop_option
    from hybridtable.commands._model_options import add_model_argument, add_plugin_argument
    from hybridtable.compensators.registry import compensator_names
    from hybridtable.studies.compensator_sweep import SCENARIOS

    p = sub.add_parser(
        "compensators",
        help="compare every compensator over the Table 2 grid (mismatch, noise, damping)",
        description="Run every registered compensator, with and without the passivity guard, "
        "over the distinct points of the paper's Table 2 under stiffness mismatch (the believed "
        "stiffness from -50% to +100%), sensor noise and a damped contact; print the worst CoR "
        "error, peak-force error and energy drift against an ideal loop, and whether the online "
        "identification and the passivity guard hold what they promise. With --model: every "
        "compensator on the modelled rig (its sampled computer at its runs' approach "
        "velocities, the model's physics) against an ideal rig with the model's contact.",
    )
    p.add_argument("--json", metavar="FILE", help="write every run and the summary as JSON")
    p.add_argument("--report", metavar="DIR", help="write figures and report.md to DIR")
    p.add_argument(
        "--quick", action="store_true", help="the Table 1 point only instead of the Table 2 grid"
    )
    p.add_argument(
        "--compensators",
        metavar="A,B",
        help=f"subset of {', '.join(compensator_names())} (default: all)",
    )
    p.add_argument(
        "--scenarios", metavar="A,B", help=f"subset of {', '.join(SCENARIOS)} (default: all)"
    )
    p.add_argument(
        "--prior-ratios",
        type=number_list("0.001..1000"),
        default=None,
        metavar="R1,R2",
        help="believed/true stiffness of the mismatch scenario [1], each 0.001 to 1000 (default: "
        "0.5,0.75,1,1.5,2)",
    )
    p.add_argument(
        "--force-noise-ratio",
        type=number_type("0..1"),
        metavar="RATIO",
        default=None,
        help="force noise std / undamped peak force [1], 0 to 1 (default 1e-3)",
    )
    p.add_argument(
        "--position-noise-ratio",
        type=number_type("0..1"),
        metavar="RATIO",
        default=None,
        help="position noise std / peak deflection [1], 0 to 1 (default 1e-4)",
    )
    add_loop_option(
        p,
        "contact_damping_ratio",
        words="damping ratio of the damped scenario's contact",
        default=SWEEP_DEFAULTS["contact_damping_ratio"],
    )
    p.add_argument(
        "--no-passivity", action="store_true", help="skip the runs with the passivity guard"
    )
    add_loop_option(p, "sample_rate_hz", " loop, as the paper")
    p.add_argument(
        "--seed",
        type=integer_type(*SEED_RANGE),
        default=0,
        help=f"noise seed, {SEED_RANGE[0]} to {SEED_RANGE[1]} (default 0)",
    )
    p.add_argument(
        "--workers",
        "--jobs",
        dest="workers",
        metavar="N",
        type=integer_type(1, 256),
        default=None,
        help="local Dask workers (processes), 1 to 256 (default: CPUs, at most 4; 1 runs here, "
        "without a cluster); with --scheduler: wait until N workers have joined",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a local cluster)",
    )
    p.add_argument(
        "--out",
        metavar="FILE.parquet",
        help="write every case's row as hybridtable sweep writes its runs (inputs, metrics, "
        "status, engine)",
    )
    p.add_argument("--tables", metavar="FILE", help="the paper's tables.json")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_model_argument(
        p,
        "rank every compensator (with and without the passivity guard) on the rig it "
        "describes, against an ideal rig with its contact (replaces the Table 2 grid)",
    )
    add_plugin_argument(p)
    p.set_defaults(func=run)


def default_workers() -> int:
    """Local Dask workers of the sweep: the cores this process may use, at most 4."""
    from hybridtable.sweeps.engine import default_workers as cores

    return min(4, cores())


def _names(text: str | None, flag: str) -> tuple[str, ...]:
    """The names of a comma-separated flag; () when not given, an error when
    given empty (``--scenarios=`` must not mean "all")."""
    if text is None:
        return ()
    names = tuple(x.strip() for x in text.split(",") if x.strip())
    if not names:
        from hybridtable.errors import CommandError

        raise CommandError(f"{flag}: empty list; give NAME[,NAME...] or leave the flag out")
    return names


def run(args: argparse.Namespace) -> int:

    from hybridtable._files import staged_folder
    from hybridtable.commands._common import check_outputs, check_suffix, write_json
    from hybridtable.commands._model_options import load_model_arg, load_plugins
    from hybridtable.errors import CommandError

    load_plugins(args)
    model = load_model_arg(args)
    if model is not None:
        return _run_model(args, model)
    for name, value in SWEEP_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    from hybridtable.reports.compensators import format_summary, write_report
    from hybridtable.studies.compensator_sweep import (
        SCENARIOS,
        SweepSettings,
        sweep_points,
        sweep_result,
        sweep_runs,
    )
    from hybridtable.studies.paper import load_tables

    tables = None if args.tables is None else load_tables(args.tables)
    check_suffix("--out", args.out, [".parquet"])
    check_outputs(
        args,
        files={"--json": args.json, "--out": args.out},
        folders={"--report": args.report},
    )
    settings = SweepSettings(
        compensators=_names(args.compensators, "--compensators"),
        prior_ratios=args.prior_ratios,
        force_noise_ratio=args.force_noise_ratio,
        position_noise_ratio=args.position_noise_ratio,
        contact_damping_ratio=args.contact_damping_ratio,
        passivity=(False,) if args.no_passivity else (False, True),
        scenarios=_names(args.scenarios, "--scenarios") or SCENARIOS,
        sample_rate_hz=args.sample_rate_hz,
        seed=args.seed,
    )
    try:
        points = sweep_points(tables, quick=args.quick)
    except (KeyError, TypeError, ValueError) as err:
        raise CommandError(f"malformed tables file: {err}") from None
    references, cases = sweep_runs(settings, points)
    source = args.tables or "the paper's Table 2"
    specs = [
        _spec("compensators (references)", references, settings.seed, source),
        _spec("compensators", cases, settings.seed, source),
    ]
    t0 = time.perf_counter()
    ref_rows, case_rows = _campaigns(args, specs)
    result = sweep_result(
        settings,
        points,
        references,
        cases,
        ref_rows,
        case_rows,
        wall_time_s=time.perf_counter() - t0,
    )
    if args.report:
        with staged_folder(args.report) as stage:
            write_report(result, stage.path)
        result.figures = [str(stage.final(f)) for f in result.figures]
    if args.json != "-":
        print(format_summary(result))
        if args.out:
            print(f"wrote {args.out}")
        for f in result.figures:
            print(f"wrote {f}")
    if args.json:
        write_json(args.json, result.to_json(), args)
    return 0


def _spec(name: str, runs: list[dict], seed: int, source: str):
    """The :class:`~hybridtable.sweeps.plan.SweepSpec` of ``runs`` (their
    inputs as explicit points; the fast engine where it applies).

    Raises
    ------
    ParameterError
        Before any work, for inputs that make no loop (a sensor delay that is
        not a whole number of ``--sample-rate-hz`` periods): one line, not a
        campaign of invalid runs.
    """
    from hybridtable.studies.compensator_sweep import RUN_METRICS
    from hybridtable.sweeps.inputs import loop_params
    from hybridtable.sweeps.spec import parse_spec

    points = [r["inputs"] for r in runs]
    for inputs in points:
        loop_params(inputs)
    raw = {
        "name": name,
        "seed": seed,
        "engine": "auto",
        "metrics": list(RUN_METRICS),
        "points": points,
    }
    return parse_spec(raw, source=source)


def _campaigns(args: argparse.Namespace, specs: list) -> list[list[dict]]:
    """The rows of each spec, run one after the other on one Dask client (a
    local cluster of ``--workers``, or ``--scheduler``); one worker: here,
    without a cluster (the same rows). The last spec's rows go to ``--out``."""
    from hybridtable.sweeps.engine import open_client, run_campaign

    progress = not args.no_progress
    n_runs = max(spec.n_runs for spec in specs)
    workers = args.workers
    if args.scheduler is None:
        workers = max(1, min(workers or default_workers(), n_runs))
    client = cluster = None
    if args.scheduler is not None or workers > 1:
        client, cluster = open_client(args.scheduler, workers)
        if progress and args.json != "-":
            info = client.scheduler_info()
            n = len(info.get("workers", {}))
            print(
                f"compensators: {sum(s.n_runs for s in specs)} runs on {n} Dask "
                f"worker{'s' if n != 1 else ''}; dashboard {client.dashboard_link}",
                file=sys.stderr,
            )
    rows = []
    try:
        for i, spec in enumerate(specs):
            out = args.out if i == len(specs) - 1 else None
            found = run_campaign(
                spec, out, client=client, in_process=client is None, progress=progress
            )
            if found.interrupted:
                raise KeyboardInterrupt
            rows.append(found.rows)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    return rows


#: Options of the grid sweep that mean nothing on a modelled rig.
_GRID_ONLY = (
    ("quick", "--quick"),
    ("scenarios", "--scenarios"),
    ("tables", "--tables"),
    ("sample_rate_hz", "--sample-rate-hz"),
    ("prior_ratios", "--prior-ratios"),
    ("force_noise_ratio", "--force-noise-ratio"),
    ("position_noise_ratio", "--position-noise-ratio"),
    ("contact_damping_ratio", "--contact-damping-ratio"),
    ("scheduler", "--scheduler"),
    ("out", "--out"),
)


def _rig_line(model) -> str:
    n = model.nominal
    velocities = sorted({r.nominal.initial_velocity_m_per_s for r in model.runs}) or [
        n.initial_velocity_m_per_s
    ]
    return (
        f"k {n.contact_stiffness_n_per_m:g} N/m, m {n.spacecraft_mass_kg:g} kg, sensor delay "
        f"{n.sensor_delay_s * 1e3:g} ms, table {n.table_natural_frequency_hz:g} Hz / "
        f"{n.table_damping_ratio:g}, lead {n.lead_time_s * 1e3:g} ms, dead band "
        f"{n.force_deadband_n:g} N, sampled at {n.sample_rate_hz:g} Hz; approach "
        + ", ".join(f"{v:g}" for v in velocities)
        + " m/s"
    )


def _run_model(args: argparse.Namespace, model) -> int:

    from hybridtable._files import staged_folder
    from hybridtable.commands._common import check_outputs, write_json
    from hybridtable.errors import CommandError
    from hybridtable.reports.compensators import (
        format_model_summary,
        model_verdict,
        write_model_report,
    )
    from hybridtable.studies.model_compensators import run_model_compensators

    given = [flag for name, flag in _GRID_ONLY if getattr(args, name) not in (None, False)]
    if given:
        raise CommandError(f"{', '.join(given)}: not with --model (the model's rig is the grid)")
    check_outputs(args, files={"--json": args.json}, folders={"--report": args.report})
    result = run_model_compensators(
        model,
        compensators=_names(args.compensators, "--compensators"),
        passivity=(False,) if args.no_passivity else (False, True),
        jobs=args.workers or 1,
        progress=not args.no_progress and args.json != "-",
    )
    rig = _rig_line(model)
    if args.report:
        with staged_folder(args.report) as stage:
            write_model_report(result, stage.path, rig)
        result.figures = [str(stage.final(f)) for f in result.figures]
    if args.json != "-":
        print(format_model_summary(result, rig))
        for f in result.figures:
            print(f"wrote {f}")
    if args.json:
        data = {
            "model": {"path": str(args.model), "description": model.describe()},
            "rig": rig,
            "verdict": model_verdict(result),
            **result.to_json(),
        }
        write_json(args.json, data, args)
    return 0
