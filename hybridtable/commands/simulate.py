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
    _add_stewart_arguments(p)
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

    from hybridtable.commands._common import (
        check_outputs,
        check_suffix,
        figure_suffixes,
        write_json,
    )
    from hybridtable.commands._loop_options import params_from_args
    from hybridtable.commands._model_options import load_model_arg, load_plugins
    from hybridtable.errors import CommandError
    from hybridtable.loop.simulation import simulate

    load_plugins(args)
    model = load_model_arg(args)
    check_outputs(args, files={"--json": args.json, "--plot": args.plot, "--html": args.html})
    if args.plot:
        check_suffix("--plot", args.plot, figure_suffixes())
    check_suffix("--html", args.html, (".html", ".htm"))
    if args.record or model is not None:
        from hybridtable.commands._record import run_record
        from hybridtable.commands._simulate_rig import run_model

        if args.plot:
            raise CommandError("--plot is for one simulation (not with --record or --model)")
        if args.scenario:
            raise CommandError(
                "--scenario sets one simulation's rig (not with --record or --model)"
            )
        if args.table == "stewart" or _stewart_flags_given(args):
            raise CommandError(
                "--table stewart simulates one contact (not with --record or --model)"
            )
        out = run_record(args, model) if args.record else run_model(args, model)
        if args.json:
            write_json(args.json, out, args)
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
    stewart_show = None
    if args.table == "stewart":
        result, params, extra, stewart_show = _run_stewart(args, params)
    elif _stewart_flags_given(args):
        raise CommandError(f"{' '.join(_stewart_flags_given(args))}: needs --table stewart")
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
        # The loop simulated: every quantity by its flat name, defaults applied.
        "params": params.quantities(),
        **extra,
    }
    if args.json != "-":
        from hybridtable.reports.verdicts import contact_verdict

        damped = params.contact_damping_n_s_per_m > 0 or bool(args.add)
        verdict = contact_verdict(params.compensator, m.cor, damped=damped)
        if args.table == "stewart":
            verdict = f"On the Stewart table, {verdict[0].lower()}{verdict[1:]}"
        print(verdict)
        print(
            f"{params.compensator}: CoR {m.cor:.5f}  peak force {m.peak_force_n:.1f} N  "
            f"contact {m.contact_duration_s:.4f} s  energy gain {m.energy_gain_j:+.4g} J  "
            f"({wall:.2f} s)"
        )
    if args.json:
        write_json(args.json, out, args)
    if args.plot:
        from hybridtable.reports.figures import plot_run

        plot_run(result, args.plot)
    if stewart_show is not None:
        stewart_show()
    return 0


def _add_stewart_arguments(p: argparse.ArgumentParser) -> None:
    """The options that show a Stewart run (``--table stewart``)."""
    from hybridtable.commands._common import number_type

    g = p.add_argument_group("seeing a Stewart run (--table stewart)")
    g.add_argument(
        "--html",
        metavar="FILE.html",
        help="record the run as a Meshcat animation in a self-contained HTML file "
        "(about 2 MB; open it in a browser)",
    )
    g.add_argument(
        "--meshcat",
        action="store_true",
        help="show the run in a live Meshcat view (a server on localhost; its URL is "
        "printed); from a terminal it plays in a loop until Enter or Ctrl-C, otherwise once",
    )
    g.add_argument(
        "--magnify",
        type=number_type("0.001..1e6"),
        metavar="X",
        help="draw the platform's displacement from home X times larger, 0.001 to 1e+06 (the physics is "
        "unchanged) (default: a round factor that draws the peak displacement at about "
        "10%% of the platform's radius)",
    )
    g.add_argument(
        "--realtime-rate",
        type=number_type("0.001..1000"),
        metavar="R",
        help="play the motion at R times real time, 0.001 to 1000, e.g. 0.2 for slow motion (default 1)",
    )


def _stewart_flags_given(args: argparse.Namespace) -> list[str]:
    """The options of :func:`_add_stewart_arguments` given on the command line."""
    given = [("--html", args.html is not None), ("--meshcat", args.meshcat)]
    given += [("--magnify", args.magnify is not None)]
    given += [("--realtime-rate", args.realtime_rate is not None)]
    return [flag for flag, on in given if on]


def _check_stewart_args(args: argparse.Namespace, params) -> None:
    """Refuse, before any simulation, what the Stewart table cannot run, with
    the flags to change (:func:`~hybridtable.stewart.run.check_stewart_loop`
    in the command line's words), and drawing options without a drawing."""

    from hybridtable.commands._common import flag_words
    from hybridtable.commands._loop_options import LOOP_OPTIONS
    from hybridtable.errors import CommandError, ParameterError
    from hybridtable.stewart.run import check_stewart_loop

    if (args.magnify is not None or args.realtime_rate is not None) and not (
        args.html or args.meshcat
    ):
        raise CommandError("--magnify and --realtime-rate set the drawing of --html or --meshcat")
    try:
        check_stewart_loop(params)
    except ParameterError as err:
        raise CommandError(flag_words(str(err), LOOP_OPTIONS)) from None


