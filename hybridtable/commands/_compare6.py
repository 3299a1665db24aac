"""``hybridtable compare`` on 6-DoF runs (``hybridtable-run6/1``): the model's
replay and closed loop against each run, component by component
(:mod:`hybridtable.six_dof.compare6`)."""

from __future__ import annotations

import argparse
import sys

from hybridtable.errors import CommandError

__all__ = ["compare6"]

#: compare's options that act on the 1-D runs only, with their defaults.
_ONE_D_ONLY = {"max_lag_s": None}


def compare6(args: argparse.Namespace) -> int:
    """Read every 6-DoF run, compare each with the model's replay and closed
    loop, print the verdicts and a table of the components' errors; with
    ``--add``, fit the effects to the runs' replays and compare again (the
    error falls, or does not)."""
    from hybridtable.commands._common import log_map_entry, write_json
    from hybridtable.commands._model_options import parse_added
    from hybridtable.commands._run6 import read_run6_arguments, require_apply6
    from hybridtable.six_dof.audit6 import audit_runs6
    from hybridtable.six_dof.compare6 import compare_run6
    from hybridtable.six_dof.fit6 import fit_runs6

    runs, layout = read_run6_arguments(
        args, _ONE_D_ONLY, {"--report": args.report}, {"--save-model": args.save_model}
    )
    model = base = None
    if args.model:
        from hybridtable.six_dof.model6 import load_model6

        model = load_model6(args.model)
        base = model.physics()
    added = parse_added(args)
    for effect, _ in added:
        require_apply6(effect, "--add")
        if model is not None and effect.name in model.effect_names:
            raise CommandError(
                f"--add {effect.name}: the model {args.model} has it already (its values are "
                "the model's; fit it again without --model)"
            )
    # the rig computer's effects are solved by the audit, not fitted to the replays
    audited = [e.name for e, _ in added if e.stage == "closed_loop"]
    added = [(e, v) for e, v in added if e.stage != "closed_loop"]
    quiet = args.json == "-"
    iterator = runs
    if len(runs) > 1 and not args.no_progress and not quiet:
        from tqdm import tqdm

        iterator = tqdm(runs, desc="compare", unit="run", file=sys.stderr, leave=False)
    results = [compare_run6(r) for r in iterator]
    audit = audit_runs6(runs)
    modelled = None if model is None else [compare_run6(r, base) for r in runs]
    fit = fitted = None
    if added:
        fit = fit_runs6(runs, added, base=base)
        fitted = [compare_run6(r, fit.physics) for r in runs]
    saved = _save_model(args, runs, model, fit, audit, fitted or modelled or results)
    report = None
    if args.report:
        from hybridtable._files import staged_folder
        from hybridtable.reports.run6 import write_report6

        with staged_folder(args.report) as stage:
            text = _fit_text(fit, added)
            if model is not None:  # the model's effects, and the fitted ones on top
                text = "\n".join(
                    t for t in (f"the model {args.model}: {model.describe()}", text) if t
                )
            files = write_report6(
                results,
                stage.path,
                fitted or modelled,
                text,
                preface=[f"Audit: {audit.sentence()}.", ""],
            )
            report = [str(stage.final(f)) for f in files]
    if not quiet:
        for c in results:
            print(c.verdict())
        print(f"audit: {audit.sentence()}")
        for name in audited:
            print(f"--add {name}: an effect of the rig computer; the audit above solves for it")
        if model is not None:
            _print_model(args.model, model, runs, results, modelled)
        if fit is not None:
            _print_fit(fit, added, modelled or results, fitted)
        for c in results:
            print(
                f"\n{c.run_id} ({c.n_ticks} ticks): RMS error per component in noise levels, "
                "replay (the recorded commands through the model's table, contact and sensor) "
                "and closed loop"
            )
            print(
                f"  {'component':<12} {'noise':>11} {'replay':>9} {'closed loop':>12}  replay's worst"
            )
            for e, loop in zip(c.components, c.closed_loop, strict=True):
                print(
                    f"  {e.name:<12} {e.noise:>11.4g} {e.error_sigma:>9.3g} "
                    f"{loop.error_sigma:>12.3g}  {e.worst_phase} at {e.worst_time_s:.4g} s "
                    f"(noise in {e.unit})"
                )
            print(
                f"  energy ratio {c.energy_ratio_measured:.4f} measured, "
                f"{c.energy_ratio_model:.4f} modelled"
            )
            for note in c.notes:
                print(f"  note: {note}")
        if saved:
            print(f"\nwrote the model to {saved}")
    if args.json:
        out = {
            "format": "hybridtable-run6/1",
            "explained": all(c.explained for c in results),
            "verdicts": [c.verdict() for c in results],
            "runs": [c.to_dict() for c in results],
            "log_map": log_map_entry(layout, runs),
            "audit": audit.to_dict(),
            "report": report,
            "model": None
            if model is None
            else {
                "file": args.model,
                "description": model.describe(),
                "other_rig": model.rig_differences([(f"run {r.run_id}", r.params) for r in runs]),
                "explained": all(c.explained for c in modelled),
                "verdicts": [c.verdict() for c in modelled],
                "runs": [c.to_dict() for c in modelled],
            },
            "saved_model": args.save_model,
            **(
                {}
                if fit is None
                else {
                    "added": {
                        "effects": [e.name for e, _ in added],
                        "fit": fit.to_dict(),
                        "explained": all(c.explained for c in fitted),
                        "verdicts": [c.verdict() for c in fitted],
                        "runs": [c.to_dict() for c in fitted],
                    }
                }
            ),
        }
        write_json(args.json, out, args)
    return 0


