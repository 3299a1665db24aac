"""``hybridtable effects``: the registered physical effects, their parameters,
units and bounds.

Lists every effect that ``diagnose``, ``compare --add`` and ``simulate --add``
know: the built-ins, those of installed packages (entry-point group
``hybridtable.effects``) and those of ``--plugin MODULE:ATTR``. Bounds that
depend on the rig (callables of a
:class:`~hybridtable.effects.effect.RigScale`) are evaluated at a
reference rig: the paper's Table 1 point (sampled at 1 kHz) by default, or the
rig of the recorded runs of ``--rig RUN``.
"""

from __future__ import annotations

import argparse

from hybridtable.errors import ParameterError

__all__ = ["register", "run", "paper_scale", "effect_json", "format_effects"]

#: Sample period of the paper's Table 1 point as a reference rig (s): the
#: paper's loop is continuous; recorded runs are sampled at 1 kHz.
PAPER_SAMPLE_PERIOD_S = 1e-3


def register(sub) -> None:
    from hybridtable.commands._common import add_log_arguments
    from hybridtable.commands._model_options import add_plugin_argument

    p = sub.add_parser(
        "effects",
        help="list the registered physical effects with their parameters, units and bounds",
        description="List every registered physical effect (built-in, from installed "
        "packages through the entry-point group hybridtable.effects, or from --plugin) "
        "with its parameters, units, bounds, typical change and null value (the value "
        "at which the effect vanishes), its stage (replay or closed loop) and a one-line "
        "description. Bounds relative to the rig (marked *) are evaluated at a reference "
        "rig: the paper's Table 1 point, or the rig of --rig RUN. The console opens with "
        "one sentence; --json gives a list of one object per effect.",
    )
    p.add_argument(
        "--json",
        metavar="FILE",
        help="write the list of effects as JSON (- for stdout, then nothing else is printed)",
    )
    add_plugin_argument(p)
    p.add_argument(
        "--rig",
        metavar="RUN",
        help="evaluate the bounds at the rig of these recorded runs (a run's .csv or "
        ".json, or a folder; the fastest approach velocity of them) (default: the "
        "paper's Table 1 point: k = 1e5 N/m, m = 2533 kg, v = 0.1 m/s, sensor delay "
        "5 ms, table 25 Hz, sampled at 1 kHz)",
    )
    add_log_arguments(p)
    p.set_defaults(func=run)


def paper_scale():
    """The :class:`~hybridtable.effects.effect.RigScale` of the paper's Table 1
    point, sampled at :data:`PAPER_SAMPLE_PERIOD_S`."""
    from hybridtable.effects.spec import RigScale
    from hybridtable.studies.paper import table1_params

    return RigScale.from_params(table1_params("none"), PAPER_SAMPLE_PERIOD_S)


def _scale_json(scale, where: str) -> dict:
    return {
        "rig": where,
        "stiffness_n_per_m": scale.stiffness_n_per_m,
        "mass_kg": scale.mass_kg,
        "sample_period_s": scale.sample_period_s,
        "sensor_delay_s": scale.sensor_delay_s,
        "velocity_m_per_s": scale.velocity_m_per_s,
        "table_frequency_hz": scale.table_frequency_hz,
        "peak_deflection_m": scale.peak_deflection_m,
        "peak_force_n": scale.peak_force_n,
    }


def effect_json(effect, source: str, scale, where: str) -> dict:
    """One effect as a JSON object, its bounds evaluated at ``scale`` (the rig ``where``)."""
    params = []
    for p in effect.parameters:
        lower, upper = p.bounds(scale)
        fields = {"lower": p.lower, "upper": p.upper, "typical": p.scale, "null": p.null}
        params.append(
            {
                "name": p.name,
                "unit": p.unit,
                "description": p.description,
                "lower": lower,
                "upper": upper,
                "typical": p.typical(scale),
                "null": p.null_value(scale),
                "bounds_depend_on_rig": callable(p.lower) or callable(p.upper),
                "rig_dependent": [k for k, v in fields.items() if callable(v)],
            }
        )
        if params[-1]["null"] is None:
            params[-1]["note"] = (
                "null null: no value of this parameter removes the effect (its absence is "
                "another parameter's null)"
            )
    sig = effect.signature
    return {
        "name": effect.name,
        "description": effect.description,
        "parameters": params,
        "stage": effect.stage,
        "default_for": list(effect.default_for),
        "loops": list(effect.loops),
        "cor_engine": cor_engine(effect, scale) if effect.apply is not None else "6-DoF only",
        "signature": {
            "channels": list(sig.channels),
            "phases": list(sig.phases),
            "text": sig.text,
        },
        "source": source,
        "touches": list(effect.touches),
        "separation_hint": effect.separation_hint,
        "bounds_at": _scale_json(scale, where),
    }


