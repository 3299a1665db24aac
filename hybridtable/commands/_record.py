"""``hybridtable simulate --record DIR``: runs written as the rig's data logger
would, with hidden effects and noise, and a ``truth.json`` of what was hidden
(``hybridtable-truth/1``).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

from hybridtable.commands._simulate_rig import refuse_unsupported, rig_info_from_args, rig_physics
from hybridtable.errors import CommandError

__all__ = ["TRUTH_FORMAT", "add_record_arguments", "run_record"]

#: Value of ``truth.json``'s ``format`` key.
TRUTH_FORMAT = "hybridtable-truth/1"


def add_record_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``simulate --record``."""
    from hybridtable.commands._common import SEED_RANGE, integer_type, number_list, number_type

    g = parser.add_argument_group(
        "recording runs (--record DIR): hybridtable-run/1 files of the rig with the "
        "--add/--model effects hidden, and truth.json"
    )
    g.add_argument(
        "--record",
        metavar="DIR",
        help="write runs (run1.csv + run1.json, ...) and truth.json into DIR; the runs' "
        "JSON holds the nominal parameters only (--compensator may list one per run)",
    )
    g.add_argument(
        "--runs",
        type=integer_type(1, 1000),
        default=None,
        help="number of runs, 1 to 1000 (default: one per velocity, else 1)",
    )
    g.add_argument(
        "--velocities",
        type=number_list("initial_velocity_m_per_s"),
        metavar="V1,V2,...",
        help="approach velocity of each run [m/s], each 0.0001 to 10 (default: "
        "--initial-velocity-m-per-s)",
    )
    g.add_argument(
        "--noise-force-n",
        type=number_type("0..1e6", "N"),
        metavar="NEWTONS",
        default=None,
        help="force-reading noise, standard deviation [N], 0 to 1e+06 (default: 0.002 x the "
        "undamped peak force v sqrt(k m) of the fastest run)",
    )
    g.add_argument(
        "--noise-position-m",
        type=number_type("0..1", "m"),
        metavar="METRES",
        default=None,
        help="table-position noise, standard deviation [m], 0 to 1 (default: 1e-4 x the "
        "undamped peak deflection v sqrt(m/k))",
    )
    g.add_argument(
        "--noise-ar1",
        type=number_type("(-1,1)"),
        default=0.0,
        metavar="PHI",
        help="lag-one correlation of both noises [1], in (-1, 1) (default 0: white)",
    )
    g.add_argument(
        "--seed",
        type=integer_type(*SEED_RANGE),
        default=0,
        help=f"noise seed of run 1; run i uses seed + i - 1, {SEED_RANGE[0]} to "
        f"{SEED_RANGE[1]} (default 0)",
    )
    g.add_argument(
        "--duration-s",
        type=number_type("0.001..10000", "s"),
        metavar="SECONDS",
        default=None,
        help="length of each record [s], 0.001 to 10000 (default: approach + 3 undamped contact durations)",
    )


