"""The rig modes of ``hybridtable simulate``: ``--model`` (the rig as a model
file describes it) and ``--record`` (runs written as the rig's data logger
would, with hidden effects and noise, and a ``truth.json`` of what was hidden).

Both run the rig computer of the run format (sampled, the compensated force
clamped at zero and gated by the deadband, the MDC with the JSON stiffness),
so the loop options that the format cannot express are refused here with a
pointer to what to use instead.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from hybridtable.errors import CommandError

__all__ = [
    "TRUTH_FORMAT",
    "add_record_arguments",
    "rig_info_from_args",
    "run_model",
    "run_record",
]

#: Value of ``truth.json``'s ``format`` key.
TRUTH_FORMAT = "hybridtable-truth/1"

#: Loop options the run format's rig computer has no place for, and what to use.
_REFUSED = {
    "contact_damping_n_s_per_m": "--add contact_damping:damping_n_s_per_m=C",
    "compensator_stiffness_n_per_m": "the run format's MDC uses the contact stiffness",
    "time_step_s": "the rig computer is sampled (--sample-rate-hz)",
    "passivity": "the run format's computer has no passivity guard",
    "clamp_nonnegative": "the run format's computer always clamps at zero",
}


def add_record_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``simulate --record``."""
    from hybridtable.commands._common import parse_float

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
        "--runs", type=int, default=None, help="number of runs (default: one per velocity, else 1)"
    )
    g.add_argument(
        "--velocities",
        metavar="V1,V2,...",
        help="approach velocity of each run [m/s] (default: --initial-velocity-m-per-s)",
    )
    g.add_argument(
        "--noise-force-n",
        type=parse_float,
        default=None,
        help="force-reading noise, standard deviation [N] (default: 0.002 x the "
        "undamped peak force v sqrt(k m) of the fastest run)",
    )
    g.add_argument(
        "--noise-position-m",
        type=parse_float,
        default=None,
        help="table-position noise, standard deviation [m] (default: 1e-4 x the "
        "undamped peak deflection v sqrt(m/k))",
    )
    g.add_argument(
        "--noise-ar1",
        type=parse_float,
        default=0.0,
        metavar="PHI",
        help="lag-one correlation of both noises, in (-1, 1) (default 0: white)",
    )
    g.add_argument(
        "--seed",
        type=int,
        default=0,
        help="noise seed of run 1; run i uses seed + i - 1 (default 0)",
    )
    g.add_argument(
        "--duration-s",
        type=parse_float,
        default=None,
        help="length of each record [s] (default: approach + 3 undamped contact durations)",
    )
    g.add_argument(
        "--force", action="store_true", help="write into a non-empty DIR, replacing its runs"
    )


def _refuse_unsupported(args: argparse.Namespace, mode: str) -> None:
    for name, instead in _REFUSED.items():
        value = getattr(args, name, None)
        if value not in (None, False):
            flag = "--" + name.replace("_", "-")
            raise CommandError(f"{mode}: {flag} is not available ({instead})")
    if getattr(args, "table", "second-order") != "second-order" or getattr(args, "html", None):
        raise CommandError(f"{mode}: the rig modes use the second-order table model")


def _number(args: argparse.Namespace, name: str, base: Any, default: float) -> float:
    from hybridtable._validation import check_finite

    value = getattr(args, name, None)
    if value is None:
        return float(base) if base is not None else default
    return check_finite("--" + name.replace("_", "-"), value)


