"""``hybridtable diagnose``: which physical effect is the rig model missing."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run", "diagnosis_json", "compare_with_effect", "format_error_fall"]


def register(sub) -> None:
    p = sub.add_parser(
        "diagnose",
        help="name the physical effect the rig model is missing (fit, rank, select)",
        description="Read recorded runs (hybridtable-run/1 CSV + JSON pairs, or folders of "
        "them) of one rig, fit every candidate effect (contact damping, Hunt-Crossley, "
        "nonlinear stiffness, stiffness error, series compliance, Coulomb friction, sensor "
        "filter, extra delay, table resonance, force bias, mass error) to the replay of the "
        "runs, rank them by the BIC of the prewhitened residuals and a leave-one-run-out "
        "check, and add effects one by one until nothing significant is left. The verdict "
        "is the missing effect, or none.",
    )
    p.add_argument("runs", nargs="+", metavar="RUN", help="a run's .csv or .json, or a folder")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--report", metavar="DIR", help="write report.md with PNG figures into this folder"
    )
    p.add_argument(
        "--effects",
        metavar="NAME[,NAME...]",
        help="candidate effects (default: every registered effect)",
    )
    p.add_argument(
        "--max-effects",
        type=int,
        default=3,
        help="most effects the forward selection adds (default 3)",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="processes fitting in parallel (default: 2)"
    )
    p.add_argument(
        "--column-map",
        metavar="FORMAT=LOG",
        action="append",
        default=[],
        help="read the format's column FORMAT from the log's column LOG (as in compare)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress output")
    p.set_defaults(func=run)


def diagnosis_json(d) -> dict:
    """The ``--json`` document of a :class:`~hybridtable.diagnose.Diagnosis`."""
    out = d.to_json()
    out["runs_read"] = [str(x.run.csv_path) if x.run.csv_path else x.run_id for x in d.data]
    return out


def run(args: argparse.Namespace) -> int:
    from hybridtable.cli import CommandError
    from hybridtable.commands.compare import _inputs, _write_json_atomic, check_outputs
    from hybridtable.diagnose import diagnose
    from hybridtable.diagnose_report import REPORT_MARKER, format_ranking, write_report
    from hybridtable.effects import get_effect
    from hybridtable.measurement import parse_column_map, read_runs

    effects = None
    if args.effects:
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        for e in effects:
            get_effect(e)
        if not effects:
            raise CommandError("--effects names no effect")
    if args.max_effects < 1:
        raise CommandError(f"--max-effects must be >= 1 (got {args.max_effects})")
    if args.workers is not None and args.workers < 1:
        raise CommandError(f"--workers must be >= 1 (got {args.workers})")
    runs = read_runs(args.runs, parse_column_map(args.column_map))
    inputs = _inputs(runs)
    check_outputs(args.json, args.report, inputs, "diagnose", REPORT_MARKER)
    quiet = args.json == "-"
    if not quiet and not args.no_progress:
        print(f"diagnosing {len(runs)} run(s)...", file=sys.stderr)
    d = diagnose(
        runs,
        effects=effects,
        max_effects=args.max_effects,
        workers=args.workers,
        progress=not (quiet or args.no_progress),
    )
    if not quiet:
        print(format_ranking(d))
        print(f"({d.simulations} model runs, {d.wall_time_s:.1f} s)")
    if args.json:
        _write_json_atomic(args.json, diagnosis_json(d))
    if args.report:
        files = write_report(d, args.report)
        if not quiet:
            print(f"wrote {files[0]} and {len(files) - 1} figures")
    return 0


def format_error_fall(nominal, with_effect, label: str) -> str:
    """Per run: replay errors over the noise and closed-loop errors, nominal
    model -> model with the effect."""
    head = (
        f"{'run':<16} {'f_mea rms/noise':>17} {'p_act rms/noise':>17} "
        f"{'v_des rms [mm/s]':>19} {'CoR error':>21}"
    )
    lines = [f"error fall with {label}:", head, "-" * len(head)]
    for a, b in zip(nominal, with_effect, strict=True):
        va = a.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        vb = b.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        lines.append(
            f"{a.run_id[:16]:<16} {a.error_to_noise('f_mea_n'):7.3f} -> {b.error_to_noise('f_mea_n'):<6.3f} "
            f"{a.error_to_noise('p_act_m'):7.3f} -> {b.error_to_noise('p_act_m'):<6.3f} "
            f"{va:8.3g} -> {vb:<8.3g} "
            f"{a.cor_model - a.cor_measured:+9.5f} -> {b.cor_model - b.cor_measured:<+9.5f}"
        )
    return "\n".join(lines)


def compare_with_effect(runs, nominal, text: str, max_lag_s, quiet: bool):
    """Compare ``runs`` with the model plus the effect of ``text``
    (``EFFECT[:param=value,...]``; parameters not given are fitted).

    Returns the comparisons with the effect and a description of the effect
    (name, parameters, units, which were fitted).
    """
    from hybridtable.compare_report import format_table
    from hybridtable.comparison import compare_run
    from hybridtable.diagnose import fit_effect
    from hybridtable.diagnose_report import format_parameters
    from hybridtable.effects import RigScale, build_spec, parse_effect_spec

    effect, given = parse_effect_spec(text)
    scale = RigScale.from_runs(runs)
    values = effect.check_values(given, scale)
    fitted = [p for p in effect.parameter_names if p not in given]
    if fitted:
        if not quiet:
            print(f"fitting {', '.join(fitted)} of {effect.name} to the runs...", file=sys.stderr)
        values = fit_effect(runs, effect.name, given)
    spec = build_spec([(effect, values)], scale)
    label = f"{effect.name}: {format_parameters(effect.name, values)}"
    physics = spec.physics(name=effect.name)
    comparisons = [compare_run(spec.closed_loop_run(r), physics, max_lag_s=max_lag_s) for r in runs]
    if not quiet:
        print("nominal model:")
        print(format_table(nominal))
        print()
        print(f"with {label}" + (f" (fitted: {', '.join(fitted)})" if fitted else ""))
        print(format_table(comparisons))
        print()
        print(format_error_fall(nominal, comparisons, effect.name))
    return comparisons, {
        "effect": effect.name,
        "parameters": dict(values),
        "units": {p.name: p.unit for p in effect.parameters},
        "fitted": fitted,
    }
