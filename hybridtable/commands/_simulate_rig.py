"""The rig modes of ``hybridtable simulate``: the rig a model file describes
(``--model``, here) and the options it shares with ``--record``
(:mod:`hybridtable.commands._record`): the run's parameters from the loop
options, the physics from the model and ``--add``.

Both run the rig computer of the run format (sampled, the compensated force
clamped at zero and gated by the deadband, the MDC with the JSON stiffness),
so the loop options that the format cannot express are refused here with a
pointer to what to use instead.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from typing import Any

from hybridtable.errors import CommandError
from hybridtable.laws.contact import mass_for_contact_frequency_kg

__all__ = [
    "RECORD_SAMPLE_RATE_HZ",
    "refuse_unsupported",
    "rig_info_from_args",
    "rig_physics",
    "run_model",
]

#: Rate of a simulated rig's computer when neither an option nor a model gives one (Hz).
RECORD_SAMPLE_RATE_HZ = 1000.0

#: Loop options the run format's rig computer has no place for, and what to use.
_REFUSED = {
    "contact_damping_n_s_per_m": "--add contact_damping:damping_n_s_per_m=C",
    "compensator_stiffness_n_per_m": "the run format's MDC uses the contact stiffness",
    "time_step_s": "the rig computer is sampled (--sample-rate-hz)",
    "passivity": "the run format's computer has no passivity guard",
    "clamp_nonnegative": "the run format's computer always clamps at zero",
}


def refuse_unsupported(args: argparse.Namespace, mode: str) -> None:
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
    from hybridtable.commands._loop_options import LOOP_OPTIONS
    from hybridtable.measurement.run_format import RunInfo
    from hybridtable.measurement.run_reader import run_info_from_dict

    def b(key):
        return getattr(base, key) if base is not None else None

    def d(name):
        return LOOP_OPTIONS[name][0]

    k = check_positive(
        "--contact-stiffness-n-per-m",
        _number(
            args,
            "contact_stiffness_n_per_m",
            b("contact_stiffness_n_per_m"),
            d("contact_stiffness_n_per_m"),
        ),
    )
    if args.contact_frequency_hz is not None or base is None:
        f = check_positive(
            "--contact-frequency-hz",
            _number(args, "contact_frequency_hz", None, d("contact_frequency_hz")),
        )
        mass = mass_for_contact_frequency_kg(k, f)
    else:
        mass = base.spacecraft_mass_kg
    delay = check_nonnegative(
        "--sensor-delay-s",
        _number(args, "sensor_delay_s", b("sensor_delay_s"), d("sensor_delay_s")),
    )
    rate = check_positive(
        "--sample-rate-hz",
        _number(args, "sample_rate_hz", b("sample_rate_hz"), RECORD_SAMPLE_RATE_HZ),
    )
    table = _number(
        args, "table_response_hz", b("table_natural_frequency_hz"), d("table_response_hz")
    )
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
            _number(
                args, "table_damping_ratio", b("table_damping_ratio"), d("table_damping_ratio")
            ),
        ),
        "compensator": compensator or args.compensator or (b("compensator") or "none"),
        "lead_time_s": check_nonnegative("--lead-time-s", lead),
        "initial_gap_m": check_nonnegative(
            "--initial-gap-m",
            _number(args, "initial_gap_m", b("initial_gap_m"), d("initial_gap_m")),
        ),
        "initial_velocity_m_per_s": check_positive(
            "--initial-velocity-m-per-s",
            velocity
            if velocity is not None
            else _number(
                args,
                "initial_velocity_m_per_s",
                b("initial_velocity_m_per_s"),
                d("initial_velocity_m_per_s"),
            ),
        ),
        "force_deadband_n": check_nonnegative(
            "--force-deadband-n",
            _number(args, "force_deadband_n", b("force_deadband_n"), deadband_n),
        ),
    }
    info = run_info_from_dict(values, "the simulated rig's options")
    assert isinstance(info, RunInfo)
    return info


def rig_physics(args: argparse.Namespace, model, scale=None):
    """The rig's physics: the model's effects and rig computer, plus --add's
    (every parameter given, checked against the bounds at ``scale``, default
    the model's).

    Returns the :class:`~hybridtable.measurement.rig.RigPhysics`, the
    :class:`~hybridtable.effects.effect.ModelSpec`, and the effects as
    ``[(name, values), ...]``.
    """
    from hybridtable.commands._model_options import parse_added_given
    from hybridtable.effects.registry import build_spec

    added = parse_added_given(args, "(nothing to fit it to here)")
    for effect, _ in added:
        if model is not None:
            for e in model.effects:
                if effect.conflicts_with(e.effect):
                    raise CommandError(f"--add {effect.name}: the model already has {e.name}")
    scale = model.scale if scale is None else scale
    checked = [(e, e.check_values(v, scale)) for e, v in added]
    effects = [(e.effect, dict(e.values)) for e in model.effects] if model is not None else []
    effects += checked
    spec = build_spec(effects, scale)
    physics = spec.physics(name="+".join(e.name for e, _ in effects) or "nominal")
    if model is not None and model.computer_for(None):
        physics = replace(physics, computer=model.computer_for(None))
    return physics, spec, [(e.name, v) for e, v in effects]


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
    from hybridtable.commands._loop_options import given_loop_options
    from hybridtable.measurement.rig import model_mass_kg, simulate_rig_contact

    refuse_unsupported(args, "simulate --model")
    physics, spec, effects = rig_physics(args, model)
    given = given_loop_options(args)
    rows = []
    if not given and model.runs:
        # Each fitted run with its own rig computer (the audit's, per run).
        cases = [
            (r.nominal, replace(physics, computer=model.computer_for(r.run_id)), r)
            for r in model.runs
        ]
    else:
        info = rig_info_from_args(args, model.nominal, "simulated")
        cases = [(info, physics, None)]
    for info, phys, mrun in cases:
        if spec.mass_ratio != 1.0:
            mass = model_mass_kg(info.spacecraft_mass_kg, spec.mass_ratio)
            info = replace(info, spacecraft_mass_kg=mass)
        modelled = _metrics(simulate_rig_contact(info, phys))
        nominal = _metrics(simulate_rig_contact(info))
        row = {
            "run_id": mrun.run_id if mrun else info.run_id,
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
