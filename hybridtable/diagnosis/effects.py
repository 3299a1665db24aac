"""Candidate physical effects: what the nominal rig model may be missing.

An :class:`Effect` is a change of the rig model, expressed as a change of a
:class:`ModelSpec` (which turns into the Drake back-ends of
:class:`hybridtable.measurement.rig.RigPhysics`), with named parameters (units, bounds,
the null value at which the effect vanishes) and the signature it leaves in
the residuals (channels, phases). The built-in library
(:mod:`hybridtable.diagnosis.library`, one module per effect):

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

from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m
from hybridtable.measurement.rig import RigPhysics, run_with_model_mass
from hybridtable.measurement.run_format import Run
from hybridtable.systems.contact_law import ContactLaw, ContactLawParams
from hybridtable.systems.measurement_chain import MeasurementChain, MeasurementChainParams
from hybridtable.systems.resonant_table import ResonantTable, StructuralModeParams

__all__ = [
    "STAGES",
    "RigScale",
    "ModelSpec",
    "EffectParameter",
    "Signature",
    "Effect",
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
        """The scale of the rig of ``runs`` (the first run's JSON), at their
        fastest approach."""
        if not runs:
            raise ParameterError("no runs")
        return cls.from_info(runs[0].info, max(r.info.initial_velocity_m_per_s for r in runs))

    @classmethod
    def from_info(cls, info: Any, velocity_m_per_s: float | None = None) -> RigScale:
        """The scale of the rig of a run's JSON (a
        :class:`~hybridtable.measurement.run_format.RunInfo`); the approach
        velocity defaults to its own."""
        return cls(
            stiffness_n_per_m=info.contact_stiffness_n_per_m,
            mass_kg=info.spacecraft_mass_kg,
            sample_period_s=info.sample_period_s,
            sensor_delay_s=info.sensor_delay_s,
            velocity_m_per_s=(
                info.initial_velocity_m_per_s if velocity_m_per_s is None else velocity_m_per_s
            ),
            table_frequency_hz=info.table_natural_frequency_hz,
        )

    @classmethod
    def from_params(cls, params: Any, sample_period_s: float) -> RigScale:
        """The scale of a loop's :class:`~hybridtable.loop.params.HybridLoopParams`,
        with the rig computer's period ``sample_period_s``."""
        return cls(
            stiffness_n_per_m=params.contact_stiffness_n_per_m,
            mass_kg=params.spacecraft_mass_kg,
            sample_period_s=sample_period_s,
            sensor_delay_s=params.sensor_delay_s,
            velocity_m_per_s=params.initial_velocity_m_per_s,
            table_frequency_hz=params.table_response_hz,
        )

    @property
    def peak_deflection_m(self) -> float:
        return self.velocity_m_per_s * math.sqrt(self.mass_kg / self.stiffness_n_per_m)

    @property
    def peak_force_n(self) -> float:
        return self.stiffness_n_per_m * self.peak_deflection_m

    @property
    def contact_duration_s(self) -> float:
        """Duration of an undamped contact, ``pi sqrt(m / k)`` (s): the time
        scale of the contact's dynamics, which bounds sensor lags and delays."""
        return math.pi * math.sqrt(self.mass_kg / self.stiffness_n_per_m)

    @property
    def critical_damping_n_s_per_m(self) -> float:
        return critical_damping_n_s_per_m(self.stiffness_n_per_m, self.mass_kg)

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
        Fields of :class:`~hybridtable.systems.contact_law.ContactLawParams`
        (``stiffness_n_per_m`` defaults to the run's nominal stiffness).
    sensor : mapping
        ``extra_delay_s`` (added to the run's sensor delay),
        ``time_constant_s``, ``bias_n``
        (:class:`~hybridtable.systems.measurement_chain.MeasurementChainParams`).
    table : mapping
        ``frequency_hz``, ``damping_ratio`` of a structural mode
        (:class:`~hybridtable.systems.resonant_table.StructuralModeParams`).
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
        """The :class:`~hybridtable.measurement.rig.RigPhysics` of this model (the nominal
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

    def linear_changes(self, params: Any) -> tuple[dict[str, float], list[str]]:
        """The model as changes of the linear loop's physical parameters.

        The linear models of :mod:`hybridtable.analysis` know a linear spring,
        viscous damping and a pure sensor delay. Returns the changes of
        ``params`` (a :class:`~hybridtable.loop.params.HybridLoopParams`;
        names in :data:`~hybridtable.measurement.rig.PHYSICS_PARAMS`) that
        represent this model there, and, in words, what they leave out:

        - ``damping_n_s_per_m`` -> ``contact_damping_n_s_per_m``;
        - ``stiffness_n_per_m`` -> ``contact_stiffness_n_per_m``;
        - ``series_compliance_m_per_n`` ``s`` -> the series stiffness
          ``k / (1 + k s)`` (exact for a massless structure);
        - ``extra_delay_s`` -> added to ``sensor_delay_s``;
        - ``bias_n``: a constant offset moves no pole (nothing to change);
        - any other change (a nonlinear law, friction, a filter, a mode, a
          user's wrapped system) is left out and named.
        """
        changes: dict[str, float] = {}
        left: list[str] = []
        contact = dict(self.contact)
        k = float(contact.pop("stiffness_n_per_m", params.contact_stiffness_n_per_m))
        if contact.pop("exponent", 1.0) != 1.0:
            left.append("the nonlinear contact stiffness (exponent != 1)")
        contact.pop("reference_deflection_m", None)
        s = float(contact.pop("series_compliance_m_per_n", 0.0))
        if k != params.contact_stiffness_n_per_m or s:
            changes["contact_stiffness_n_per_m"] = k / (1.0 + k * s)
        if "damping_n_s_per_m" in contact:
            changes["contact_damping_n_s_per_m"] = float(contact.pop("damping_n_s_per_m"))
        contact.pop("friction_velocity_m_per_s", None)
        for key, value in contact.items():
            if value:
                left.append(f"contact {key} = {value:g} (not linear)")
        sensor = dict(self.sensor)
        if sensor.get("extra_delay_s"):
            changes["sensor_delay_s"] = params.sensor_delay_s + float(sensor["extra_delay_s"])
        if sensor.get("time_constant_s"):
            left.append(f"the sensor's low pass ({sensor['time_constant_s']:g} s)")
        if self.table:
            left.append(
                f"the table's structural mode ({self.table.get('frequency_hz', math.nan):g} Hz)"
            )
        for component, _ in self.wrappers:
            left.append(f"a user effect's {component} system")
        return changes, left

    def closed_loop_run(self, run: Run) -> Run:
        """``run`` with the spacecraft mass the model integrates with
        (:func:`~hybridtable.measurement.rig.run_with_model_mass`)."""
        return run_with_model_mass(run, self.mass_ratio)


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