def _list(text: str | None, flag: str, convert) -> list:
    if text is None:
        return []
    try:
        items = [convert(x.strip()) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CommandError(f"{flag}: expected a comma-separated list, got {text!r}") from None
    if not items:
        raise CommandError(f"{flag}: empty list")
    return items


def _per_run(items: list, n: int, flag: str) -> list:
    if not items:
        return [None] * n
    if len(items) == 1:
        return items * n
    if len(items) != n:
        raise CommandError(f"{flag}: give one value or one per run ({n} runs), got {len(items)}")
    return items


def run_record(args: argparse.Namespace, model) -> dict:
    """``simulate --record DIR``: write the runs and ``truth.json``."""
    from hybridtable._files import staged_folder
    from hybridtable.commands._common import check_outputs, write_json
    from hybridtable.effects.model_file import tool_version
    from hybridtable.measurement.recorder import record_run, write_run
    from hybridtable.measurement.rig import computer_with_model_mass
    from hybridtable.systems.noise import MeasurementNoiseParams

    refuse_unsupported(args, "simulate --record")
    velocities = list(args.velocities or [])
    compensators = _list(args.compensator, "--compensator", str)
    n = args.runs or max(len(velocities), len(compensators), 1)
    velocities = _per_run(velocities, n, "--velocities")
    compensators = _per_run(compensators, n, "--compensator")
    folder = Path(args.record)
    check_outputs(args, folders={"--record": folder})
    base = model.nominal if model is not None else None
    infos = [
        rig_info_from_args(args, base, f"{folder.name}-run{i + 1}", compensators[i], velocities[i])
        for i in range(n)
    ]
    v_max = max(i.initial_velocity_m_per_s for i in infos)
    k, m = infos[0].contact_stiffness_n_per_m, infos[0].spacecraft_mass_kg
    sigma_f = (
        args.noise_force_n if args.noise_force_n is not None else 2e-3 * v_max * math.sqrt(k * m)
    )
    sigma_x = (
        args.noise_position_m
        if args.noise_position_m is not None
        else 1e-4 * v_max * math.sqrt(m / k)
    )
    if args.force_deadband_n is None and base is None:
        infos = [replace(i, force_deadband_n=5.0 * sigma_f) for i in infos]
    from hybridtable.effects.spec import RigScale

    physics, spec, effects = rig_physics(
        args, model, model.scale if model is not None else RigScale.from_info(infos[0], v_max)
    )
    from hybridtable.measurement.recorder import FORMAT_COMPENSATORS

    for i in infos:
        if i.compensator not in FORMAT_COMPENSATORS:
            raise CommandError(
                f"--compensator {i.compensator}: a recorded run's computer is one of "
                f"{', '.join(FORMAT_COMPENSATORS)}"
            )
    progress = None
    if n > 1 and args.json != "-":
        from tqdm import tqdm

        progress = tqdm(total=n, desc="record", unit="run", file=sys.stderr, leave=False)
    records = []
    truth_runs = []
    for i, info in enumerate(infos):
        noise = MeasurementNoiseParams(sigma_f, sigma_x, args.seed + i, args.noise_ar1)
        # The mass the computer integrates with: the audited one, else the ratio's.
        computer = computer_with_model_mass(
            physics.computer, info.spacecraft_mass_kg, spec.mass_ratio
        )
        phys = replace(physics, computer=computer)
        run, truth = record_run(info, phys, noise, args.duration_s)
        records.append(run)
        truth_runs.append(
            {
                "run_id": info.run_id,
                "csv": f"run{i + 1}.csv",
                "json": f"run{i + 1}.json",
                "seed": args.seed + i,
                "compensator": info.compensator,
                "initial_velocity_m_per_s": info.initial_velocity_m_per_s,
                **truth,
            }
        )
        if progress is not None:
            progress.update()
    if progress is not None:
        progress.close()
    from hybridtable.effects.registry import get_effect

    units = {name: {p.name: p.unit for p in get_effect(name).parameters} for name, _ in effects}
    truth_doc = {
        "format": TRUTH_FORMAT,
        "tool_version": tool_version(),
        "hidden": {
            "effects": [
                {
                    "name": name,
                    "parameters": {
                        k_: {"value": v, "unit": units[name][k_]} for k_, v in values.items()
                    },
                }
                for name, values in effects
            ],
            "computer": dict(physics.computer),
        },
        "noise": {
            "force_std_n": sigma_f,
            "position_std_m": sigma_x,
            "ar1_coefficient": args.noise_ar1,
        },
        "model_file": args.model,
        "nominal": infos[0].to_dict(),
        "runs": truth_runs,
    }
    if args.model is None:
        truth_doc["note"] = "model_file null: the nominal model, no --model file"
    # All runs and truth.json appear together, or none (an interruption
    # leaves the folder as it was).
    with staged_folder(folder) as stage:
        for i, run in enumerate(records):
            write_run(run, stage.path, f"run{i + 1}", force=True)
        write_json(str(stage.path / "truth.json"), truth_doc)
    hidden = (
        "; ".join(
            f"{name} " + ", ".join(f"{k_}={v:g}" for k_, v in values.items())
            for name, values in effects
        )
        or "nothing (the nominal rig)"
    )
    out = {"record": str(folder), "truth": truth_doc}
    if args.json != "-":
        cors = ", ".join(f"{r['cor']:.4f}" for r in truth_runs)
        print(
            f"Recorded {n} run(s) into {folder} (CoR {cors}); hidden: {hidden}; noise "
            f"{sigma_f:.3g} N and {sigma_x:.3g} m (AR(1) {args.noise_ar1:g}); see truth.json."
        )
    return out
