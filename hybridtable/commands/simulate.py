"""``hybridtable simulate``: one run of the hybrid loop."""

from __future__ import annotations

import argparse
import math
import time

__all__ = ["register", "add_loop_arguments", "params_from_args", "run"]


def add_loop_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by the commands that set up one loop (defaults: Table 1)."""
    from hybridtable.commands._common import parse_float
    from hybridtable.compensators.registry import compensator_names

    g = parser.add_argument_group("loop parameters (defaults: the paper's Table 1 point)")
    g.add_argument("--compensator", default="none", help=f"one of {', '.join(compensator_names())}")
    g.add_argument("--sensor-delay-s", type=parse_float, default=0.005)
    g.add_argument("--table-response-hz", type=parse_float, default=25.0, help="inf: ideal table")
    g.add_argument("--table-damping-ratio", type=parse_float, default=0.8)
    g.add_argument("--contact-frequency-hz", type=parse_float, default=1.0)
    g.add_argument("--contact-stiffness-n-per-m", type=parse_float, default=1e5)
    g.add_argument("--contact-damping-n-s-per-m", type=parse_float, default=0.0)
    g.add_argument("--initial-velocity-m-per-s", type=parse_float, default=0.1)
    g.add_argument("--initial-gap-m", type=parse_float, default=0.001)
    g.add_argument(
        "--lead-time-s", type=parse_float, default=None, help="default: the sensor delay"
    )
    g.add_argument(
        "--compensator-stiffness-n-per-m",
        type=parse_float,
        default=None,
        help="stiffness the compensator believes (MDC, SDMDC, smith) or starts from "
        "(sdmdc-online's prior); default: the true one",
    )
    g.add_argument(
        "--passivity",
        action="store_true",
        help="guard the compensator with the time-domain passivity observer/controller",
    )
    g.add_argument("--force-deadband-n", type=parse_float, default=0.0)
    g.add_argument("--clamp-nonnegative", action="store_true", help="clamp f_comp at zero")
    g.add_argument(
        "--sample-rate-hz",
        type=parse_float,
        default=None,
        help="sampled rig computer (default: continuous)",
    )
    g.add_argument(
        "--time-step-s",
        type=parse_float,
        default=None,
        help="continuous-mode step (default: min(2e-4, 1/(5000 f_con)))",
    )


def params_from_args(args: argparse.Namespace):
    """HybridLoopParams from the options of :func:`add_loop_arguments`."""
    from hybridtable.studies.paper import paper_params

    return paper_params(
        compensator=args.compensator,
        sensor_delay_s=args.sensor_delay_s,
        table_response_hz=args.table_response_hz,
        table_damping_ratio=args.table_damping_ratio,
        contact_frequency_hz=args.contact_frequency_hz,
        contact_stiffness_n_per_m=args.contact_stiffness_n_per_m,
        initial_velocity_m_per_s=args.initial_velocity_m_per_s,
        contact_damping_n_s_per_m=args.contact_damping_n_s_per_m,
        initial_gap_m=args.initial_gap_m,
        lead_time_s=args.lead_time_s,
        compensator_stiffness_n_per_m=args.compensator_stiffness_n_per_m,
        force_deadband_n=args.force_deadband_n,
        clamp_nonnegative=args.clamp_nonnegative,
        sample_rate_hz=args.sample_rate_hz,
        time_step_s=args.time_step_s,
        passivity=getattr(args, "passivity", False),
    )


def register(sub) -> None:
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
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hybridtable.commands._common import write_json
    from hybridtable.loop.simulation import simulate

    params = params_from_args(args)
    t0 = time.perf_counter()
    extra = {}
    if args.table == "stewart":
        from hybridtable.stewart.run import simulate_stewart

        run_ = simulate_stewart(params, html=args.html)
        result, params, extra = run_.result, run_.params, run_.summary()
    elif args.html:
        from hybridtable.errors import CommandError

        raise CommandError("--html needs --table stewart")
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