def _fit_text(fit, added) -> str:
    """The fitted values, one line an effect ("" without a fit)."""
    if fit is None:
        return ""
    units = {e.name: {p.name: p.unit for p in e.parameters} for e, _ in added}
    lines = []
    for name, values in fit.values.items():
        parts = []
        for k, v in values.items():
            s = fit.std[name].get(k)
            given = " (given)" if k not in fit.fitted[name] else ""
            err = f" +- {s:.3g}" if s is not None else given
            unit = units[name][k]
            parts.append(f"{k} = {v:.5g}{err}" + (f" {unit}" if unit != "1" else ""))
        lines.append(f"{name}: {', '.join(parts)}")
    return "\n".join(lines)


def _print_fit(fit, added, before, after) -> None:
    """The fitted values and how the replay's error fell."""
    print(f"\nwith {' + '.join(e.name for e, _ in added)} (fitted to the replays):")
    for line in _fit_text(fit, added).splitlines():
        print(f"  {line}")
    print(
        f"  replay chi2 {fit.chi2_before:.4g} -> {fit.chi2_after:.4g} over {fit.n_residuals} "
        f"residuals ({fit.evaluations} replays{'' if fit.success else '; a polish did not converge'})"
    )
    _print_fall(before, after)


def _print_model(path, model, runs, before, after) -> None:
    """The model file's effects and how the replay's error moved with them."""
    print(f"\nwith the model {path} ({model.describe()}):")
    for note in model.rig_differences([(f"run {r.run_id}", r.params) for r in runs]):
        print(f"  note: {note}")
    _print_fall(before, after)


def _save_model(args, runs, model, fit, audit, final) -> str | None:
    """Write ``--save-model``: the model file's effects (if any), the fitted
    ones and the audit's, with the final comparison as the evidence; returns
    the file and what it holds, in words."""
    if not args.save_model:
        return None
    from hybridtable.commands._model_options import write_model
    from hybridtable.six_dof.model6 import fitted_effects, model6_of_runs

    fitted = {e.name: e for e in (model.effects if model else ())}
    fitted |= {e.name: e for e in fitted_effects(fit)}
    evidence = {
        "explained": all(c.explained for c in final),
        "verdicts": [c.verdict() for c in final],
        "worst_error_sigma": max(c.worst.error_sigma for c in final),
        "error_unit": "RMS replay error of the worst component, in its noise levels",
    }
    saved = model6_of_runs(runs, list(fitted.values()), audit, "compare", evidence)
    write_model(args.save_model, saved)
    return f"{args.save_model}: {saved.describe()}"


def _print_fall(before, after) -> None:
    """Each run's verdict with the effects, and its worst component's fall."""
    for b, a in zip(before, after, strict=True):
        print(f"  {a.verdict()}")
        print(
            f"    the replay's worst component {b.worst.name}: {b.worst.error_sigma:.3g} -> "
            f"{next(c for c in a.components if c.name == b.worst.name).error_sigma:.3g} noise "
            f"levels; worst now {a.worst.name} {a.worst.error_sigma:.3g}"
        )