def rig_info_from_args(
    args: argparse.Namespace,
    base=None,
    run_id: str = "simulated",
    compensator: str | None = None,
    velocity: float | None = None,
    deadband_n: float = 0.0,
):
    """The :class:`~hybridtable.measurement.run_format.RunInfo` of a simulated
    rig run: the loop options given, else ``base``'s values (a RunInfo, e.g. a
    model's nominal rig), else the paper's Table 1 point at 1000 Hz.

    Raises
    ------
    ParameterError
        Naming the option whose value is out of range.
    """
    from hybridtable._validation import check_nonnegative, check_positive
    from hybridtable.commands.simulate import LOOP_OPTIONS
    from hybridtable.measurement.run_format import RunInfo
    from hybridtable.measurement.run_reader import run_info_from_dict

    def b(key):
        return getattr(base, key) if base is not None else None

    k = check_positive(
        "--contact-stiffness-n-per-m",
        _number(args, "contact_stiffness_n_per_m", b("contact_stiffness_n_per_m"), 1e5),
    )
    if args.contact_frequency_hz is not None or base is None:
        f = check_positive(
            "--contact-frequency-hz",
            _number(args, "contact_frequency_hz", None, LOOP_OPTIONS["contact_frequency_hz"][0]),
        )
        mass = k / (2.0 * math.pi * f) ** 2
    else:
        mass = base.spacecraft_mass_kg
    delay = check_nonnegative(
        "--sensor-delay-s", _number(args, "sensor_delay_s", b("sensor_delay_s"), 0.005)
    )
    rate = check_positive(
        "--sample-rate-hz", _number(args, "sample_rate_hz", b("sample_rate_hz"), 1000.0)
    )
    table = _number(args, "table_response_hz", b("table_natural_frequency_hz"), 25.0)
    if not (table > 0 and math.isfinite(table)):
        raise CommandError(
            f"--table-response-hz must be finite and > 0 for a recorded rig (got {table})"
        )
    lead = _number(
        args, "lead_time_s", b("lead_time_s") if args.sensor_delay_s is None else None, delay
    )
    values = {
        "format": "hybridtable-run/1",
        "run_id": run_id,
        "sample_rate_hz": rate,
        "spacecraft_mass_kg": mass,
        "contact_stiffness_n_per_m": k,
        "sensor_delay_s": delay,
        "table_natural_frequency_hz": table,
        "table_damping_ratio": check_nonnegative(
            "--table-damping-ratio",
            _number(args, "table_damping_ratio", b("table_damping_ratio"), 0.8),
        ),
        "compensator": compensator or args.compensator or (b("compensator") or "none"),
        "lead_time_s": check_nonnegative("--lead-time-s", lead),
        "initial_gap_m": check_nonnegative(
            "--initial-gap-m", _number(args, "initial_gap_m", b("initial_gap_m"), 0.001)
        ),
        "initial_velocity_m_per_s": check_positive(
            "--initial-velocity-m-per-s",
            velocity
            if velocity is not None
            else _number(args, "initial_velocity_m_per_s", b("initial_velocity_m_per_s"), 0.1),
        ),
        "force_deadband_n": check_nonnegative(
            "--force-deadband-n",
            _number(args, "force_deadband_n", b("force_deadband_n"), deadband_n),
        ),
    }
    info = run_info_from_dict(values, "the simulated rig's options")
    assert isinstance(info, RunInfo)
    return info


def _physics(args: argparse.Namespace, model, info):
    """The rig's physics: the model's effects and rig computer, plus --add's
    (every parameter given). Returns (physics, the effects as (name, values))."""
    from hybridtable.commands._model_options import parse_added
    from hybridtable.diagnosis.registry import build_spec

    added = parse_added(args)
    for effect, values in added:
        missing = [p for p in effect.parameter_names if p not in values]
        if missing:
            raise CommandError(
                f"--add {effect.name}: give {', '.join(f'{p}=...' for p in missing)} "
                "(nothing to fit it to here)"
            )
        if model is not None:
            for e in model.effects:
                if effect.conflicts_with(e.effect):
                    raise CommandError(f"--add {effect.name}: the model already has {e.name}")
    scale = model.scale if model is not None else _scale(info)
    checked = [(e, e.check_values(v, scale)) for e, v in added]
    effects = [(e.effect, dict(e.values)) for e in model.effects] if model is not None else []
    effects += checked
    spec = build_spec(effects, scale)
    physics = spec.physics(name="+".join(e.name for e, _ in effects) or "nominal")
    if model is not None and model.computer_for(None):
        physics = replace(physics, computer=model.computer_for(None))
    return physics, spec, [(e.name, v) for e, v in effects], scale


