"""``hybridtable margins``: linear stability margins over sensor delay x table frequency;
at one operating point the gain, phase and delay margins (and, with
``--export-linear``, the linear loop as a file python-control loads); with
``--model``, of the rig a model file describes."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from hybridtable.commands._grid import DEFAULT_TABLES, default_delays, parse_list
from hybridtable.commands._loop_options import LOOP_OPTIONS, add_loop_option
from hybridtable.laws.contact import mass_for_contact_frequency_kg
from hybridtable.limits import TABLE1_DEFAULTS

__all__ = ["register", "run"]

#: Defaults of the rig options without ``--model`` (None in the parser, so
#: that ``--model`` can tell an option given from one left alone).
RIG_DEFAULTS = {
    name: LOOP_OPTIONS[name][0]
    for name in (
        "table_damping_ratio",
        "contact_frequency_hz",
        "contact_stiffness_n_per_m",
        "initial_velocity_m_per_s",
    )
}


def register(sub) -> None:
    from hybridtable.commands._common import integer_type, number_type
    from hybridtable.commands._model_options import add_model_argument, add_plugin_argument

    p = sub.add_parser(
        "margins",
        help="linear stability margins over sensor delay x table frequency",
        description="Linearize the in-contact hybrid loop with Drake (bilateral contact, "
        "ungated compensator; Pade delay, or a sampled-data model with --sample-rate-hz) and "
        "give, per compensator and grid point, the predicted CoR, damping ratio, phase margin "
        "and effective delay, with the critical sensor delay per table frequency and the "
        "critical table frequency per delay, the sensor delay up to which the CoR stays within "
        "--cor-limit, and at one operating point the gain, phase and delay margins (python-"
        "control, loop broken at the spacecraft model's force input). Other parameters: the "
        "paper's Table 1. With "
        "--model: the rig of a model file, its physics in the linear loop at every grid point, "
        "and its operating point against the nominal model and a simulation of the model.",
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
        help="sensor delays of the grid [s], 'a,b,c' or 'start:stop:count', each 0 to 1, at "
        "most 1000 values (default "
        "0:0.02:41; sampled: whole samples up to 0.02 s)",
    )
    p.add_argument(
        "--table-response-hz",
        metavar="LIST",
        default=DEFAULT_TABLES,
        help="table response frequencies of the grid [Hz], same syntax, each 0.1 to 10000, "
        f"inf = ideal table (default {DEFAULT_TABLES})",
    )
    model = "; with --model: the model's"
    add_loop_option(p, "table_damping_ratio", model + " rig's")
    add_loop_option(
        p,
        "contact_frequency_hz",
        model + " mass",
        "contact natural frequency, sets the spacecraft mass",
    )
    add_loop_option(p, "contact_stiffness_n_per_m", model + " rig's")
    g = p.add_mutually_exclusive_group()
    add_loop_option(g, "contact_damping_n_s_per_m", model)
    add_loop_option(g, "contact_damping_ratio")
    add_loop_option(p, "lead_time_s", "; with --model: the rig's lead time", "SDC lead")
    add_loop_option(
        p,
        "initial_velocity_m_per_s",
        model + " nominal one",
        "approach velocity of the validation runs",
    )
    add_loop_option(
        p,
        "sample_rate_hz",
        "; a delay between two samples reads both, mixed; with --model: the model's rig's rate",
        "sampled-data model of a rig computer at this rate",
    )
    p.add_argument(
        "--pade-order",
        type=integer_type(1, 10),
        default=3,
        metavar="N",
        help="order of the delay's Pade model, 1 to 10 (default 3)",
    )
    p.add_argument(
        "--validate",
        type=integer_type(0, 1000),
        default=0,
        metavar="N",
        help="run the nonlinear simulation at N grid points per compensator, 0 to 1000 (default 0)",
    )
    p.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    p.add_argument(
        "--report", metavar="DIR", help="write heatmaps, critical curves, Bode plot, report.md"
    )
    p.add_argument(
        "--cor-limit",
        type=number_type("0.001..1000"),
        default=1.01,
        metavar="COR",
        help="the CoR limit [1], 0.001 to 1000: report the largest sensor delay up to which the "
        "predicted CoR stays within it",
    )
    p.add_argument(
        "--operating-delay-s",
        type=number_type("sensor_delay_s"),
        default=None,
        metavar="SECONDS",
        help="sensor delay of the operating point of the gain/phase/delay margins and "
        "--export-linear [s], 0 to 1 (default 0.005, the paper's Table 1; with --model: the "
        "rig's)",
    )
    p.add_argument(
        "--operating-table-hz",
        type=number_type("table_response_hz"),
        default=None,
        metavar="HZ",
        help="table response frequency of the operating point [Hz], 0.1 to 10000, or inf (default 25, the "
        "paper's Table 1; with --model: the rig's)",
    )
    p.add_argument(
        "--export-linear",
        metavar="FILE",
        help="write the linear loop at the operating point (A, B, C, D, dt, state/input/"
        "output names and units, parameters) as FILE.json or FILE.npz, for control.ss",
    )
    p.add_argument(
        "--export-compensator",
        metavar="NAME",
        default=None,
        help="the compensator of --export-linear (default: SDMDC if listed, else the first "
        "listed; with --model: the rig's own if listed)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_model_argument(
        p,
        "the margins of the rig it describes (its nominal parameters, sampled at its rate; its "
        "effects in the linear loop at every grid point) and, at the rig's operating point, "
        "the nominal against the model's CoR and a simulation of the model",
    )
    add_plugin_argument(p)
    p.set_defaults(func=run)


def _model_base(args: argparse.Namespace, model):
    """The model's rig (:func:`~hybridtable.measurement.rig.rig_params` of its
    nominal run), the options given overriding it."""
    from hybridtable.measurement.rig import rig_params

    base = rig_params(model.nominal, f"{args.model}: nominal")
    changes: dict = {}
    k = base.contact_stiffness_n_per_m
    if args.contact_stiffness_n_per_m is not None:
        k = args.contact_stiffness_n_per_m
        changes.update(contact_stiffness_n_per_m=k, compensator_stiffness_n_per_m=k)
    if args.contact_frequency_hz is not None:
        if not (math.isfinite(args.contact_frequency_hz) and args.contact_frequency_hz > 0):
            from hybridtable.errors import CommandError

            raise CommandError("--contact-frequency-hz must be > 0")
        changes["spacecraft_mass_kg"] = mass_for_contact_frequency_kg(k, args.contact_frequency_hz)
    for name in ("table_damping_ratio", "initial_velocity_m_per_s", "lead_time_s"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    if args.sample_rate_hz is not None:
        changes["sample_rate_hz"] = args.sample_rate_hz
    return base.with_(**changes)


def _base_params(args: argparse.Namespace, model=None):
    from hybridtable.errors import CommandError
    from hybridtable.studies.paper import paper_params

    if model is not None:
        base = _model_base(args, model)
    else:
        given = {k: getattr(args, k) for k in RIG_DEFAULTS}
        rig = {k: v if given[k] is None else given[k] for k, v in RIG_DEFAULTS.items()}
        base = paper_params(
            sensor_delay_s=0.0,  # the grid sets it
            table_damping_ratio=rig["table_damping_ratio"],
            contact_frequency_hz=rig["contact_frequency_hz"],
            contact_stiffness_n_per_m=rig["contact_stiffness_n_per_m"],
            initial_velocity_m_per_s=rig["initial_velocity_m_per_s"],
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
    from hybridtable._files import staged_folder
    from hybridtable._validation import check_choice
    from hybridtable.analysis.robustness import grid_cor_limits
    from hybridtable.analysis.validation import validate_sweep
    from hybridtable.commands._common import check_outputs, write_json
    from hybridtable.commands._model_options import load_model_arg, load_plugins
    from hybridtable.compensators.paper import COMPENSATORS
    from hybridtable.errors import CommandError, ParameterError
    from hybridtable.reports.margin_point import (
        format_grid,
        format_point,
        margins_verdict,
        point_margins,
    )
    from hybridtable.reports.margins import (
        format_model_point,
        model_operating_point,
        operating_point,
        table1_point,
        write_report,
    )
    from hybridtable.sweeps.margins_grid import sweep_margins

    load_plugins(args)
    model = load_model_arg(args)

    try:  # any letter case, as everywhere a compensator is named
        comps = [
            check_choice("--compensator", c.strip(), COMPENSATORS, any_case=True)
            for c in args.compensator.split(",")
            if c.strip()
        ]
    except ParameterError as err:
        raise CommandError(str(err)) from None
    if not comps or len(set(comps)) != len(comps):
        raise CommandError("--compensator: give each compensator once")
    base = _base_params(args, model)
    delays = (
        default_delays(base.sample_rate_hz)
        if args.sensor_delay_s is None
        else parse_list(args.sensor_delay_s, "--sensor-delay-s", "sensor_delay_s")
    )
    tables = parse_list(args.table_response_hz, "--table-response-hz", "table_response_hz")
    if (delays < 0).any() or not np.isfinite(delays).all():
        raise CommandError("--sensor-delay-s: delays must be finite and >= 0")
    if (tables <= 0).any():
        raise CommandError("--table-response-hz: frequencies must be > 0 (inf: ideal table)")
    check_outputs(args, files={"--json": args.json}, folders={"--report": args.report})
    check_outputs(args, files={"--export-linear": args.export_linear})
    op_delay, op_table, export_comp = _operating_point(args, base, model, comps)
    progress = not args.no_progress and args.json != "-"

    t0 = time.perf_counter()
    transform = simulate_fn = None
    if model is not None:
        from hybridtable.studies.model_compensators import model_transform, simulate_model

        transform = model_transform(model)

        def simulate_fn(p):
            return simulate_model(model, p)

    result = sweep_margins(
        base,
        delays,
        tables,
        comps,
        pade_order=args.pade_order,
        progress=progress,
        model=model,
        transform=transform,
    )
    sweep_wall = time.perf_counter() - t0
    if args.validate:
        validate_sweep(result, args.validate, progress=progress, simulate_fn=simulate_fn)
    model_point = model_lines = None
    if model is not None:
        model_point = model_operating_point(model, base, comps, args.pade_order)
        model_lines = format_model_point(model_point, model, args.model)
    point = point_margins(
        base, comps, op_delay, op_table, args.pade_order, args.cor_limit, transform
    )
    verdict = margins_verdict(result, point)
    limits = grid_cor_limits(result, args.cor_limit)
    exported = None
    if args.export_linear:
        exported = _export_linear(args.export_linear, point, export_comp, args.pade_order)
    table1 = None
    if args.report is not None:
        table1 = operating_point(
            {c: table1_point(base.with_(compensator=c)) for c in comps},
            args.pade_order,
            simulate=True,
        )
        with staged_folder(args.report) as stage:
            files = write_report(
                result, stage.path, table1, model_lines, point, args.cor_limit, verdict
            )
        files = [stage.final(f) for f in files]
    wall = time.perf_counter() - t0

    data = result.to_json_dict()
    data = {"verdict": verdict, **data, "cor_limit": args.cor_limit}
    for c, lim in limits.items():
        data["compensators"][c].update({k: v.tolist() for k, v in lim.items()})
    data["operating_point_margins"] = point.to_dict()
    if exported is not None:
        data["linear_export"] = {"path": str(exported), "compensator": export_comp}
    data["sweep_wall_time_s"] = sweep_wall
    data["wall_time_s"] = wall
    if table1 is not None:
        data["table1_point"] = table1.to_dict()
    if model_point is not None:
        data["model"].update(
            path=str(args.model),
            description=model.describe(),
            left_out=list(model_point.left_out),
            linear_changes={k: list(v) for k, v in model_point.linear_changes.items()},
            operating_point_sensor_delay_s=model.nominal.sensor_delay_s,
            operating_point_table_response_hz=model.nominal.table_natural_frequency_hz,
            operating_point_initial_velocity_m_per_s=base.initial_velocity_m_per_s,
        )
        data["operating_point"] = model_point.to_dict()
    if args.json != "-":
        for line in model_lines or ():
            print(line)
        print(verdict)
        for line in format_point(point):
            print(line)
        for line in format_grid(result, sweep_wall, limits, args.cor_limit, point.undamped):
            print(line)
        if args.report is not None:
            for f in files:
                print(f"wrote {f}")
        if exported is not None:
            print(f"wrote {exported} (the linear loop with {export_comp}, for control.ss)")
        print(f"wall time {wall:.1f} s")
    if args.json:
        write_json(args.json, _with_notes(data), args)
    return 0


def _with_notes(data: dict) -> dict:
    """The margins document with a note beside every null or infinity (what it means)."""
    from hybridtable.commands._common import note_unset

    note_unset(
        data,
        {
            "max_validation_abs_error": "max_validation_abs_error: no nonlinear validation "
            "(--validate 0)"
        },
    )
    note_unset(
        data.get("model", {}),
        {"sample_rate_hz": "sample_rate_hz null: a continuous rig computer (no --sample-rate-hz)"},
    )
    grid_words = {
        "critical_delay_s": "critical_delay_s inf: stable at every delay of the search at "
        "that table frequency",
        "critical_table_hz": "critical_table_hz inf: no table is fast enough at that delay "
        "(unstable with an ideal table or, sampled, at half the sample rate)",
        "cor_limited_delay_s": "cor_limited_delay_s inf: the predicted CoR stays within "
        "--cor-limit at every delay of the search at that table frequency",
        "cor_limited_table_hz": "cor_limited_table_hz inf: the predicted CoR stays within "
        "--cor-limit at every table frequency of the grid at that delay",
    }
    for entry in data.get("compensators", {}).values():
        note_unset(entry, grid_words)
    point_words = {
        "gain_margin": "gain_margin and gain_margin_db inf, phase_crossover_rad_per_s null: "
        "the phase never crosses -180 deg, so no gain makes the loop unstable",
        "delay_margin_s": "delay_margin_s inf: no gain crossover, so no delay makes the loop "
        "unstable",
        "critical_delay_s": "critical_delay_s inf: stable at every delay up to search_max_delay_s",
        "cor_limited_delay_s": "cor_limited_delay_s inf: the predicted CoR stays within "
        "cor_limit at every delay up to search_max_delay_s",
    }
    for key in ("operating_point_margins", "operating_point"):
        for entry in data.get(key, {}).get("compensators", {}).values():
            note_unset(entry, point_words)
    return data


def _operating_point(args: argparse.Namespace, base, model, comps) -> tuple[float, float, str]:
    """The operating point's sensor delay (s) and table frequency (Hz), and the
    compensator of ``--export-linear``, checked."""
    from hybridtable.analysis.linear_export import EXPORT_SUFFIXES
    from hybridtable.errors import CommandError

    if not (math.isfinite(args.cor_limit) and args.cor_limit > 0):
        raise CommandError("--cor-limit must be a number > 0")
    delay, table = args.operating_delay_s, args.operating_table_hz
    if delay is None:
        delay = TABLE1_DEFAULTS["sensor_delay_s"] if model is None else model.nominal.sensor_delay_s
    elif not (math.isfinite(delay) and delay >= 0):
        raise CommandError("--operating-delay-s must be finite and >= 0")
    if table is None:
        table = (
            TABLE1_DEFAULTS["table_response_hz"]
            if model is None
            else model.nominal.table_natural_frequency_hz
        )
    elif not table > 0:
        raise CommandError("--operating-table-hz must be > 0 (inf: ideal table)")
    comp = args.export_compensator
    if comp is None:
        own = model.nominal.compensator if model is not None else None
        comp = own if own in comps else "SDMDC" if "SDMDC" in comps else comps[0]
    elif comp not in comps:
        raise CommandError(f"--export-compensator: {comp!r} is not in --compensator")
    if args.export_linear:
        if Path(args.export_linear).suffix.lower() not in EXPORT_SUFFIXES:
            raise CommandError("--export-linear: give a file name ending in .json or .npz")
        if args.json and Path(args.json).resolve() == Path(args.export_linear).resolve():
            raise CommandError("--export-linear and --json name the same file")
    return float(delay), float(table), comp


def _export_linear(path: str, point, compensator: str, pade_order: int) -> Path:
    """Write the linear loop of ``compensator`` at the operating point."""
    from hybridtable.analysis.linear_export import (
        linear_model_document,
        save_linear_model,
        state_labels,
    )

    loop = point.loops[compensator]
    m, g = point.margins[compensator], point.robust[compensator]
    doc = linear_model_document(
        loop,
        compensator,
        {"sensor_delay_s": point.sensor_delay_s, "table_response_hz": point.table_response_hz},
        state_labels(loop.params, pade_order),
        extra={"margins": {"predicted_cor": m.predicted_cor, **g.to_dict()}},
    )
    return save_linear_model(path, doc)