def _run_stewart(args: argparse.Namespace, params):
    """The Stewart branch of :func:`run`: simulate with a progress bar, and
    return ``(result, params, JSON fields, show)``; ``show()`` (after the
    summary lines) writes ``--html`` and plays ``--meshcat``."""
    import math
    import sys

    from hybridtable.errors import CommandError, ParameterError, SimulationError, WorkspaceError
    from hybridtable.stewart.run import DEFAULT_SAMPLE_RATE_HZ, simulate_stewart
    from hybridtable.stewart.view import auto_force_scale_n_per_m, auto_magnify

    _check_stewart_args(args, params)
    try:
        run_ = simulate_stewart(params, progress=True)
    except WorkspaceError as err:
        v, f = params.initial_velocity_m_per_s, params.contact_frequency_hz
        raise SimulationError(  # the run failed (exit 1), its parameters were valid
            f"the Stewart table left its workspace during the run: {err}. The devices "
            f"penetrate about --initial-velocity-m-per-s / (2 pi --contact-frequency-hz) = "
            f"{v / (2.0 * math.pi * f):.3f} m; lower --initial-velocity-m-per-s or raise "
            "--contact-frequency-hz"
        ) from None
    except ParameterError as err:
        if not str(err).startswith(("could not tune", "the table does not follow")):
            raise
        rate = params.sample_rate_hz or DEFAULT_SAMPLE_RATE_HZ
        raise CommandError(
            f"the Stewart table could not be tuned to --table-response-hz "
            f"{params.table_response_hz:g} with --table-damping-ratio "
            f"{params.table_damping_ratio:g} at --sample-rate-hz {rate:g} (its leg servo is "
            "too slow for it); give a lower --table-response-hz or a higher --sample-rate-hz"
        ) from None
    extra = run_.summary()
    drawing = None
    if args.html or args.meshcat:
        motion, radius = run_.motion, run_.stewart.geometry.top_radius_m
        drawing = {
            "magnify": args.magnify or auto_magnify(motion.peak_displacement_m, radius),
            "force_arrow_n_per_m": auto_force_scale_n_per_m(motion.peak_force_n),
            "realtime_rate": args.realtime_rate or 1.0,
            "peak_plate_displacement_m": motion.peak_displacement_m,
        }
        extra["drawing"] = drawing

    def show() -> None:
        if args.json != "-":
            step = run_.step
            print(
                f"Stewart table identified as {step.response_frequency_hz:.2f} Hz, damping "
                f"ratio {step.damping_ratio:.3f}; the 1-D loop with that table gives CoR "
                f"{run_.second_order_cor:.5f}"
            )
        if drawing is not None:
            out = sys.stderr if args.json == "-" else sys.stdout
            _show_stewart(args, run_, drawing, out)

    return run_.result, run_.params, extra, show


def _show_stewart(args: argparse.Namespace, run_, drawing: dict, out) -> None:
    """Write ``--html`` and play ``--meshcat`` (after the summary lines)."""
    import sys

    from hybridtable.errors import CommandError
    from hybridtable.stewart.view import open_meshcat, show_live

    motion = run_.motion
    magnify, force_scale = drawing["magnify"], drawing["force_arrow_n_per_m"]
    rate = drawing["realtime_rate"]
    peak_mm = 1e3 * motion.peak_displacement_m
    print(
        f"Drawing: the plate's displacement magnified x{magnify:g} (peak {peak_mm:.1f} mm drawn "
        f"as {magnify * peak_mm:.0f} mm); the contact force as a red arrow, 1 m per "
        f"{force_scale:g} N (peak {motion.peak_force_n:.0f} N); {rate:g} x real time",
        file=out,
    )
    if args.html:
        run_.write_html(args.html, magnify=magnify, realtime_rate=rate, overwrite=True)
        print(f"Recording: {args.html}", file=out)
    if args.meshcat:
        try:
            meshcat = open_meshcat()
        except RuntimeError as err:
            raise CommandError(f"--meshcat: could not start a Meshcat server ({err})") from None
        view = run_.view(meshcat, magnify=magnify, force_scale_n_per_m=force_scale)
        print(f"Meshcat live view: {meshcat.web_url()}", file=out, flush=True)
        show_live(
            view,
            rate,
            interactive=sys.stdin.isatty(),
            say=lambda line: print(line, file=out, flush=True),
        )


def _simulate_with_effects(args: argparse.Namespace, params):
    """The paper's loop with the ``--add`` effects (every parameter given)."""
    from hybridtable.commands._simulate_rig import rig_physics
    from hybridtable.effects.spec import RigScale
    from hybridtable.errors import CommandError
    from hybridtable.loop.builder import build_hybrid_loop
    from hybridtable.loop.simulation import run_loop

    scale = RigScale.from_params(params, params.sample_period_s or params.step_s)
    physics, spec, _ = rig_physics(args, None, scale)
    params = physics.apply(params)  # the effects' changes of the loop (spec.with_loop)
    changes_sensor = bool(spec.sensor) or any(c == "sensor" for c, _ in spec.wrappers)
    if changes_sensor and params.sample_period_s is None:
        raise CommandError("--add: effects of the force sensor need --sample-rate-hz")
    if spec.mass_ratio != 1.0:
        from hybridtable.measurement.rig import model_mass_kg

        params = params.with_(
            spacecraft_mass_kg=model_mass_kg(params.spacecraft_mass_kg, spec.mass_ratio)
        )
    loop = build_hybrid_loop(
        params,
        table=physics.make_table(params),
        contact=physics.make_contact(params),
        sensor=physics.make_sensor(params) if changes_sensor else None,
    )
    return run_loop(loop), params