def _scale(info):
    from hybridtable.diagnosis.effects import RigScale

    return RigScale(
        stiffness_n_per_m=info.contact_stiffness_n_per_m,
        mass_kg=info.spacecraft_mass_kg,
        sample_period_s=info.sample_period_s,
        sensor_delay_s=info.sensor_delay_s,
        velocity_m_per_s=info.initial_velocity_m_per_s,
        table_frequency_hz=info.table_natural_frequency_hz,
    )


def _metrics(result) -> dict[str, float]:
    m = result.metrics
    return {
        "cor": m.cor,
        "peak_force_n": m.peak_force_n,
        "contact_duration_s": m.contact_duration_s,
        "energy_gain_j": m.energy_gain_j,
        "v_in_m_per_s": m.v_in_m_per_s,
        "v_out_m_per_s": m.v_out_m_per_s,
    }


# -- simulate --model ------------------------------------------------------------
def run_model(args: argparse.Namespace, model) -> dict:
    """``simulate --model``: with no loop option, every run the model was
    fitted to, at its own conditions, against its recorded CoR and the
    nominal model's; with loop options, one run of the modelled rig there."""
    from hybridtable.commands.simulate import given_loop_options
    from hybridtable.measurement.rig import simulate_rig_contact

    _refuse_unsupported(args, "simulate --model")
    physics_args = _physics(args, model, model.nominal)
    physics, spec, effects, _ = physics_args
    given = given_loop_options(args)
    rows = []
    if not given and model.runs:
        cases = [(r.nominal, model.physics(r.run_id), r) for r in model.runs]
        if args.add:
            cases = [
                (r.nominal, replace(physics, computer=model.computer_for(r.run_id)), r)
                for r in model.runs
            ]
    else:
        info = rig_info_from_args(args, model.nominal, "simulated")
        cases = [(info, physics, None)]
    for info, phys, mrun in cases:
        if spec.mass_ratio != 1.0:
            info = replace(info, spacecraft_mass_kg=info.spacecraft_mass_kg * spec.mass_ratio)
        modelled = _metrics(simulate_rig_contact(info, phys))
        nominal = _metrics(simulate_rig_contact(info))
        row = {
            "run_id": mrun.run_id if mrun else None,
            "compensator": info.compensator,
            "initial_velocity_m_per_s": info.initial_velocity_m_per_s,
            **modelled,
            "cor_nominal": nominal["cor"],
        }
        if mrun is not None and mrun.cor_measured is not None:
            row["cor_measured"] = mrun.cor_measured
            row["cor_error"] = modelled["cor"] - mrun.cor_measured
            row["cor_error_nominal"] = nominal["cor"] - mrun.cor_measured
        rows.append(row)
    out = {
        "model": args.model,
        "description": model.describe(),
        "effects": [{"name": n, "parameters": dict(v)} for n, v in effects],
        "runs": rows,
    }
    errors = [abs(r["cor_error"]) for r in rows if "cor_error" in r]
    if errors:
        out["max_abs_cor_error"] = max(errors)
        out["max_abs_cor_error_nominal"] = max(abs(r["cor_error_nominal"]) for r in rows)
    if args.json != "-":
        print(_model_sentence(out))
        print(f"model: {model.describe()}")
        head = f"{'run':<24} {'comp':<8} {'v0 [m/s]':>9} {'CoR model':>10} {'recorded':>9} {'error':>9} {'nominal':>9}"
        print(head)
        print("-" * len(head))
        for r in rows:
            rec = (
                f"{r['cor_measured']:9.5f} {r['cor_error']:+9.5f}"
                if "cor_measured" in r
                else f"{'-':>9} {'-':>9}"
            )
            print(
                f"{(r['run_id'] or 'simulated'):<24} {r['compensator']:<8} "
                f"{r['initial_velocity_m_per_s']:9.4g} {r['cor']:10.5f} {rec} {r['cor_nominal']:9.5f}"
            )
    return out


