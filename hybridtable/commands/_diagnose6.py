"""``hybridtable diagnose`` on 6-DoF runs (``hybridtable-run6/1``): which
effect the six-axis rig's model misses (:mod:`hybridtable.six_dof.diagnose6`)."""

from __future__ import annotations

import argparse
import sys

from hybridtable.errors import CommandError

__all__ = ["diagnose6"]

#: diagnose's options that act on the 1-D runs only, with their defaults.
_ONE_D_ONLY: dict[str, object] = {}


def diagnose6(args: argparse.Namespace) -> int:
    """Read every 6-DoF run, run the forward selection, print the verdict,
    the components' errors before and after and each round's ranking;
    ``--report DIR``: the compare report of the runs, with the effects found
    fitted, under the diagnosis."""
    from hybridtable.commands._common import log_map_entry, write_json
    from hybridtable.commands._run6 import read_run6_arguments, require_apply6
    from hybridtable.effects.registry import get_effect
    from hybridtable.effects.workers import worker_count
    from hybridtable.six_dof.diagnose6 import diagnose_runs6
    from hybridtable.six_dof.verdict6 import pooled_error

    runs, layout = read_run6_arguments(
        args, _ONE_D_ONLY, {"--report": args.report}, {"--save-model": args.save_model}
    )
    effects = None
    if args.effects is not None:
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        if not effects:
            raise CommandError("--effects names no effect")
        for e in effects:
            require_apply6(get_effect(e), "--effects")
    quiet = args.json == "-"
    result = diagnose_runs6(
        runs,
        effects,
        workers=worker_count(args.workers),
        progress=not args.no_progress and not quiet and sys.stderr.isatty(),
        max_effects=args.max_effects,
    )
    report = _report(args.report, runs, result) if args.report else None
    saved = None
    if args.save_model:
        from hybridtable.commands._model_options import write_model
        from hybridtable.six_dof.model6 import fitted_effects, model6_of_runs

        evidence = {
            "verdict": result.verdict,
            "sentence": result.sentence(),
            "explained": result.explained,
            "nominal_pooled_error": pooled_error(result.nominal_errors),
            "final_pooled_error": pooled_error(result.final_errors),
            "error_unit": "RMS replay error per component in noise levels, pooled",
        }
        model = model6_of_runs(runs, fitted_effects(result.fit), result.audit, "diagnose", evidence)
        write_model(args.save_model, model)
        saved = args.save_model
    if not quiet:
        print(result.sentence())
        print(
            f"\nRMS replay error per component, noise levels ({len(runs)} run(s), "
            f"{result.fits} fits)"
        )
        print(f"  {'component':<12}{'nominal':>10}{'model':>10}")
        for name, e0 in result.nominal_errors.items():
            print(f"  {name:<12}{e0:>10.3g}{result.final_errors[name]:>10.3g}")
        if result.audit is not None:
            print(f"audit: {result.audit.sentence()}")
        for name, why in result.refused.items():
            print(f"left out: {name} cannot act on this rig ({why})")
        for line in _rounds(result) + _separations(result):
            print(line)
        if report:
            print(f"report: {report[0]}")
        if saved:
            print(f"wrote the model to {saved}: {model.describe()}")
    if args.json:
        out = {"format": "hybridtable-run6/1", **result.to_dict()}
        out["log_map"] = log_map_entry(layout, runs)
        out["report"] = report
        out["saved_model"] = saved
        write_json(args.json, out, args)
    return 0


def _rounds(result) -> list[str]:
    """Each round's choice and its four best candidates, one line a round."""
    lines = []
    for i, step in enumerate(result.steps, 1):
        ranked = sorted(
            (r for r in step.ranking if "delta_bic" in r),
            key=lambda r: r["delta_bic"],
            reverse=True,
        )
        listed = ", ".join(f"{r['effect']} {r['delta_bic']:.4g}" for r in ranked[:4])
        if step.kind == "swap":
            listed = ", ".join(
                f"{r['effect']} for {r['replaces']} {r['delta_bic']:.4g}" for r in ranked[:4]
            )
            lines.append(f"swap: {step.why} (delta BIC against the selection: {listed})")
            continue
        lines.append(f"round {i}: {step.why} (delta BIC: {listed})")
    return lines


def _separations(result) -> list[str]:
    """Each selected effect's separating runs from its look-alikes, in words."""
    if not result.separations:
        return []
    from hybridtable.effects.selection import separation_words

    return [
        separation_words(s, s["effects"]) for found in result.separations.values() for s in found
    ]


def _report(folder, runs, result) -> list[str]:
    """The compare report of ``runs`` (and of them with the effects found,
    fitted), the diagnosis above it; returns the files written."""
    from hybridtable._files import staged_folder
    from hybridtable.commands._compare6 import _fit_text
    from hybridtable.effects.registry import get_effect
    from hybridtable.reports.run6 import write_report6
    from hybridtable.six_dof.compare6 import compare_run6

    nominal = [compare_run6(r) for r in runs]
    fitted = text = None
    if result.fit is not None:
        fitted = [compare_run6(r, result.fit.physics) for r in runs]
        text = _fit_text(result.fit, [(get_effect(n), {}) for n in result.fit.values])
    preface = [f"**{result.sentence()}**", ""]
    if result.audit is not None:
        preface += [f"Audit: {result.audit.sentence()}.", ""]
    lines = _rounds(result) + _separations(result)
    preface += [f"- {line}" for line in lines] + [""] * bool(lines)
    with staged_folder(folder) as stage:
        files = write_report6(
            nominal,
            stage.path,
            fitted,
            text or "",
            preface=preface,
            title="Which effect a six-axis rig's model is missing",
        )
        return [str(stage.final(f)) for f in files]
