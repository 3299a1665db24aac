"""``hybridtable diagnose``: is the rig model missing something, and what?"""

from __future__ import annotations

import argparse
import sys

__all__ = ["BUILTIN_EFFECT_NAMES", "register", "run", "diagnosis_json"]

#: The built-in effects diagnose tries, named in ``--help`` without importing the library
#: (Drake) at start-up; ``tests/commands`` checks it against the library.
BUILTIN_EFFECT_NAMES: tuple[str, ...] = (
    "contact_damping",
    "hunt_crossley",
    "nonlinear_stiffness",
    "stiffness_error",
    "series_compliance",
    "coulomb_friction",
    "sensor_filter",
    "extra_delay",
    "table_resonance",
    "force_bias",
    "mass_error (decided by the audit)",
)


def register(sub) -> None:
    from hybridtable.commands._common import add_axial_argument, add_run_arguments, integer_type
    from hybridtable.commands._model_options import (
        add_plugin_argument,
        add_save_model_arguments,
    )

    p = sub.add_parser(
        "diagnose",
        help="say whether the rig model misses something, and what (audit, fit, rank, test)",
        description="Read recorded runs (hybridtable-run/1 CSV + JSON pairs, or folders of "
        "them) of one rig. First audit the rig computer: the mass, lead time, MDC stiffness "
        "and deadband it used are solved from the record by arithmetic and compared with "
        "the JSON. Then fit every registered physical effect to the replay of the runs and "
        "add effects one by one while one is significant (delta BIC > 10 and leave-one-"
        "run-out z > 3) and removes >= 25% of the held-out excess error; pairs and swaps "
        "are tried when that leaves a misfit. An end test of the residuals against the "
        "no-contact noise (false-alarm rate 1% per set) decides 'explained'. The verdict "
        "is 'none', the effect(s) named, or 'unexplained'. Built-in effects: "
        + ", ".join(BUILTIN_EFFECT_NAMES)
        + " (plus registered plug-ins). The console opens with one sentence; --json "
        "gives every figure. 6-DoF runs (hybridtable-run6/1) are diagnosed on their "
        "replays, every component in noise levels, over the effects of a six-axis rig "
        "(docs/run6-format.md).",
    )
    add_run_arguments(p, report="write report.md with PNG figures into this folder")
    add_axial_argument(p)
    p.add_argument(
        "--effects",
        metavar="NAME[,NAME...]",
        help="candidate effects, any that hybridtable effects lists (default: those it marks "
        "as tried by diagnose: the eleven built-ins of recorded runs, and the effects of "
        "installed packages and --plugin)",
    )
    p.add_argument(
        "--max-effects",
        type=integer_type(1, 20),
        default=3,
        metavar="N",
        help="most physical effects the model may gain, 1 to 20 (default 3)",
    )
    p.add_argument(
        "--workers",
        type=integer_type(1, 256),
        default=None,
        help="processes fitting in parallel, 1 to 256 (default: 2)",
    )
    add_plugin_argument(p)
    add_save_model_arguments(p)
    p.add_argument("--no-progress", action="store_true", help="no progress output")
    p.set_defaults(func=run)


def diagnosis_json(d) -> dict:
    """The ``--json`` document of a :class:`~hybridtable.diagnosis.candidates.Diagnosis`."""
    out = d.to_json()
    out["runs_read"] = [str(x.run.csv_path) if x.run.csv_path else x.run_id for x in d.data]
    return out


#: How long [s] each contact event of a long log keeps after its contact.
EVENT_TAIL_S = 1.0


def run(args: argparse.Namespace) -> int:
    from hybridtable._files import staged_folder
    from hybridtable.commands._common import (
        check_outputs,
        input_paths,
        log_map_entry,
        read_run_arguments,
        write_json,
    )
    from hybridtable.commands._model_options import load_plugins, write_model
    from hybridtable.diagnosis.diagnose import diagnose
    from hybridtable.effects.registry import get_effect
    from hybridtable.errors import CommandError
    from hybridtable.measurement.comparison import check_comparable
    from hybridtable.reports.diagnose import (
        format_ranking,
        summary_sentence,
        write_report,
    )
    from hybridtable.six_dof.run6 import is_run6

    if is_run6(args.runs) and not args.axial:
        from hybridtable.commands._diagnose6 import diagnose6

        return diagnose6(args)
    load_plugins(args)
    effects = None
    if args.effects is not None:  # given, even empty (--effects=)
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        for e in effects:
            get_effect(e)
        if not effects:
            raise CommandError("--effects names no effect")
    # A long log's events keep a second after their contact: a ringing table
    # or a backlash shows there, and the rest is free flight (the fits' time).
    runs, splits, layout = read_run_arguments(args, tail_s=EVENT_TAIL_S)
    for r in runs:  # no contact, or one that has not ended: no CoR, nothing to fit
        check_comparable(r)
    inputs = input_paths(runs)
    check_outputs(
        args,
        inputs,
        files={"--json": args.json, "--save-model": args.save_model},
        folders={"--report": args.report},
    )
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
        print(summary_sentence(d))
        print()
        print(format_ranking(d))
        print(f"({d.simulations} model runs, {d.wall_time_s:.1f} s)")
        for s in splits:
            print(s.sentence())
    if args.save_model:
        from hybridtable.diagnosis.diagnose import model_from_diagnosis

        model = model_from_diagnosis(d)
        write_model(args.save_model, model)
        if not quiet:
            print(f"wrote the model to {args.save_model}: {model.describe()}")
    if args.json:
        document = diagnosis_json(d)
        if splits:
            document["contact_events"] = [s.to_dict() for s in splits]
        if (log_map := log_map_entry(layout, runs)) is not None:
            document["log_map"] = log_map
        write_json(args.json, document, args)
    if args.report:
        with staged_folder(args.report) as stage:
            files = write_report(d, stage.path)
        files = [stage.final(f) for f in files]
        if not quiet:
            print(
                f"wrote {files[0]}, {files[0].with_suffix('.html')} (figures embedded) and "
                f"{len(files) - 1} figures"
            )
    return 0
