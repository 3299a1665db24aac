"""What a sweep can vary: every parameter of the loop, and a few derived ones.

A run of a campaign is a set of named inputs (:data:`INPUTS`): the fields of
:class:`~hybridtable.loop.params.HybridLoopParams` under their own names, plus

- ``contact_frequency_hz``: sets the spacecraft mass from the contact stiffness,
  ``m = k / (2 pi f)^2`` (how the paper gives its runs);
- ``contact_damping_ratio``: sets the contact damping ``c = 2 zeta sqrt(k m)``;
- ``compensator_stiffness_ratio``: the stiffness the MDC believes over the true
  one (a stiffness mismatch);
- ``force_noise_n``, ``position_noise_m``: white noise (standard deviations) on
  the force and table position the rig computer reads, a new sample every
  computer period, seeded by the run's own seed;
- ``table_backend``: ``second_order`` (the loop's table) or ``stewart`` (the
  3-3 Stewart platform in a MultibodyPlant, tuned to ``table_response_hz``);
- ``EFFECT.PARAMETER``: a parameter of a registered effect (``hybridtable
  effects`` lists them), e.g. ``coulomb_friction.friction_force_n``: the run's
  rig has that effect (every parameter of an effect given; a sampled rig
  computer, as the effects model the run format's).

A parameter a spec does not give takes the paper's Table 1 value
(:data:`DEFAULTS`) or the loop's own default. :func:`loop_params` turns the
inputs of one run into the loop's parameters exactly as
:func:`~hybridtable.studies.paper.paper_params` does, so a spec of the paper's
points gives the paper's runs bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from hybridtable.errors import ParameterError
from hybridtable.limits import LIMITS, TABLE1_DEFAULTS, check_plausible

__all__ = [
    "Input",
    "INPUTS",
    "DEFAULTS",
    "CONFLICTS",
    "NOISE_INPUTS",
    "TABLE_BACKENDS",
    "input_of",
    "effect_values",
    "check_kind",
    "check_value",
    "loop_params",
    "noise_params",
]


@dataclass(frozen=True)
class Input:
    """One input a spec may set.

    Attributes
    ----------
    name : str
    kind : {"number", "text", "bool"}
    unit : str
        SI unit ("1": dimensionless, "": text or bool).
    doc : str
        What it is, in a few words.
    whole : bool
        A whole number (a count): a grid or a ``choice`` gives it, no
        continuous distribution.
    """

    name: str
    kind: str
    unit: str
    doc: str
    whole: bool = False


def _loop_inputs() -> dict[str, Input]:
    from hybridtable.loop.params import FIELDS

    docs = {
        "spacecraft_mass_kg": ("kg", "spacecraft model mass"),
        "contact_stiffness_n_per_m": ("N/m", "true contact stiffness"),
        "contact_damping_n_s_per_m": ("N s/m", "true contact damping"),
        "sensor_delay_s": ("s", "force-sensor delay"),
        "table_response_hz": ("Hz", "table response frequency (inf: ideal table)"),
        "table_damping_ratio": ("1", "table damping ratio"),
        "compensator": ("", "a registered compensator"),
        "lead_time_s": ("s", "SDC lead time (default: the sensor delay)"),
        "compensator_stiffness_n_per_m": ("N/m", "stiffness the MDC believes"),
        "compensator_damping_n_s_per_m": ("N s/m", "damping the MDC believes"),
        "force_deadband_n": ("N", "measured forces at or below it are no contact"),
        "clamp_nonnegative": ("", "clamp the compensated force at zero"),
        "contact_gate": ("", "how the compensator tells contact"),
        "initial_velocity_m_per_s": ("m/s", "approach velocity"),
        "initial_gap_m": ("m", "gap between the devices at t = 0"),
        "table_initial_state": ("", "tracking, command, rest or given"),
        "table_initial_position_m": ("m", "table position at t = 0 (given)"),
        "table_initial_velocity_m_per_s": ("m/s", "table velocity at t = 0 (given)"),
        "sample_rate_hz": ("Hz", "rig computer rate (absent: continuous)"),
        "time_step_s": ("s", "continuous mode's largest step"),
        "passivity": ("", "the passivity guard on the compensator"),
        "computer_integrator": ("", "the sampled computer's rule: semi_implicit_euler, ..."),
    }
    out = {}
    for name in FIELDS:
        unit, doc = docs[name]
        kind = "bool" if name in ("clamp_nonnegative", "passivity") else "number"
        if name in ("compensator", "contact_gate", "table_initial_state", "computer_integrator"):
            kind = "text"
        out[name] = Input(name, kind, unit, doc)
    return out


#: Every input a spec may set, by name.
INPUTS: dict[str, Input] = {
    **_loop_inputs(),
    "contact_frequency_hz": Input(
        "contact_frequency_hz", "number", "Hz", "contact frequency; sets the mass"
    ),
    "contact_damping_ratio": Input(
        "contact_damping_ratio", "number", "1", "contact damping / critical; sets the damping"
    ),
    "compensator_stiffness_ratio": Input(
        "compensator_stiffness_ratio", "number", "1", "believed / true contact stiffness"
    ),
    "force_noise_n": Input("force_noise_n", "number", "N", "force reading noise (std)"),
    "position_noise_m": Input("position_noise_m", "number", "m", "position reading noise (std)"),
    "table_backend": Input("table_backend", "text", "", "second_order or stewart"),
}

#: The table back-ends a run can have.
TABLE_BACKENDS: tuple[str, ...] = ("second_order", "stewart")


def input_of(name: str) -> Input | None:
    """The :class:`Input` called ``name``: one of :data:`INPUTS`, or
    ``EFFECT.PARAMETER`` of a registered effect; None if there is none
    (a 6-DoF campaign's: :func:`~hybridtable.sweeps.plan.input_for`)."""
    if name in INPUTS:
        return INPUTS[name]
    effect_name, dot, parameter = name.partition(".")
    if not dot:
        return None
    from hybridtable.effects.registry import effect_names, get_effect

    if effect_name not in effect_names() or get_effect(effect_name).apply is None:
        return None  # not an effect of the 1-D loop (a six-axis rig's only)
    for p in get_effect(effect_name).parameters:
        if p.name == parameter:
            return Input(name, "number", p.unit, p.description)
    return None


def effect_values(values: dict[str, Any]) -> dict[str, dict[str, float]]:
    """The effects a run's inputs give: ``{effect: {parameter: value}}``."""
    out: dict[str, dict[str, float]] = {}
    for name, value in values.items():
        effect, dot, parameter = name.partition(".")
        if dot:
            out.setdefault(effect, {})[parameter] = float(value)
    return out


#: The noise inputs (they need the Drake diagram and the run's seed).
NOISE_INPUTS: tuple[str, ...] = ("force_noise_n", "position_noise_m")

#: Values of the inputs a spec does not give: the paper's Table 1 point.
DEFAULTS: dict[str, Any] = dict(TABLE1_DEFAULTS)

#: Pairs of inputs that set the same quantity: a spec gives at most one of each.
CONFLICTS: tuple[tuple[str, str], ...] = (
    ("spacecraft_mass_kg", "contact_frequency_hz"),
    ("contact_damping_n_s_per_m", "contact_damping_ratio"),
    ("compensator_stiffness_n_per_m", "compensator_stiffness_ratio"),
)


def check_kind(spec: Input, value: Any, choices: tuple[str, ...] | None = None) -> None:
    """Raise unless ``value`` is of the input's kind: a flag, one of
    ``choices`` (text), or a number (not a flag).

    Raises
    ------
    ParameterError
        One line naming the input.
    """
    name = spec.name
    if spec.kind == "bool":
        if not isinstance(value, bool):
            raise ParameterError(f"{name} must be true or false (got {value!r})")
    elif spec.kind == "text":
        if not isinstance(value, str):
            raise ParameterError(f"{name} must be a string (got {value!r})")
        if choices is not None and value not in choices:
            raise ParameterError(f"{name} must be one of {', '.join(choices)} (got {value!r})")
    elif isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterError(f"{name} must be a number (got {value!r})")


def check_value(name: str, value: Any) -> Any:
    """``value`` as the input ``name`` takes it, or raise.

    Numbers are checked against their plausible range
    (:data:`hybridtable.limits.LIMITS`), text against its choices, bools for
    their type.

    Raises
    ------
    ParameterError
        One line naming ``name``.
    """
    spec = input_of(name)
    if spec is None:
        raise ParameterError(f"unknown parameter {name!r}")
    check_kind(spec, value, _choices(name) if spec.kind == "text" else None)
    if spec.kind != "number":
        return value
    if name in LIMITS:
        return check_plausible(name, value)
    value = float(value)
    if "." in name:  # an effect's parameter: its bounds depend on the rig, checked per run
        if not math.isfinite(value):
            raise ParameterError(f"{name} must be a finite number (got {value!r})")
        return value
    if math.isnan(value) or value < 0.0 or math.isinf(value):
        raise ParameterError(f"{name} must be a finite number >= 0 (got {value!r})")
    return value


def _choices(name: str) -> tuple[str, ...]:
    if name == "compensator":
        from hybridtable.compensators.registry import compensator_names

        return tuple(compensator_names())
    if name == "table_backend":
        return TABLE_BACKENDS
    if name == "contact_gate":
        from hybridtable.compensators.paper import CONTACT_GATES

        return CONTACT_GATES
    if name == "computer_integrator":
        from hybridtable.laws.spacecraft import INTEGRATORS

        return tuple(INTEGRATORS)
    from hybridtable.loop.params import TABLE_INITIAL_STATES

    return TABLE_INITIAL_STATES


def loop_params(values: dict[str, Any]):
    """The :class:`~hybridtable.loop.params.HybridLoopParams` of one run.

    Parameters
    ----------
    values : dict
        Inputs by name (:data:`INPUTS`); those not given take :data:`DEFAULTS`.
        The noise inputs are ignored here (:func:`noise_params`).

    Raises
    ------
    ParameterError
        If the combination is not a loop (a value out of range, a rule of a
        sampled computer on a continuous one, ...), naming the field.
    """
    from hybridtable.loop.params import HybridLoopParams

    v = {k: x for k, x in values.items() if "." not in k and k != "table_backend"}
    for name in NOISE_INPUTS:
        v.pop(name, None)
    for name, default in DEFAULTS.items():
        if name == "contact_frequency_hz" and "spacecraft_mass_kg" in v:
            continue
        v.setdefault(name, default)
    damping_ratio = v.pop("contact_damping_ratio", None)
    stiffness_ratio = v.pop("compensator_stiffness_ratio", None)
    if "contact_frequency_hz" in v:
        f = v.pop("contact_frequency_hz")
        k = v.pop("contact_stiffness_n_per_m")
        params = HybridLoopParams.from_contact_frequency(f, k, **v)
    else:
        params = HybridLoopParams(**v)
    if damping_ratio is not None:
        params = params.with_contact_damping_ratio(damping_ratio)
    if stiffness_ratio is not None:
        params = params.with_(
            compensator_stiffness_n_per_m=stiffness_ratio * params.contact_stiffness_n_per_m
        )
    return params


def noise_params(values: dict[str, Any], seed: int):
    """The :class:`~hybridtable.systems.noise.MeasurementNoiseParams` of a run
    whose inputs set a noise (None when both are absent or zero)."""
    force = float(values.get("force_noise_n", 0.0))
    position = float(values.get("position_noise_m", 0.0))
    if force == 0.0 and position == 0.0:
        return None
    from hybridtable.systems.noise import MeasurementNoiseParams

    return MeasurementNoiseParams(force, position, int(seed))