def _model_sentence(out: dict) -> str:
    rows = out["runs"]
    if "max_abs_cor_error" in out:
        return (
            f"The model reproduces the recorded CoR of {len(rows)} run(s) within "
            f"{out['max_abs_cor_error']:.4f} (the nominal model: within "
            f"{out['max_abs_cor_error_nominal']:.4f})."
        )
    r = rows[0]
    return (
        f"{r['compensator']}: the modelled rig gives CoR {r['cor']:.5f} "
        f"(nominal model {r['cor_nominal']:.5f}), peak force {r['peak_force_n']:.1f} N."
    )


# -- simulate --record -------------------------------------------------------------
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


def _check_record_folder(folder: Path, n: int, force: bool) -> None:
    if folder.exists() and not folder.is_dir():
        raise CommandError(f"--record {folder} is a file, not a folder")
    if folder.is_dir() and any(folder.iterdir()) and not force:
        raise CommandError(
            f"--record {folder} is not empty; choose a new folder, or give --force "
            f"(replaces run1..run{n} and truth.json there, leaves other files)"
        )


def run_record(args: argparse.Namespace, model) -> dict:
    """``simulate --record DIR``: write the runs and ``truth.json``."""
    import json

    from hybridtable.commands._common import write_json_atomic
    from hybridtable.diagnosis.model_file import tool_version
    from hybridtable.measurement.recorder import record_run, write_run
    from hybridtable.systems.noise import MeasurementNoiseParams

    _refuse_unsupported(args, "simulate --record")
    velocities = _list(args.velocities, "--velocities", float)
    compensators = _list(args.compensator, "--compensator", str)
    if args.runs is not None and args.runs < 1:
        raise CommandError(f"--runs must be >= 1 (got {args.runs})")
    n = args.runs or max(len(velocities), len(compensators), 1)
    velocities = _per_run(velocities, n, "--velocities")
    compensators = _per_run(compensators, n, "--compensator")
    if args.seed < 0:
        raise CommandError(f"--seed must be >= 0 (got {args.seed})")
    folder = Path(args.record)
    _check_record_folder(folder, n, args.force)
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
    physics, spec, effects, scale = _physics(
        args, model, replace(infos[0], initial_velocity_m_per_s=v_max)
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
        phys = physics
        if spec.mass_ratio != 1.0:  # the computer integrates with another mass
            mass = info.spacecraft_mass_kg * spec.mass_ratio
            phys = replace(physics, computer={**physics.computer, "spacecraft_mass_kg": mass})
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
    folder.mkdir(parents=True, exist_ok=True)
    for i, run in enumerate(records):
        write_run(run, folder, f"run{i + 1}", force=args.force)
    from hybridtable.diagnosis.registry import get_effect

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
    truth_path = folder / "truth.json"
    if truth_path.exists() and not args.force:
        raise CommandError(f"{truth_path} exists; give --force to replace it")
    write_json_atomic(str(truth_path), truth_doc)
    hidden = (
        "; ".join(
            f"{name} " + ", ".join(f"{k_}={v:g}" for k_, v in values.items())
            for name, values in effects
        )
        or "nothing (the nominal rig)"
    )
    out = {"record": str(folder), "truth": json.loads(truth_path.read_text())}
    if args.json != "-":
        cors = ", ".join(f"{r['cor']:.4f}" for r in truth_runs)
        print(
            f"Recorded {n} run(s) into {folder} (CoR {cors}); hidden: {hidden}; noise "
            f"{sigma_f:.3g} N and {sigma_x:.3g} m (AR(1) {args.noise_ar1:g}); see truth.json."
        )
    return out
