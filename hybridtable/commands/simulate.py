"""``hybridtable simulate``: one run of the hybrid loop."""

from __future__ import annotations

import argparse
import math
import time

__all__ = ["register", "run"]


def register(sub) -> None:
    from hybridtable.commands._loop_options import add_loop_arguments
    from hybridtable.commands._model_options import (
        add_effect_argument,
        add_model_argument,
        add_plugin_argument,
    )
    from hybridtable.commands._record import add_record_arguments

    p = sub.add_parser(
        "simulate",
        help="simulate one contact of the hybrid loop",
        description="Simulate one contact of the 1-D hybrid loop and print its CoR, "
        "peak force, contact duration and energy gain.",
    )
    add_loop_arguments(p)
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument("--plot", metavar="FILE.png", help="plot positions, velocity and forces")
    p.add_argument(
        "--table",
        choices=("second-order", "stewart"),
        default="second-order",
        help="table back-end: the second-order model, or the Stewart platform "
        "(MultibodyPlant, tuned to --table-response-hz; sampled loop, default 1000 Hz)",
    )
    p.add_argument(
        "--html", metavar="FILE.html", help="record a Meshcat animation (--table stewart)"
    )
    add_effect_argument(
        p, ": give every parameter, e.g. --add contact_damping:damping_n_s_per_m=300"
    )
    add_model_argument(
        p,
        "simulate the rig it describes (its sampled computer, nominal parameters and "
        "effects); without loop options, each run it was fitted to, against its recorded CoR",
    )
    add_plugin_argument(p)
    add_record_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import write_json
    from hybridtable.commands._loop_options import params_from_args
    from hybridtable.commands._model_options import load_model_arg, load_plugins
    from hybridtable.errors import CommandError
    from hybridtable.loop.simulation import simulate

    load_plugins(args)
    model = load_model_arg(args)
    if args.record or model is not None:
        from hybridtable.commands._record import run_record
        from hybridtable.commands._simulate_rig import run_model

        if args.plot:
            raise CommandError("--plot is for one simulation (not with --record or --model)")
        out = run_record(args, model) if args.record else run_model(args, model)
        if args.json:
            write_json(args.json, out)
        return 0
    for flag in ("runs", "velocities", "noise_force_n", "noise_position_m", "duration_s"):
        if getattr(args, flag) is not None:
            raise CommandError(f"--{flag.replace('_', '-')} needs --record DIR")
    if args.compensator is not None and "," in args.compensator:
        raise CommandError("--compensator: one compensator (a list only with --record)")
    params = params_from_args(args)
    t0 = time.perf_counter()
    extra = {}
    if args.table == "stewart" and args.add:
        raise CommandError("--add: effects need the second-order table back-end")
    if args.table == "stewart":
        from hybridtable.stewart.run import simulate_stewart

        run_ = simulate_stewart(params, html=args.html)
        result, params, extra = run_.result, run_.params, run_.summary()
    elif args.html:
        from hybridtable.errors import CommandError

        raise CommandError("--html needs --table stewart")
    elif args.add:
        result, params = _simulate_with_effects(args, params)
    else:
        result = simulate(params)
    wall = time.perf_counter() - t0
    m = result.metrics
    out = {
        "compensator": params.compensator,
        "cor": m.cor,
        "peak_force_n": m.peak_force_n,
        "contact_duration_s": m.contact_duration_s,
        "energy_gain_j": m.energy_gain_j,
        "v_in_m_per_s": m.v_in_m_per_s,
        "v_out_m_per_s": m.v_out_m_per_s,
        "peak_compensated_force_n": m.peak_compensated_force_n,
        "spacecraft_mass_kg": params.spacecraft_mass_kg,
        "effective_delay_s": params.effective_delay_s,
        "cor_estimate_uncompensated": math.exp(
            math.pi**2 * params.contact_frequency_hz * params.effective_delay_s
        ),
        "wall_time_s": wall,
        **extra,
    }
    if args.json != "-":
        print(
            f"{params.compensator}: CoR {m.cor:.5f}  peak force {m.peak_force_n:.1f} N  "
            f"contact {m.contact_duration_s:.4f} s  energy gain {m.energy_gain_j:+.4g} J  "
            f"({wall:.2f} s)"
        )
    if args.json:
        write_json(args.json, out)
    if args.plot:
        from hybridtable.reports.figures import plot_run

        plot_run(result, args.plot)
    return 0


def _simulate_with_effects(args: argparse.Namespace, params):
    """The paper's loop with the ``--add`` effects (every parameter given)."""
    from hybridtable.commands._simulate_rig import rig_physics
    from hybridtable.diagnosis.effects import RigScale
    from hybridtable.errors import CommandError
    from hybridtable.loop.builder import build_hybrid_loop
    from hybridtable.loop.simulation import run_loop

    scale = RigScale.from_params(params, params.sample_period_s or params.step_s)
    physics, spec, _ = rig_physics(args, None, scale)
    changes_sensor = bool(spec.sensor) or any(c == "sensor" for c, _ in spec.wrappers)
    if changes_sensor and params.sample_period_s is None:
        raise CommandError("--add: effects of the force sensor need --sample-rate-hz")
    if spec.mass_ratio != 1.0:
        params = params.with_(spacecraft_mass_kg=params.spacecraft_mass_kg * spec.mass_ratio)
    loop = build_hybrid_loop(
        params,
        table=physics.make_table(params),
        contact=physics.make_contact(params),
        sensor=physics.make_sensor(params) if changes_sensor else None,
    )
    return run_loop(loop), params
