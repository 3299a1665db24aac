"""Candidate physical effects: what the nominal rig model may be missing.

An :class:`Effect` is a change of the rig model, expressed as a change of a
:class:`ModelSpec` (which turns into the Drake back-ends of
:class:`hybridtable.rig.RigPhysics`), with named parameters (units, bounds,
the null value at which the effect vanishes) and the signature it leaves in
the residuals (channels, phases). The library (:data:`EFFECTS`):

=====================  ==========================================  ==================
effect                 parameters                                  signature
=====================  ==========================================  ==================
contact_damping        damping_n_s_per_m                           f_mea: compression +, restitution -
hunt_crossley          damping_factor_s_per_m                      f_mea: like damping, ~ deflection
nonlinear_stiffness    exponent, reference_stiffness_n_per_m       f_mea: shape of the force pulse
stiffness_error        contact_stiffness_n_per_m                   f_mea: height/length of the pulse
series_compliance      series_compliance_m_per_n                   f_mea: like a softer contact
coulomb_friction       friction_force_n                            f_mea: step at touch, +/- offset
sensor_filter          time_constant_s                             f_mea: lag, smoothed touch
extra_delay            extra_delay_s                               f_mea: shift of the pulse
table_resonance        frequency_hz, damping_ratio                 p_act (and f_mea): ringing
force_bias             bias_n                                      f_mea: offset in every phase
mass_error             mass_ratio                                  closed loop: v_des
=====================  ==========================================  ==================

Every effect except ``mass_error`` acts on the physical part and is seen by the
replay; ``mass_error`` (the spacecraft model integrating with another mass
than the run's JSON says) is seen only by the closed loop.

A user registers an effect of their own with :func:`register_effect`; its
``apply`` may change the fields of :class:`ModelSpec` or wrap a back-end with
:meth:`ModelSpec.wrap` (see ``docs/diagnose.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from hybridtable._validation import ParameterError
from hybridtable.effect_systems import (
    ContactLaw,
    ContactLawParams,
    MeasurementChain,
    MeasurementChainParams,
    ResonantTable,
    StructuralModeParams,
)
from hybridtable.measurement import Run
from hybridtable.rig import RigPhysics

__all__ = [
    "STAGES",
    "RigScale",
    "ModelSpec",
    "EffectParameter",
    "Signature",
    "Effect",
    "EFFECTS",
    "register_effect",
    "unregister_effect",
    "effect_names",
    "get_effect",
    "parse_effect_spec",
    "build_spec",
]

#: Where an effect is seen: in the replay of the physical part, or only in
#: the closed loop.
STAGES: tuple[str, ...] = ("replay", "closed_loop")

Bound = float | Callable[["RigScale"], float]


# -- scale of a rig ------------------------------------------------------------
@dataclass(frozen=True)
class RigScale:
    """Nominal magnitudes of a set of runs of one rig (bounds and scales of
    effect parameters are expressed with them), SI units.

    ``peak_deflection_m`` and ``peak_force_n`` are those of an undamped
    contact at the fastest approach, ``v sqrt(m / k)`` and ``k`` times it.
    """

    stiffness_n_per_m: float
    mass_kg: float
    sample_period_s: float
    sensor_delay_s: float
    velocity_m_per_s: float
    table_frequency_hz: float

    @classmethod
    def from_runs(cls, runs: Sequence[Run]) -> RigScale:
        if not runs:
            raise ParameterError("no runs")
        info = runs[0].info
        return cls(
            stiffness_n_per_m=info.contact_stiffness_n_per_m,
            mass_kg=info.spacecraft_mass_kg,
            sample_period_s=info.sample_period_s,
            sensor_delay_s=info.sensor_delay_s,
            velocity_m_per_s=max(r.info.initial_velocity_m_per_s for r in runs),
            table_frequency_hz=info.table_natural_frequency_hz,
        )

    @property
    def peak_deflection_m(self) -> float:
        return self.velocity_m_per_s * math.sqrt(self.mass_kg / self.stiffness_n_per_m)

    @property
    def peak_force_n(self) -> float:
        return self.stiffness_n_per_m * self.peak_deflection_m

    @property
    def critical_damping_n_s_per_m(self) -> float:
        return 2.0 * math.sqrt(self.stiffness_n_per_m * self.mass_kg)

    @property
    def nyquist_hz(self) -> float:
        return 0.5 / self.sample_period_s


# -- the model an effect changes -----------------------------------------------
Wrapper = Callable[[Any, Any], Any]  # (HybridLoopParams, System) -> System


@dataclass(frozen=True)
class ModelSpec:
    """A rig model as changes of the nominal one.

    Attributes
    ----------
    contact : mapping
        Fields of :class:`~hybridtable.effect_systems.ContactLawParams`
        (``stiffness_n_per_m`` defaults to the run's nominal stiffness).
    sensor : mapping
        ``extra_delay_s`` (added to the run's sensor delay),
        ``time_constant_s``, ``bias_n``
        (:class:`~hybridtable.effect_systems.MeasurementChainParams`).
    table : mapping
        ``frequency_hz``, ``damping_ratio`` of a structural mode
        (:class:`~hybridtable.effect_systems.StructuralModeParams`).
    mass_ratio : float
        Mass the spacecraft model integrates with, over the run's JSON mass
        (closed loop only).
    wrappers : tuple of (component, wrapper)
        ``component`` in ``"table"``, ``"contact"``, ``"sensor"``;
        ``wrapper(params, system) -> system`` with the same ports, applied
        after the fields above (a user's own effect).
    """

    contact: Mapping[str, float] = field(default_factory=dict)
    sensor: Mapping[str, float] = field(default_factory=dict)
    table: Mapping[str, float] = field(default_factory=dict)
    mass_ratio: float = 1.0
    wrappers: tuple[tuple[str, Wrapper], ...] = ()

    def __post_init__(self) -> None:
        for name in ("contact", "sensor", "table"):
            object.__setattr__(self, name, MappingProxyType(dict(getattr(self, name))))
        for component, _ in self.wrappers:
            if component not in ("table", "contact", "sensor"):
                raise ParameterError(
                    f"ModelSpec.wrappers: component must be table, contact or sensor "
                    f"(got {component!r})"
                )

    def with_contact(self, **values: float) -> ModelSpec:
        return replace(self, contact={**self.contact, **values})

    def with_sensor(self, **values: float) -> ModelSpec:
        return replace(self, sensor={**self.sensor, **values})

    def with_table(self, **values: float) -> ModelSpec:
        return replace(self, table={**self.table, **values})

    def wrap(self, component: str, wrapper: Wrapper) -> ModelSpec:
        """A spec whose ``component`` back-end is passed through ``wrapper``."""
        return replace(self, wrappers=(*self.wrappers, (component, wrapper)))

    @property
    def is_nominal(self) -> bool:
        return not (self.contact or self.sensor or self.table or self.wrappers) and (
            self.mass_ratio == 1.0
        )

    def _wrapped(self, component: str, make):
        wrappers = [w for c, w in self.wrappers if c == component]
        if make is None and not wrappers:
            return None

        def factory(params):
            if make is not None:
                system = make(params)
            else:
                system = getattr(RigPhysics(), f"make_{component}")(params)
            for w in wrappers:
                system = w(params, system)
            return system

        return factory

    def physics(self, name: str = "model") -> RigPhysics:
        """The :class:`~hybridtable.rig.RigPhysics` of this model (the nominal
        systems where nothing changes)."""
        contact = sensor = table = None
        if self.contact:
            values = dict(self.contact)

            def contact(params):
                law = {"stiffness_n_per_m": params.contact_stiffness_n_per_m, **values}
                return ContactLaw(ContactLawParams(**law))

        if self.sensor:
            s = dict(self.sensor)
            unknown = set(s) - {"extra_delay_s", "time_constant_s", "bias_n"}
            if unknown:
                raise ParameterError(f"ModelSpec.sensor: unknown field(s) {', '.join(unknown)}")

            def sensor(params):
                delay = params.sensor_delay_s + s.get("extra_delay_s", 0.0)
                if delay < 0.0:
                    raise ParameterError(
                        f"sensor delay {params.sensor_delay_s} s + extra_delay_s "
                        f"{s.get('extra_delay_s')} s is negative"
                    )
                return MeasurementChain(
                    MeasurementChainParams(
                        params.sample_period_s,
                        delay_s=max(delay, 0.0),
                        time_constant_s=s.get("time_constant_s", 0.0),
                        bias_n=s.get("bias_n", 0.0),
                    )
                )

        if self.table:
            mode = StructuralModeParams(**dict(self.table))

            def table(params):
                return ResonantTable(params.table(), mode)

        return RigPhysics(
            table=self._wrapped("table", table),
            contact=self._wrapped("contact", contact),
            sensor=self._wrapped("sensor", sensor),
            name=name,
        )

    def closed_loop_run(self, run: Run) -> Run:
        """``run`` with the spacecraft mass the model integrates with."""
        if self.mass_ratio == 1.0:
            return run
        info = replace(run.info, spacecraft_mass_kg=run.info.spacecraft_mass_kg * self.mass_ratio)
        return replace(run, info=info)


# -- effects -------------------------------------------------------------------
def _value(bound: Bound, scale: RigScale) -> float:
    return float(bound(scale)) if callable(bound) else float(bound)


@dataclass(frozen=True)
class EffectParameter:
    """A parameter of an effect.

    Parameters
    ----------
    name : str
        Name with its unit (``damping_n_s_per_m``).
    unit : str
        Unit, for reports (``"N s/m"``; ``"1"`` for a pure number).
    description : str
    lower, upper : float or callable
        Bounds of the fit (a callable gets the :class:`RigScale`).
    scale : float or callable
        A typical change (the fit's unit step).
    null : float or callable or None
        The value at which the effect vanishes (``None``: no such value, e.g.
        the frequency of a mode).
    initial : float or callable or None
        Start of the fit (default: ``null``, else the middle of the bounds).
    """

    name: str
    unit: str
    description: str
    lower: Bound
    upper: Bound
    scale: Bound
    null: Bound | None = None
    initial: Bound | None = None

    def bounds(self, scale: RigScale) -> tuple[float, float]:
        return _value(self.lower, scale), _value(self.upper, scale)

    def typical(self, scale: RigScale) -> float:
        return _value(self.scale, scale)

    def null_value(self, scale: RigScale) -> float | None:
        return None if self.null is None else _value(self.null, scale)

    def start(self, scale: RigScale) -> float:
        if self.initial is not None:
            return _value(self.initial, scale)
        if self.null is not None:
            return _value(self.null, scale)
        lo, hi = self.bounds(scale)
        return 0.5 * (lo + hi)


@dataclass(frozen=True)
class Signature:
    """Where an effect shows: residual channels, phases, and in words."""

    channels: tuple[str, ...]
    phases: tuple[str, ...]
    text: str


Apply = Callable[[ModelSpec, Mapping[str, float], RigScale], ModelSpec]
Starts = Callable[[RigScale, Sequence[Mapping[str, np.ndarray]]], list[dict[str, float]]]


@dataclass(frozen=True)
class Effect:
    """A candidate physical effect.

    Parameters
    ----------
    name : str
    description : str
    parameters : tuple of EffectParameter
        One or two (the fits stay cheap and identifiable).
    signature : Signature
    apply : callable
        ``apply(spec, values, scale) -> spec``: the model with the effect at
        the parameter values ``values`` (a mapping name -> value).
    stage : {"replay", "closed_loop"}
        Where the effect is seen (and fitted).
    touches : tuple of str
        What the effect changes (e.g. ``"contact.stiffness"``); two effects
        that touch the same thing are not combined.
    starts : callable, optional
        ``starts(scale, residuals) -> [values, ...]``: extra starting points
        of the fit, from the nominal residuals (``residuals[i]`` has
        ``"time_s"``, ``"f_mea_n"``, ``"p_act_m"`` of run ``i``).
    separation_hint : str
        What kind of run tells the effect apart from look-alikes.
    """

    name: str
    description: str
    parameters: tuple[EffectParameter, ...]
    signature: Signature
    apply: Apply
    stage: str = "replay"
    touches: tuple[str, ...] = ()
    starts: Starts | None = None
    separation_hint: str = ""

    def __post_init__(self) -> None:
        if not self.name or not self.name.replace("_", "").isalnum():
            raise ParameterError(f"effect name must be a word (got {self.name!r})")
        if self.stage not in STAGES:
            raise ParameterError(f"effect {self.name}: stage must be one of {', '.join(STAGES)}")
        if not self.parameters:
            raise ParameterError(f"effect {self.name}: needs at least one parameter")
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ParameterError(f"effect {self.name}: duplicate parameter names")
        object.__setattr__(self, "touches", tuple(self.touches) or (f"effect.{self.name}",))

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    def parameter(self, name: str) -> EffectParameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise ParameterError(
            f"effect {self.name} has no parameter {name!r} "
            f"(its parameters: {', '.join(self.parameter_names)})"
        )

    def start(self, scale: RigScale) -> dict[str, float]:
        return {p.name: p.start(scale) for p in self.parameters}

    def null_values(self, scale: RigScale) -> dict[str, float] | None:
        """Parameter values at which the effect vanishes (None if it has none)."""
        out = {p.name: p.null_value(scale) for p in self.parameters}
        return None if any(v is None for v in out.values()) else out

    def check_values(self, values: Mapping[str, float], scale: RigScale) -> dict[str, float]:
        """``values`` completed with the start values, checked against the bounds.

        Raises
        ------
        ParameterError
            Naming an unknown parameter or a value out of bounds.
        """
        out = self.start(scale)
        for name, value in values.items():
            p = self.parameter(name)
            lo, hi = p.bounds(scale)
            v = float(value)
            if not (math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(
                    f"{self.name}: {name} = {value} out of bounds [{lo:.6g}, {hi:.6g}] {p.unit}"
                )
            out[name] = v
        return out

    def conflicts_with(self, other: Effect) -> bool:
        return self is other or bool(set(self.touches) & set(other.touches))


#: The registry: effect name -> Effect.
EFFECTS: dict[str, Effect] = {}


def register_effect(effect: Effect, replace_existing: bool = False) -> Effect:
    """Add ``effect`` to :data:`EFFECTS` (diagnose fits every registered effect).

    Raises
    ------
    ParameterError
        If the name is taken and ``replace_existing`` is false.
    """
    if effect.name in EFFECTS and not replace_existing:
        raise ParameterError(f"effect {effect.name!r} is already registered")
    EFFECTS[effect.name] = effect
    return effect


def unregister_effect(name: str) -> None:
    """Remove an effect from the registry (no error if absent)."""
    EFFECTS.pop(name, None)


def effect_names() -> tuple[str, ...]:
    """Names of the registered effects, in registration order."""
    return tuple(EFFECTS)


def get_effect(name: str) -> Effect:
    """The registered effect ``name``.

    Raises
    ------
    ParameterError
        If there is none.
    """
    try:
        return EFFECTS[name]
    except KeyError:
        raise ParameterError(
            f"unknown effect {name!r} (one of {', '.join(effect_names())})"
        ) from None


def parse_effect_spec(text: str) -> tuple[Effect, dict[str, float]]:
    """``"EFFECT[:param=value,...]"`` -> (effect, given values).

    Raises
    ------
    ParameterError
        For an unknown effect or parameter, or a malformed value.
    """
    name, _, rest = text.strip().partition(":")
    effect = get_effect(name.strip())
    values: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise ParameterError(f"--add {text}: expected param=value, got {item!r}")
        effect.parameter(key)
        try:
            values[key] = float(value)
        except ValueError:
            raise ParameterError(f"--add {text}: {key} is not a number ({value!r})") from None
    return effect, values


def build_spec(
    effects: Sequence[tuple[Effect, Mapping[str, float]]],
    scale: RigScale,
    base: ModelSpec | None = None,
) -> ModelSpec:
    """The model with ``effects`` applied in order to ``base`` (default nominal)."""
    spec = base or ModelSpec()
    for effect, values in effects:
        spec = effect.apply(spec, values, scale)
    return spec


# -- the library ---------------------------------------------------------------
def _stiffness_parameter(name: str, description: str) -> EffectParameter:
    """A stiffness parameter from 0.2 to 5 times the nominal, null at the nominal."""
    return EffectParameter(
        name,
        "N/m",
        description,
        lower=lambda s: 0.2 * s.stiffness_n_per_m,
        upper=lambda s: 5.0 * s.stiffness_n_per_m,
        scale=lambda s: 0.01 * s.stiffness_n_per_m,
        null=lambda s: s.stiffness_n_per_m,
    )


def _resonance_starts(
    scale: RigScale, residuals: Sequence[Mapping[str, np.ndarray]]
) -> list[dict[str, float]]:
    """Starts of the mode's fit: the peak of the position residual's spectrum
    within the bounds, and a coarse grid."""
    lo = _mode_lower(scale)
    hi = _mode_upper(scale)
    starts = [
        {"frequency_hz": f, "damping_ratio": 0.05} for f in np.geomspace(lo * 1.5, hi / 1.5, 4)
    ]
    power, freqs = None, None
    for res in residuals:
        e = np.asarray(res["p_act_m"], dtype=float)
        if e.size < 16:
            continue
        e = (e - e.mean()) * np.hanning(e.size)
        n = 1 << int(math.ceil(math.log2(4 * e.size)))
        spec = np.abs(np.fft.rfft(e, n)) ** 2
        f = np.fft.rfftfreq(n, scale.sample_period_s)
        if power is None:
            power, freqs = spec, f
        elif len(spec) == len(power):
            power = power + spec
    if power is not None:
        band = (freqs >= lo) & (freqs <= hi)
        if band.any():
            peak = float(freqs[band][np.argmax(power[band])])
            starts = [
                {"frequency_hz": peak, "damping_ratio": z} for z in (0.02, 0.08, 0.2)
            ] + starts
    return starts


def _delay_starts(scale: RigScale, residuals) -> list[dict[str, float]]:
    h = scale.sample_period_s
    lo = -scale.sensor_delay_s
    return [{"extra_delay_s": j * h} for j in (-2, -1, 1, 2, 3) if j * h >= lo]


def _mode_lower(scale: RigScale) -> float:
    f = scale.table_frequency_hz
    return max(1.0, 0.5 * f) if math.isfinite(f) else 1.0


def _mode_upper(scale: RigScale) -> float:
    return 0.45 / scale.sample_period_s


def _library() -> list[Effect]:
    F_MEA, P_ACT, V_DES = "f_mea_n", "p_act_m", "v_des_m_per_s"
    CONTACT = ("compression", "restitution")
    return [
        Effect(
            name="contact_damping",
            description="viscous damping in the contact: f = k d + c v",
            parameters=(
                EffectParameter(
                    "damping_n_s_per_m",
                    "N s/m",
                    "viscous contact damping c",
                    lower=0.0,
                    upper=lambda s: s.critical_damping_n_s_per_m,
                    scale=lambda s: 0.01 * s.critical_damping_n_s_per_m,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "force higher in compression, lower in restitution; a jump c v at the touch; "
                "the force-deflection loop encloses energy",
            ),
            apply=lambda spec, v, s: spec.with_contact(damping_n_s_per_m=v["damping_n_s_per_m"]),
            touches=("contact.damping",),
            separation_hint="a run at another approach velocity (the damping force grows with it)",
        ),
        Effect(
            name="hunt_crossley",
            description="Hunt-Crossley damping, proportional to the deflection: "
            "f = k d (1 + alpha v)",
            parameters=(
                EffectParameter(
                    "damping_factor_s_per_m",
                    "s/m",
                    "Hunt-Crossley factor alpha (CoR ~ 1 - 2/3 alpha v_in)",
                    lower=0.0,
                    upper=lambda s: 10.0 / s.velocity_m_per_s,
                    scale=lambda s: 0.05 / s.velocity_m_per_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "like viscous damping but no jump at the touch: the damping force vanishes "
                "with the deflection",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                hunt_crossley_s_per_m=v["damping_factor_s_per_m"]
            ),
            touches=("contact.hunt_crossley",),
            separation_hint="a faster approach (the touch is steeper: a jump for viscous "
            "damping, none for Hunt-Crossley)",
        ),
        Effect(
            name="nonlinear_stiffness",
            description="power-law contact: f = k_ref d_ref (d / d_ref)^n, d_ref the peak "
            "deflection of an undamped contact at the fastest approach",
            parameters=(
                EffectParameter(
                    "exponent",
                    "1",
                    "exponent n (1: linear; 1.5: Hertzian)",
                    lower=0.5,
                    upper=3.0,
                    scale=0.02,
                    null=1.0,
                ),
                _stiffness_parameter(
                    "reference_stiffness_n_per_m", "secant stiffness f / d at d_ref"
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "the force pulse changes shape (steeper or flatter at small deflection), "
                "symmetric in compression and restitution",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                exponent=v["exponent"],
                stiffness_n_per_m=v["reference_stiffness_n_per_m"],
                reference_deflection_m=s.peak_deflection_m,
            ),
            touches=("contact.stiffness",),
            separation_hint="runs at two approach velocities (the secant stiffness changes "
            "with the peak deflection only for a power law)",
        ),
        Effect(
            name="stiffness_error",
            description="the contact stiffness differs from the nominal one",
            parameters=(
                _stiffness_parameter("contact_stiffness_n_per_m", "true contact stiffness k"),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "force pulse higher (stiffer) or lower, and shorter or longer",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                stiffness_n_per_m=v["contact_stiffness_n_per_m"]
            ),
            touches=("contact.stiffness",),
            separation_hint="a run with another contact spring, or a measurement of the "
            "contact point's position (a series compliance and a softer contact act as "
            "the same effective stiffness)",
        ),
        Effect(
            name="series_compliance",
            description="a compliance s of the structure between the table's position sensor "
            "and the contact: the contact deflects by d - s f",
            parameters=(
                EffectParameter(
                    "series_compliance_m_per_n",
                    "m/N",
                    "series compliance s (1 / structure stiffness)",
                    lower=0.0,
                    upper=lambda s: 4.0 / s.stiffness_n_per_m,
                    scale=lambda s: 0.01 / s.stiffness_n_per_m,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "a softer effective contact, k / (1 + k s); never a stiffer one",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                series_compliance_m_per_n=v["series_compliance_m_per_n"]
            ),
            touches=("contact.series",),
            separation_hint="a run with another contact spring, or a measurement of the "
            "contact point's position",
        ),
        Effect(
            name="coulomb_friction",
            description="a constant force F against the deflection rate while in contact "
            "(sign smoothed over 2 % of the approach velocity)",
            parameters=(
                EffectParameter(
                    "friction_force_n",
                    "N",
                    "Coulomb friction force F",
                    lower=0.0,
                    upper=lambda s: 0.3 * s.peak_force_n,
                    scale=lambda s: 0.005 * s.peak_force_n,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "a step +F at the touch, +F in compression, -F in restitution, the contact "
                "releases early",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                friction_force_n=v["friction_force_n"],
                friction_velocity_m_per_s=0.02 * s.velocity_m_per_s,
            ),
            touches=("contact.friction",),
            separation_hint="a run at another approach velocity (friction does not grow "
            "with it, damping does)",
        ),
        Effect(
            name="sensor_filter",
            description="first-order low pass of the force-measurement chain",
            parameters=(
                EffectParameter(
                    "time_constant_s",
                    "s",
                    "time constant tau of the low pass",
                    lower=0.0,
                    upper=lambda s: 10.0 * s.sample_period_s,
                    scale=lambda s: 0.5 * s.sample_period_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                ("compression", "restitution", "free_flight"),
                "the reading lags and the touch is rounded; a tail after the release",
            ),
            apply=lambda spec, v, s: spec.with_sensor(time_constant_s=v["time_constant_s"]),
            touches=("sensor.filter",),
            separation_hint="a faster or shorter contact (a larger approach velocity or a "
            "smaller spacecraft mass): a low pass rounds the touch, a delay only shifts it",
        ),
        Effect(
            name="extra_delay",
            description="the force sensor's delay differs from the nominal one (any "
            "fraction of a tick)",
            parameters=(
                EffectParameter(
                    "extra_delay_s",
                    "s",
                    "true delay minus nominal delay",
                    lower=lambda s: -s.sensor_delay_s,
                    upper=lambda s: 5.0 * s.sample_period_s,
                    scale=lambda s: 0.5 * s.sample_period_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "the measured pulse shifted in time: error ~ delay x force rate, + at "
                "the touch and - at the release",
            ),
            apply=lambda spec, v, s: spec.with_sensor(extra_delay_s=v["extra_delay_s"]),
            touches=("sensor.delay",),
            starts=_delay_starts,
            separation_hint="a faster or shorter contact (a larger approach velocity or a "
            "smaller spacecraft mass)",
        ),
        Effect(
            name="table_resonance",
            description="a lightly damped structural mode between the table's servo and "
            "its contact device",
            parameters=(
                EffectParameter(
                    "frequency_hz",
                    "Hz",
                    "natural frequency of the mode",
                    lower=_mode_lower,
                    upper=_mode_upper,
                    scale=lambda s: 0.01 * _mode_upper(s),
                    initial=lambda s: math.sqrt(_mode_lower(s) * _mode_upper(s)),
                ),
                EffectParameter(
                    "damping_ratio",
                    "1",
                    "damping ratio of the mode",
                    lower=0.005,
                    upper=1.0,
                    scale=0.01,
                    initial=0.05,
                ),
            ),
            signature=Signature(
                (P_ACT, F_MEA),
                ("approach", "compression", "restitution", "free_flight"),
                "ringing of the table position at the mode's frequency after the start "
                "and the touch, and in the force while in contact",
            ),
            apply=lambda spec, v, s: spec.with_table(
                frequency_hz=v["frequency_hz"], damping_ratio=v["damping_ratio"]
            ),
            touches=("table.mode",),
            starts=_resonance_starts,
            separation_hint="a run with a sharper start (a larger approach velocity)",
        ),
        Effect(
            name="force_bias",
            description="an offset in the force reading",
            parameters=(
                EffectParameter(
                    "bias_n",
                    "N",
                    "offset b of the reading",
                    lower=lambda s: -0.2 * s.peak_force_n,
                    upper=lambda s: 0.2 * s.peak_force_n,
                    scale=lambda s: 0.002 * s.peak_force_n,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                ("approach", "compression", "restitution", "free_flight"),
                "a constant force error in every phase, also without contact",
            ),
            apply=lambda spec, v, s: spec.with_sensor(bias_n=v["bias_n"]),
            touches=("sensor.bias",),
            separation_hint="a longer record without contact",
        ),
        Effect(
            name="mass_error",
            description="the spacecraft model integrates with another mass than the run's "
            "JSON says (closed loop only)",
            parameters=(
                EffectParameter(
                    "mass_ratio",
                    "1",
                    "mass used over the JSON's spacecraft_mass_kg",
                    lower=0.5,
                    upper=2.0,
                    scale=0.005,
                    null=1.0,
                ),
            ),
            signature=Signature(
                (V_DES,),
                CONTACT,
                "closed loop: the spacecraft's velocity change in contact is off by the "
                "mass ratio; the replay is unaffected",
            ),
            apply=lambda spec, v, s: replace(spec, mass_ratio=v["mass_ratio"]),
            stage="closed_loop",
            touches=("spacecraft.mass",),
            separation_hint="none needed: the closed loop tells the mass from the physics",
        ),
    ]


for _effect in _library():
    register_effect(_effect)
del _effect
