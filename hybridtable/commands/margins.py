"""``hybridtable margins``: linear stability margins over sensor delay x table frequency."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

__all__ = ["register", "run", "parse_list", "default_delays"]

DEFAULT_DELAYS = "0:0.02:41"
DEFAULT_TABLES = "5:200:40"


def parse_list(text: str, name: str) -> np.ndarray:
    """``"a,b,c"`` or ``"start:stop:count"`` (``count`` evenly spaced values,
    both ends included) as a float array.

    Raises
    ------
    CommandError
        On malformed input (one line, names the option).
    """
    from hybridtable.errors import CommandError

    text = text.strip()
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop = float(parts[0]), float(parts[1])
            count = int(parts[2])
            if count < 1 or not (math.isfinite(start) and math.isfinite(stop)):
                raise ValueError
            values = np.linspace(start, stop, count)
        else:
            values = np.array([float(v) for v in text.split(",") if v.strip() != ""])
    except ValueError:
        raise CommandError(
            f"{name}: expected comma-separated numbers or start:stop:count, got {text!r}"
        ) from None
    if values.size == 0 or np.isnan(values).any():
        raise CommandError(f"{name}: expected at least one number, got {text!r}")
    return values


def default_delays(sample_rate_hz: float | None) -> np.ndarray:
    """0-20 ms: 41 values, or whole sample periods up to 20 ms when sampled
    (at most 81 values)."""
    if sample_rate_hz is None:
        return np.linspace(0.0, 0.02, 41)
    h = 1.0 / sample_rate_hz
    n = int(math.floor(0.02 / h + 1e-9))
    samples = np.unique(np.round(np.linspace(0, n, min(n + 1, 81))).astype(int))
    return samples * h


def register(sub) -> None:
    from hybridtable.commands._common import parse_float

    p = sub.add_parser(
        "margins",
        help="linear stability margins over sensor delay x table frequency",
        description="Linearize the in-contact hybrid loop with Drake (bilateral contact, "
        "ungated compensator; Pade delay, or a sampled-data model with --sample-rate-hz) and "
        "give, per compensator and grid point, the predicted CoR, damping ratio, phase margin "
        "and effective delay, with the critical sensor delay per table frequency and the "
        "critical table frequency per delay. Other parameters: the paper's Table 1.",
    )
    p.add_argument(
        "--compensator",
        default="none,SDC,MDC,SDMDC",
        help="comma-separated compensators (default: all four)",
    )
    p.add_argument(
        "--sensor-delay-s",
        metavar="LIST",
        default=None,
        help="delays, 'a,b,c' or 'start:stop:count' (default 0:0.02:41; sampled: whole "
        "samples up to 20 ms)",
    )
    p.add_argument(
        "--table-response-hz",
        metavar="LIST",
        default=DEFAULT_TABLES,
        help=f"table response frequencies, same syntax, inf = ideal (default {DEFAULT_TABLES})",
    )
    p.add_argument("--table-damping-ratio", type=parse_float, default=0.8, metavar="Z")
    p.add_argument("--contact-frequency-hz", type=parse_float, default=1.0, metavar="F")
    p.add_argument("--contact-stiffness-n-per-m", type=parse_float, default=1e5)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--contact-damping-n-s-per-m", type=parse_float, default=None)
    g.add_argument(
        "--contact-damping-ratio",
        type=parse_float,
        default=None,
        help="contact damping as a ratio c / (2 sqrt(k m))",
    )
    p.add_argument(
        "--lead-time-s", type=parse_float, default=None, help="SDC lead (default: the delay)"
    )
    p.add_argument(
        "--initial-velocity-m-per-s",
        type=parse_float,
        default=0.1,
        help="approach velocity of the validation runs",
    )
    p.add_argument(
        "--sample-rate-hz",
        type=parse_float,
        default=None,
        metavar="R",
        help="sampled-data model of a rig computer at R Hz (delays must be whole samples)",
    )
    p.add_argument("--pade-order", type=int, default=3, metavar="N", help="default 3")
    p.add_argument(
        "--validate",
        type=int,
        default=0,
        metavar="N",
        help="run the nonlinear simulation at N grid points per compensator",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--report", metavar="DIR", help="write heatmaps, critical curves, Bode plot, summary.md"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def _base_params(args: argparse.Namespace):
    from hybridtable.errors import CommandError
    from hybridtable.studies.paper import paper_params

    base = paper_params(
        sensor_delay_s=0.0,  # the grid sets it
        table_damping_ratio=args.table_damping_ratio,
        contact_frequency_hz=args.contact_frequency_hz,
        contact_stiffness_n_per_m=args.contact_stiffness_n_per_m,
        initial_velocity_m_per_s=args.initial_velocity_m_per_s,
        lead_time_s=args.lead_time_s,
        sample_rate_hz=args.sample_rate_hz,
    )
    if args.contact_damping_ratio is not None:
        if not (math.isfinite(args.contact_damping_ratio) and args.contact_damping_ratio >= 0):
            raise CommandError("--contact-damping-ratio must be >= 0")
        base = base.with_contact_damping_ratio(args.contact_damping_ratio)
    elif args.contact_damping_n_s_per_m is not None:
        base = base.with_(contact_damping_n_s_per_m=args.contact_damping_n_s_per_m)
    return base


def run(args: argparse.Namespace) -> int:
    from hybridtable.analysis.sweep import sweep_margins
    from hybridtable.analysis.validation import validate_sweep
    from hybridtable.commands._common import write_json
    from hybridtable.compensators.paper import COMPENSATORS
    from hybridtable.errors import CommandError
    from hybridtable.reports.margins import (
        REPORT_FILES,
        operating_point,
        table1_point,
        write_report,
    )
    from hybridtable.systems.sensor import delay_samples

    comps = [c.strip() for c in args.compensator.split(",") if c.strip()]
    for c in comps:
        if c not in COMPENSATORS:
            raise CommandError(f"--compensator: {c!r} is not one of {', '.join(COMPENSATORS)}")
    if not comps or len(set(comps)) != len(comps):
        raise CommandError("--compensator: give each compensator once")
    if args.pade_order < 1:
        raise CommandError("--pade-order must be >= 1")
    if args.validate < 0:
        raise CommandError("--validate must be >= 0")
    base = _base_params(args)
    delays = (
        default_delays(base.sample_rate_hz)
        if args.sensor_delay_s is None
        else parse_list(args.sensor_delay_s, "--sensor-delay-s")
    )
    tables = parse_list(args.table_response_hz, "--table-response-hz")
    if (delays < 0).any() or not np.isfinite(delays).all():
        raise CommandError("--sensor-delay-s: delays must be finite and >= 0")
    if (tables <= 0).any():
        raise CommandError("--table-response-hz: frequencies must be > 0 (inf: ideal table)")
    if base.sample_period_s is not None:
        for T in delays:
            delay_samples(float(T), base.sample_period_s)  # ParameterError if not whole
    if args.report is not None:
        d = Path(args.report)
        if d.exists() and not d.is_dir():
            raise CommandError(f"--report: {d} exists and is not a directory")
        taken = [name for name in REPORT_FILES if (d / name).exists()]
        if taken:
            raise CommandError(f"--report: {d / taken[0]} exists; choose another directory")
    progress = not args.no_progress and args.json != "-"

    t0 = time.perf_counter()
    result = sweep_margins(
        base, delays, tables, comps, pade_order=args.pade_order, progress=progress
    )
    sweep_wall = time.perf_counter() - t0
    if args.validate:
        validate_sweep(result, args.validate, progress=progress)
    table1 = None
    if args.report is not None:
        table1 = operating_point(
            {c: table1_point(base.with_(compensator=c)) for c in comps},
            args.pade_order,
            simulate=True,
        )
        files = write_report(result, args.report, table1)
    wall = time.perf_counter() - t0

    data = result.to_json_dict()
    data["sweep_wall_time_s"] = sweep_wall
    data["wall_time_s"] = wall
    if table1 is not None:
        data["table1_point"] = table1.to_dict()
    if args.json != "-":
        _print_summary(result, sweep_wall)
        if args.report is not None:
            for f in files:
                print(f"wrote {f}")
        print(f"wall time {wall:.1f} s")
    if args.json:
        write_json(args.json, data)
    return 0


def _print_summary(result, sweep_wall: float) -> None:
    kind = (
        f"sampled at {result.base.sample_rate_hz:g} Hz"
        if result.sampled
        else f"Pade order {result.pade_order}"
    )
    print(
        f"grid {result.sensor_delay_s.size} delays x {result.table_response_hz.size} table "
        f"frequencies, {kind}: {sweep_wall:.1f} s"
    )
    print(
        f"{'compensator':12s} {'CoR min':>9s} {'CoR max':>9s} {'stable':>11s} {'crit. delay [ms]':>20s}"
    )
    for c, cs in result.compensators.items():
        cor = cs.predicted_cor[np.isfinite(cs.predicted_cor)]
        cd = cs.critical_delay_s * 1e3
        print(
            f"{c:12s} {cor.min():9.5f} {cor.max():9.5f} "
            f"{int(cs.stable.sum()):5d}/{cs.stable.size:<5d} "
            f"{np.nanmin(cd):9.3f}-{np.nanmax(cd):<9.3f}"
        )
    if result.validation:
        err = result.max_validation_error()
        n_fail = sum(v.abs_error is None for v in result.validation)
        print(
            f"validation: {len(result.validation)} simulations, max |CoR_linear - CoR_sim| "
            f"= {err:.5f}" + (f", {n_fail} failed" if n_fail else "")
            if err is not None
            else f"validation: all {n_fail} simulations failed"
        )