def cor_engine(effect, scale) -> str:
    """How ``explain`` runs a loop with ``effect`` for a CoR
    (:func:`~hybridtable.explain.model.loop_of`): ``"fast engine"`` when every
    change is one of the loop's parameters, else ``"Drake diagram"`` (the
    systems that carry it); on the paper's Table 1 conditions with a 1 kHz rig
    computer, every parameter one typical change from its null."""
    from hybridtable.explain.conditions import Conditions
    from hybridtable.explain.model import EffectAt, loop_of

    at = EffectAt(effect, scale)
    case = ("SDMDC", Conditions(sample_rate_hz=1.0 / PAPER_SAMPLE_PERIOD_S))
    try:
        _, systems = loop_of(case, (at,), at.probe_values())
    except ParameterError as err:
        return f"cannot: {err}"
    return "fast engine" if systems is None else "Drake diagram"


def _number(x: float | None, rig: bool) -> str:
    text = "-" if x is None else f"{x:.4g}"
    return text + ("*" if rig else " ")


def format_effects(items: list[dict]) -> str:
    """The console text of :func:`effect_json` objects: one sentence, the rig
    the bounds are evaluated at, and the table."""
    from hybridtable.effects.registry import SOURCES

    counts = {s: sum(1 for e in items if e["source"] == s) for s in SOURCES}
    plugins = counts["entry point"] + counts["plug-in"]
    head = (
        f"{len(items)} effects registered ({counts['built-in']} built-in, {plugins} from plug-ins"
    )
    parts = []
    if counts["entry point"]:
        parts.append(f"{counts['entry point']} from entry points")
    if counts["plug-in"]:
        parts.append(f"{counts['plug-in']} by --plugin")
    if parts:
        head += ": " + ", ".join(parts)
    if counts["script"]:
        head += f"; {counts['script']} registered by a script"
    head += ")."
    lines = [head]
    if items:
        s = items[0]["bounds_at"]
        lines.append(
            f"Values marked * depend on the rig; evaluated at {s['rig']}: "
            f"k = {s['stiffness_n_per_m']:.4g} N/m, m = {s['mass_kg']:.4g} kg, "
            f"h = {s['sample_period_s']:.4g} s, T = {s['sensor_delay_s']:.4g} s, "
            f"v = {s['velocity_m_per_s']:.4g} m/s, f_table = {s['table_frequency_hz']:.4g} Hz "
            f"(peak deflection {s['peak_deflection_m']:.4g} m, peak force "
            f"{s['peak_force_n']:.4g} N)."
        )
    lines.append("")
    header = (
        f"{'effect':<28}{'source':<12}{'stage':<12}{'tried by':<18}{'CoR by':<15}"
        f"{'loops':<13}description\n"
        f"  {'parameter':<30}{'unit':<8}{'lower':>12}{'upper':>12}{'typical':>12}"
        f"{'null':>12}  description"
    )
    lines.append(header)
    lines.append("-" * 117)
    for e in items:
        tried = ", ".join(e["default_for"]) or "when named"
        lines.append(
            f"{e['name']:<28}{e['source']:<12}{e['stage']:<12}{tried:<18}{e['cor_engine']:<15}"
            f"{', '.join(e['loops']):<13}{e['description']}"
        )
        for p in e["parameters"]:
            rig = set(p["rig_dependent"])
            lines.append(
                f"  {p['name']:<30}{p['unit']:<8}"
                f"{_number(p['lower'], 'lower' in rig):>12}"
                f"{_number(p['upper'], 'upper' in rig):>12}"
                f"{_number(p['typical'], 'typical' in rig):>12}"
                f"{_number(p['null'], 'null' in rig):>12}  {p['description']}"
            )
    lines.append("")
    lines.append(
        "typical: the fit's unit step; null: the value at which the effect vanishes "
        "(- : none). tried by: the commands that try the effect unless told which "
        "(diagnose --effects, explain --effects name any effect); CoR by: how explain runs "
        "the loop with it; loops: the 1-D loop's runs and tables, 6-DoF runs (simulate6 "
        "--add, compare and diagnose of hybridtable-run6/1 runs: diagnose tries every effect "
        "with 6-DoF among its loops). Use an effect with --add NAME[:param=value,...]."
    )
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import (
        check_outputs,
        input_paths,
        log_layout_of,
        write_json,
    )
    from hybridtable.effects.registry import effect_names, effect_source, get_effect, load_plugin
    from hybridtable.effects.spec import RigScale

    effect_names()  # registers the entry points' effects before the plug-ins
    for text in args.plugin:
        load_plugin(text)
    inputs = []
    if args.rig:
        from hybridtable.measurement.run_reader import read_runs

        runs = read_runs([args.rig], layout=log_layout_of(args))
        inputs = input_paths(runs)
        scale = RigScale.from_runs(runs)
        ids = ", ".join(r.run_id for r in runs)
        where = f"the rig of {args.rig} ({ids})"
    else:
        scale = paper_scale()
        where = "the paper's Table 1 point"
    check_outputs(args, inputs, files={"--json": args.json})
    names = effect_names()
    items = [effect_json(get_effect(n), effect_source(n), scale, where) for n in names]
    if args.json != "-":
        print(format_effects(items))
    if args.json:
        # a document like every command's: what it was asked, then the list
        write_json(args.json, {"registered": len(items), "effects": items}, args)
    return 0
