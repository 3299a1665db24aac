"""``hybridtable compare``: the rig model against recorded runs."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._common import add_axial_argument, add_run_arguments, number_type
    from hybridtable.commands._model_options import (
        add_effect_argument,
        add_model_argument,
        add_plugin_argument,
        add_save_model_arguments,
    )

    p = sub.add_parser(
        "compare",
        help="compare the rig model with recorded runs (replay and closed loop)",
        description="Read recorded runs (hybridtable-run/1 CSV + JSON pairs, or folders of "
        "them), replay each recorded command through the model's table, contact and force "
        "sensor, re-run the whole loop, and report the errors against the noise floor, by "
        "phase, with whiteness tests and force-deflection loops. 6-DoF runs "
        "(hybridtable-run6/1, docs/run6-format.md) are compared with the scenario's closed "
        "loop, component by component. Any defect of an input "
        "file is reported in one line (exit code 2).",
    )
    add_run_arguments(p, report="write report.md with PNG figures into this folder")
    add_axial_argument(p)
    p.add_argument(
        "--max-lag-s",
        type=number_type("0.001..1000", "s"),
        metavar="SECONDS",
        default=None,
        help="longest lag of the whiteness tests [s], 0.001 to 1000 (default: 50 ticks)",
    )
    add_effect_argument(
        p,
        ": compare the model with these effects too and show the error fall; "
        "parameters not given are fitted to the runs, jointly",
    )
    add_model_argument(
        p,
        "compare the runs with this model (its effects and rig computer) too; "
        "with --add, the added effects are fitted on top of it",
    )
    add_plugin_argument(p)
    add_save_model_arguments(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hybridtable._files import staged_folder
    from hybridtable.commands._common import (
        check_outputs,
        input_paths,
        log_map_entry,
        read_run_arguments,
        write_json,
    )
    from hybridtable.commands._model_options import (
        load_model_arg,
        load_plugins,
        parse_added,
        write_model,
    )
    from hybridtable.errors import CommandError
    from hybridtable.measurement.comparison import (
        check_comparable,
        compare_run,
        pool_noise_floors,
    )
    from hybridtable.reports.compare import format_table, format_whiteness, verdict, write_report
    from hybridtable.six_dof.run6 import is_run6

    if is_run6(args.runs) and not args.axial:
        from hybridtable.commands._compare6 import compare6

        return compare6(args)
    load_plugins(args)
    added = parse_added(args)  # a malformed --add before any work
    for effect, _ in added:
        if effect.apply is None:
            raise CommandError(
                f"--add {effect.name}: the effect acts on a six-axis rig only (hybridtable "
                "effects, column loops): these are 1-D runs"
            )
    base = load_model_arg(args)
    runs, splits, layout = read_run_arguments(args)
    for r in runs:  # every defect before any work
        check_comparable(r)
    inputs = input_paths(runs)
    check_outputs(
        args,
        inputs,
        files={"--json": args.json, "--save-model": args.save_model},
        folders={"--report": args.report},
    )
    quiet = args.json == "-"
    iterator = runs
    if len(runs) > 1 and not args.no_progress and not quiet:
        from tqdm import tqdm

        iterator = tqdm(runs, desc="compare", unit="run", file=sys.stderr, leave=False)
    comparisons = [compare_run(r, max_lag_s=args.max_lag_s) for r in iterator]
    pool_noise_floors(comparisons)
    sentence = verdict(comparisons)
    document = {"verdict": sentence, "runs": [c.to_json() for c in comparisons]}
    if splits:
        document["contact_events"] = [s.to_dict() for s in splits]
    model = None
    if added or base is not None:
        model, comparisons, document = _compare_with_model(
            runs, comparisons, added, base, args, quiet
        )
        sentence = document["verdict"]
    elif not quiet:
        print(sentence)  # the console opens with the verdict
        print()
        print(format_table(comparisons))
        print()
        print(format_whiteness(comparisons))
    if splits and not quiet:
        print()
        for s in splits:
            print(s.sentence())
    if splits and model is not None:
        document["contact_events"] = [s.to_dict() for s in splits]
    if args.save_model:
        if model is None:
            from hybridtable.effects.model_file import RigModel

            model = RigModel.from_runs(runs, [], source="compare")
        write_model(args.save_model, model)
        if not quiet:
            print(f"wrote the model to {args.save_model}: {model.describe()}")
    if args.json:
        if (log_map := log_map_entry(layout, runs)) is not None:
            document["log_map"] = log_map
        write_json(args.json, document, args)
    if args.report:
        with staged_folder(args.report) as stage:
            files = write_report(comparisons, stage.path, verdict_text=sentence)
        files = [stage.final(f) for f in files]
        if not quiet:
            print(
                f"wrote {files[0]}, {files[0].with_suffix('.html')} (figures embedded) and "
                f"{len(files) - 1} figures"
            )
    return 0


def _compare_with_model(runs, nominal, added, base, args, quiet: bool):
    """``compare --add`` / ``--model``: the comparisons with the model (the
    added effects fitted where their values are not given), printed beside
    the nominal ones."""
    from dataclasses import replace

    from hybridtable.diagnosis.add_effect import (
        added_json,
        compare_with_model,
        model_with_effects,
    )
    from hybridtable.reports.compare import (
        format_error_fall,
        format_table,
        format_whiteness,
        verdict,
    )

    def notify(message: str) -> None:
        if not quiet:
            print(message, file=sys.stderr)

    if base is not None:
        for line in base.rig_differences(runs):
            notify(f"warning: {line}")
    if added:
        model = model_with_effects(runs, added, base, notify)
    else:
        model = base
    comparisons = compare_with_model(runs, model, args.max_lag_s)
    evidence = {
        "error_to_noise_nominal": {c.run_id: c.to_json()["error_to_noise"] for c in nominal},
        "error_to_noise": {c.run_id: c.to_json()["error_to_noise"] for c in comparisons},
    }
    if added:
        model = replace(model, evidence=evidence)
    names = [e.name for e, _ in added]
    label = model.describe()
    effects = " + ".join(model.effect_names)
    sentence = verdict(comparisons, f"The model with {effects}" if effects else "The given model")
    if not quiet:
        print(sentence)  # the console opens with the verdict
        print()
        print("nominal model:")
        print(format_table(nominal))
        print()
        print(f"with {label}")
        print(format_table(comparisons))
        print()
        print(format_whiteness(comparisons))
        print()
        print(format_error_fall(nominal, comparisons, "+".join(model.effect_names) or "the model"))
    document = {
        "verdict": sentence,
        "runs": [c.to_json() for c in comparisons],
        "nominal_runs": [c.to_json() for c in nominal],
        "model": model.to_json(),
        "model_file": args.model,
        "added_effects": added_json(model, names),
    }
    if args.model is None:
        document["note"] = "model_file null: the nominal model with --add, no --model file"
    return model, comparisons, document
