"""``hybridtable diagnose`` on 6-DoF runs (``hybridtable-run6/1``): which
effect the six-axis rig's model misses (:mod:`hybridtable.six_dof.diagnose6`)."""

from __future__ import annotations

import argparse
import sys

from hybridtable.errors import CommandError

__all__ = ["diagnose6"]

#: diagnose's options that act on the 1-D runs only, with their defaults.
_ONE_D_ONLY = {"report": None, "save_model": None}


def diagnose6(args: argparse.Namespace) -> int:
    """Read every 6-DoF run, run the forward selection, print the verdict,
    the components' errors before and after and each round's ranking."""
    from hybridtable.commands._common import log_map_entry, write_json
    from hybridtable.commands._run6 import read_run6_arguments, require_apply6
    from hybridtable.effects.registry import get_effect
    from hybridtable.effects.workers import worker_count
    from hybridtable.six_dof.diagnose6 import diagnose_runs6

    runs, layout = read_run6_arguments(args, _ONE_D_ONLY)
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
        for i, step in enumerate(result.steps, 1):
            ranked = sorted(
                (r for r in step.ranking if "delta_bic" in r),
                key=lambda r: r["delta_bic"],
                reverse=True,
            )
            listed = ", ".join(f"{r['effect']} {r['delta_bic']:.4g}" for r in ranked[:4])
            print(f"round {i}: {step.why} (delta BIC: {listed})")
    if args.json:
        out = {"format": "hybridtable-run6/1", **result.to_dict()}
        out["log_map"] = log_map_entry(layout, runs)
        write_json(args.json, out, args)
    return 0
