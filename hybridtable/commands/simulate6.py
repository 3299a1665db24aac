"""``hybridtable simulate6 SCENARIO.toml``: one docking contact of the 6-DoF loop."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._common import number_type
    from hybridtable.commands._model_options import (
        add_effect_argument,
        add_model_argument,
        add_plugin_argument,
    )

    p = sub.add_parser(
        "simulate6",
        help="simulate one 6-DoF docking contact from a scenario file",
        description="Simulate one docking contact of the 6-DoF hybrid loop: a rigid "
        "spacecraft (mass, inertia tensor, docking port off its centre of mass), Drake's "
        "compliant contact of a ring of pads on a plate or of a probe in a drogue (geometry = "
        '"cone": hydroelastic, captured when the probe head passes the throat), the table '
        "model or the Stewart "
        "platform moved by full-pose inverse kinematics, a delayed 6-axis F/T sensor, and a "
        "compensator on the wrench (SDC, MDC with a 6x6 stiffness, SDMDC). Prints the CoR "
        "along the contact normal and the energy ratio against the ideal rig (no delay, ideal "
        "table), peak force and moment, and the modes of the loop linearized in contact. The "
        "scenario format is in docs/six_dof.md; examples in examples/six_dof/.",
    )
    p.add_argument("scenario", metavar="SCENARIO.toml", help="the scenario (TOML)")
    p.add_argument(
        "--compensator",
        metavar="NAME",
        help="replace the scenario's compensator: none, SDC, MDC, SDMDC, sdmdc-online (the "
        "contact's stiffness identified online) or a registered "
        "wrench compensator (default: the scenario's, else none)",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--html",
        metavar="FILE.html",
        help="write a Meshcat recording: the devices, the spacecraft, the table's legs and "
        "the contact force as an arrow (motion magnified)",
    )
    p.add_argument(
        "--plot", metavar="FILE.png", help="plot the six wrench components [N, N m] over time [s]"
    )
    p.add_argument(
        "--no-reference",
        action="store_true",
        help="skip the ideal rig's run (no delay, ideal table) the verdict compares with",
    )
    g = p.add_argument_group(
        "recording a run (--record DIR): a hybridtable-run6/1 run (docs/run6-format.md) as the "
        "rig's data logger would write it"
    )
    g.add_argument(
        "--record",
        metavar="DIR",
        help="write run1.csv and run1.json into DIR: the simulated run as the rig computer "
        "read it, with the scenario's noise ([rig] force_noise_n, moment_noise_n_m, "
        "position_noise_m, attitude_noise_rad, seed: inside the loop); existing files are "
        "replaced only with --force",
    )
    g.add_argument(
        "--noise-position-m",
        type=number_type("0..1", "m"),
        metavar="METRES",
        default=None,
        help="replace the scenario's [rig] position_noise_m: white noise on the table's "
        "measured position (its encoders, which the compensator reads), std per axis [m], "
        "0 to 1 (default: the scenario's, else 0)",
    )
    g.add_argument(
        "--noise-attitude-rad",
        type=number_type("0..0.1", "rad"),
        metavar="RADIANS",
        default=None,
        help="replace the scenario's [rig] attitude_noise_rad: a rotation of this std about "
        "each axis on the table's measured attitude [rad], 0 to 0.1 (default: the "
        "scenario's, else 0)",
    )
    add_effect_argument(
        p,
        ": the rig's physical part has it (a six-axis rig's effect or one of the 1-D loop's "
        "along the normal: hybridtable effects, column loops), the rig computer does not know "
        "it; every parameter given; with --record, the run's JSON states the scenario and "
        "truth.json what was hidden",
    )
    add_model_argument(
        p,
        "the rig's physical part (and computer) as a 6-DoF model file says (diagnose or "
        "compare --add on 6-DoF runs, --save-model), under this scenario; --add adds to it",
    )
    add_plugin_argument(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _progress(enabled: bool):
    if not enabled or not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=1.0, unit="s", leave=False, file=sys.stderr, desc="simulate6")

    def update(t: float, t_end: float) -> None:
        bar.total = t_end
        bar.n = t
        bar.refresh()

    return update, bar.close


def run(args: argparse.Namespace) -> int:
    import math

    from hybridtable.commands._common import (
        check_outputs,
        check_suffix,
        figure_suffixes,
        write_json,
    )
    from hybridtable.reports.six_dof import docking_verdict, format_docking
    from hybridtable.six_dof.linear import contact_modes
    from hybridtable.six_dof.scenario import load_scenario
    from hybridtable.six_dof.simulation import simulate6

    overrides = {} if args.compensator is None else {"compensator": args.compensator}
    for flag, name in (
        ("noise_position_m", "position_noise_m"),
        ("noise_attitude_rad", "attitude_noise_rad"),
    ):
        if getattr(args, flag) is not None:
            overrides[name] = getattr(args, flag)
    params = load_scenario(args.scenario, **overrides)
    physics, hidden = _hidden_physics(args, params)
    check_outputs(
        args,
        [args.scenario],
        files={"--json": args.json, "--plot": args.plot, "--html": args.html},
        folders={"--record": args.record},
    )
    if args.plot:
        check_suffix("--plot", args.plot, figure_suffixes())
    check_suffix("--html", args.html, (".html", ".htm"))
    if params.table == "stewart":
        from hybridtable.six_dof.stewart_backend import check_stewart_scenario

        check_stewart_scenario(params)
    quiet = args.json == "-"
    update, close = _progress(not args.no_progress and not quiet)
    try:
        result = simulate6(params, progress=update, physics=physics)
    finally:
        close()
    reference = None
    if not args.no_reference:
        reference = simulate6(params.ideal_rig()).metrics
    from hybridtable.six_dof.registry import linear_law

    # A plug-in that declares no linear law has no margins (not the "none" loop's).
    # the margins of the rig simulated: the scenario's, with the model's or
    # --add's effects where it has them
    modes = (
        contact_modes(params, physics=physics)
        if linear_law(params.compensator) is not None
        else None
    )
    m = result.metrics
    sim_s = float(result.time_s[-1]) if len(result.time_s) else 0.0
    out = {
        "scenario": str(args.scenario),
        "compensator": params.compensator,
        "table": params.table,
        "cor_normal": m.cor_normal,
        "energy_ratio": m.energy_ratio,
        "peak_force_n": m.peak_force_n,
        "peak_moment_n_m": m.peak_moment_n_m,
        "contact_duration_s": m.contact_duration_s,
        "metrics": m.to_dict(),
        "reference": None if reference is None else reference.to_dict(),
        "margins": None if modes is None else modes.to_dict(),
        "params": params.to_dict(),
        "simulated_s": sim_s,
        "wall_time_s": result.wall_time_s,
    }
    if hidden:
        out["hidden"] = {"effects": hidden, "physics": physics.to_dict()}
    identified = result.extra.get("identified_stiffness_n_per_m")
    if identified is not None:
        out["identified_stiffness_n_per_m"] = identified
    notes = [m.spin_note] if m.spin_note else []
    if m.spin_note:  # said beside the number too
        out["metrics"]["note"] = m.spin_note
    if reference is None:
        notes.append("reference null: --no-reference skipped the ideal rig's run")
    if modes is None:
        notes.append(
            f"margins null: the plug-in {params.compensator!r} declares no linear law "
            "(register_wrench_compensator(..., linear=LinearLaw(...)))"
        )
    if notes:
        out["note"] = "; ".join(notes)
    if modes is not None and math.isinf(modes.critical_delay_s):
        out["margins"]["note"] = "critical_delay_s inf: no mode grows at any delay up to 50 ms"
    if modes is not None and physics is not None:
        out["margins"]["rig"] = _margins_rig(params, physics)
    if not quiet:
        if reference is not None:
            print(docking_verdict(params.compensator, m, reference))
        else:
            print(
                f"{params.compensator}: CoR along the normal {m.cor_normal:.4f}, energy ratio "
                f"{m.energy_ratio:.4f}."
            )
        print(format_docking(params.compensator, m, reference, modes, result.wall_time_s, sim_s))
        if modes is not None and physics is not None:
            print(f"margins: {_margins_rig(params, physics)}")
        if identified is not None:
            print(
                f"identified contact stiffness {identified:.4g} N/m at the end (the compensator "
                f"believed {params.believed_contact.contact_stiffness_n_per_m:.4g}, the "
                f"contact's is {params.contact.contact_stiffness_n_per_m:.4g})"
            )
        if m.spin_note:
            print(f"note: {m.spin_note}")
    if args.plot:
        from hybridtable.reports.six_dof import plot_wrench

        plot_wrench(result, args.plot)
        out["plot"] = str(args.plot)
        if not quiet:
            print(f"wrote {args.plot}")
    if args.html:
        from hybridtable.six_dof.view import write_docking_html

        drawn = write_docking_html(result, args.html, overwrite=bool(args.force))
        out["html"] = drawn
        if not quiet:
            print(
                f"wrote {args.html} (motion magnified x{drawn['magnify']:g}, force arrow "
                f"1 m per {drawn['force_scale_n_per_m']:g} N)"
            )
    if hidden and not quiet:
        print(
            "the rig's physical part had "
            + "; ".join(
                f"{e['name']} ({', '.join(f'{k} = {v:g}' for k, v in e['values'].items())})"
                for e in hidden
            )
            + ", which the rig computer did not know"
        )
    if args.record:
        out["record"] = _record(args, result, hidden, physics)
        if not quiet:
            print(f"wrote {out['record']['csv']} and {out['record']['json']}")
    if args.json:
        write_json(args.json, out, args)
    return 0


def _margins_rig(params, physics) -> str:
    """Whose margins ``simulate6`` reports with effects, in words, and where
    the loop linearized in contact may not give the CoR: an MDC term of a
    constant stiffness (``nominal``, ``given``) gated by a reading that lags
    the contact (a low pass, a mount) pushes after the release."""
    from hybridtable.six_dof.registry import linear_law

    words = (
        "of the rig with the effects of --model/--add (the sensor delay scanned is the "
        "scenario's; the rig's is that plus the model's)"
    )
    law = linear_law(params.compensator)
    lags = physics.sensor_time_constant_s > 0.0 or physics.sensor_mount is not None
    if law is not None and law.law in ("MDC", "SDMDC") and lags:
        if params.stiffness_model in ("nominal", "given"):
            words += (
                "; the reading lags the contact, and the MDC term's gate reads it: after the "
                "release the term still pushes, which the loop in contact does not see "
                "(its CoR may be far from these margins'; docs/run6-format.md)"
            )
    return words


def _hidden_physics(args: argparse.Namespace, params):
    """The rig's physical part with ``--add``'s effects (every parameter
    given, within its bounds at the scenario), and the effects as JSON."""
    from hybridtable.commands._model_options import load_plugins, parse_added_given
    from hybridtable.errors import CommandError
    from hybridtable.six_dof.physics6 import NOMINAL_PHYSICS, physics_with, rig_scale

    load_plugins(args)
    added = parse_added_given(args, "(the rig's hidden value: nothing to fit it to here)")
    scale = rig_scale(params)
    checked = [(effect, effect.check_values(values, scale)) for effect, values in added]
    base, hidden = NOMINAL_PHYSICS, []
    if args.model:
        from hybridtable.six_dof.model6 import load_model6

        model = load_model6(args.model)
        for note in model.rig_differences([("the scenario", params)]):
            print(f"note: {note}", file=sys.stderr)
        base = model.physics()
        for e, _ in checked:
            if e.name in model.effect_names:
                raise CommandError(f"--add {e.name}: the model {args.model} has it already")
        hidden = [
            {
                "name": e.name,
                "values": dict(e.values),
                "units": {p.name: p.unit for p in e.effect.parameters},
                "model": args.model,
            }
            for e in model.effects
        ]
    physics = physics_with(checked, scale, base)
    hidden += [
        {
            "name": e.name,
            "values": dict(v),
            "units": {p.name: p.unit for p in e.parameters},
        }
        for e, v in checked
    ]
    return (physics if hidden else None), hidden


def _json_values(value):
    """A TOML document's values as JSON has them: an infinite number is the
    string ``"inf"`` (the scenario's own spelling of an ideal table)."""
    import math

    if isinstance(value, dict):
        return {k: _json_values(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_values(v) for v in value]
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return value


def _record(args: argparse.Namespace, result, hidden: list, physics) -> dict:
    """Write the run of ``--record`` (the scenario file's content, with the
    command line's compensator, as its JSON) and, with hidden effects,
    ``truth.json`` (what was hidden: nothing, without ``--add``)."""
    import json
    from pathlib import Path

    from hybridtable._files import staged_folder, write_text_atomic
    from hybridtable.loop.scenario import read_scenario
    from hybridtable.six_dof.run6 import run6_csv_text, run6_json, run6_of_docking

    scenario = _json_values(read_scenario(args.scenario))
    if args.compensator is not None:
        scenario.setdefault("compensator", {})["name"] = result.params.compensator
    noise = result.params.rig.noise
    for flag, key, value in (
        ("noise_position_m", "position_noise_m", noise.position_std_m),
        ("noise_attitude_rad", "attitude_noise_rad", noise.attitude_std_rad),
    ):
        if getattr(args, flag) is not None:
            scenario.setdefault("rig", {})[key] = value
    run_id = f"{Path(args.scenario).stem}-{result.params.compensator}"
    run = run6_of_docking(result, run_id, scenario)
    folder = Path(args.record)
    with staged_folder(folder) as stage:
        write_text_atomic(stage.path / "run1.csv", run6_csv_text(run))
        write_text_atomic(stage.path / "run1.json", json.dumps(run6_json(run), indent=2) + "\n")
        # always written: a run recorded again with --force has no older truth beside it
        from hybridtable.commands._record import TRUTH_FORMAT
        from hybridtable.effects.model_file import tool_version

        truth = {
            "format": TRUTH_FORMAT,
            "tool_version": tool_version(),
            "hidden": {
                "effects": hidden,
                "physics": None if physics is None else physics.to_dict(),
            },
            "runs": [{"run_id": run_id, "csv": "run1.csv", "json": "run1.json"}],
        }
        write_text_atomic(stage.path / "truth.json", json.dumps(truth, indent=2) + "\n")
    return {
        "folder": str(folder),
        "csv": str(folder / "run1.csv"),
        "json": str(folder / "run1.json"),
        "run_id": run_id,
        "ticks": run.n,
        "position_noise_m": noise.position_std_m,
        "attitude_noise_rad": noise.attitude_std_rad,
    }
