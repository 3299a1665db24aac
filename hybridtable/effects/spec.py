"""The model an effect changes (:class:`ModelSpec`) and the scale of a rig (:class:`RigScale`).

A :class:`ModelSpec` is the nominal rig model plus changes: fields of the
contact law, the sensor's measurement chain and a structural mode of the table
(Drake back-ends of :class:`~hybridtable.measurement.rig.RigPhysics`), the mass
the rig computer integrates with, a user's wrapped systems, and changes of the
loop's own parameters (:attr:`ModelSpec.loop`: the table's response, the
compensator's lead, what the MDC believes). The same spec is

- replayed and run closed loop against recorded runs (``diagnose``,
  ``compare --add``): :meth:`ModelSpec.physics` gives its systems;
- run through one contact for a CoR (``explain``): :meth:`ModelSpec.realize`
  gives the loop's parameters and, when a change is not one of them (a
  nonlinear law, a filter, a mode, a wrapped system), the systems to build;
  where every change is a loop parameter the fast engine runs it;
- put on the linear loop (``margins --model``): :meth:`ModelSpec.linear_changes`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m
from hybridtable.limits import LIMITS
from hybridtable.loop.params import HybridLoopParams
from hybridtable.measurement.rig import RigPhysics, model_mass_kg, run_with_model_mass
from hybridtable.measurement.run_format import Run
from hybridtable.systems.contact_law import ContactLaw, ContactLawParams
from hybridtable.systems.measurement_chain import MeasurementChain, MeasurementChainParams
from hybridtable.systems.resonant_table import ResonantTable, StructuralModeParams

__all__ = ["RigScale", "ModelSpec", "LoopChange"]


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

#: A change of the loop's own parameters: ``change(params) -> params`` (e.g.
#: the table's response frequency times a ratio). A change of the physics goes
#: through :meth:`~hybridtable.loop.params.HybridLoopParams.with_physics`, so
#: that the compensator keeps what it believed.
LoopChange = Callable[[HybridLoopParams], HybridLoopParams]


@dataclass(frozen=True)
class ModelSpec:
    """A rig model as changes of the nominal one.

    Attributes
    ----------
    contact : mapping
        Fields of :class:`~hybridtable.systems.contact_law.ContactLawParams`
        (``stiffness_n_per_m`` defaults to the run's nominal stiffness;
        ``damping_n_s_per_m`` adds to the stated damping, which a run states
        as none).
    sensor : mapping
        ``extra_delay_s`` (added to the run's sensor delay),
        ``time_constant_s``, ``bias_n``, ``mount_frequency_hz``,
        ``mount_damping_ratio``
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
    loop : tuple of LoopChange
        Changes of the loop's parameters, applied in order after the fields
        above (on each run's or each CoR row's own parameters).
    """

    contact: Mapping[str, float] = field(default_factory=dict)
    sensor: Mapping[str, float] = field(default_factory=dict)
    table: Mapping[str, float] = field(default_factory=dict)
    mass_ratio: float = 1.0
    wrappers: tuple[tuple[str, Wrapper], ...] = ()
    loop: tuple[LoopChange, ...] = ()

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

    def with_loop(self, change: LoopChange) -> ModelSpec:
        """A spec that changes the loop's parameters by ``change`` too."""
        return replace(self, loop=(*self.loop, change))

    @property
    def is_nominal(self) -> bool:
        return not (self.contact or self.sensor or self.table or self.wrappers or self.loop) and (
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
                # a damper adds to the stated one (a run states none)
                law["damping_n_s_per_m"] = params.contact_damping_n_s_per_m + values.get(
                    "damping_n_s_per_m", 0.0
                )
                return ContactLaw(ContactLawParams(**law))

        if self.sensor:
            s = dict(self.sensor)
            chain = {"time_constant_s", "bias_n", "mount_frequency_hz", "mount_damping_ratio"}
            unknown = set(s) - chain - {"extra_delay_s"}
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
                        **{k: v for k, v in s.items() if k in chain},
                    )
                )

        if self.table:
            mode = StructuralModeParams(**dict(self.table))

            def table(params):
                return ResonantTable(params.plant.table, mode)

        return RigPhysics(
            table=self._wrapped("table", table),
            contact=self._wrapped("contact", contact),
            sensor=self._wrapped("sensor", sensor),
            name=name,
            loop=self.loop,
        )

    def _contact_changes(self, params: HybridLoopParams) -> tuple[dict[str, float], list[str]]:
        """The contact's fields as changes of the loop's physical parameters, and,
        in words, what they leave out."""
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
        if "damping_n_s_per_m" in contact:  # added to the stated damper (a run states none)
            extra = float(contact.pop("damping_n_s_per_m"))
            changes["contact_damping_n_s_per_m"] = params.contact_damping_n_s_per_m + extra
        contact.pop("friction_velocity_m_per_s", None)
        for key, value in contact.items():
            if value:
                left.append(f"contact {key} = {value:g} (not linear)")
        return changes, left

    def _sensor_changes(
        self, params: HybridLoopParams, exact: bool
    ) -> tuple[dict[str, float], list[str]]:
        """The sensor's fields as a change of the sensor delay, and, in words,
        what that leaves out (``exact``: an offset too, and a delay below the
        smallest plausible one, :data:`~hybridtable.limits.LIMITS`, held at 0)."""
        changes: dict[str, float] = {}
        left: list[str] = []
        sensor = dict(self.sensor)
        if sensor.get("extra_delay_s"):
            delay = params.sensor_delay_s + float(sensor["extra_delay_s"])
            if exact:  # held at zero, as is one below the smallest a rig states
                delay = delay if delay >= LIMITS["sensor_delay_s"].smallest_nonzero else 0.0
            changes["sensor_delay_s"] = delay
        if sensor.get("time_constant_s"):
            left.append(f"the sensor's low pass ({sensor['time_constant_s']:g} s)")
        if math.isfinite(sensor.get("mount_frequency_hz", math.inf)):
            left.append(f"the sensor's mount ({sensor['mount_frequency_hz']:g} Hz)")
        if exact and sensor.get("bias_n"):
            left.append(f"the sensor's offset ({sensor['bias_n']:g} N)")
        return changes, left

    def _systems_left(self) -> list[str]:
        """What only systems carry, beside the contact and the sensor: the
        table's mode, a user's wrapped systems."""
        left = []
        if self.table:
            left.append(
                f"the table's structural mode ({self.table.get('frequency_hz', math.nan):g} Hz)"
            )
        for component, _ in self.wrappers:
            left.append(f"a user effect's {component} system")
        return left

    def linear_changes(self, params: Any) -> tuple[dict[str, float], list[str]]:
        """The model as changes of the linear loop's physical parameters.

        The linear models of :mod:`hybridtable.analysis` know a linear spring,
        viscous damping and a pure sensor delay. Returns the changes of
        ``params`` (a :class:`~hybridtable.loop.params.HybridLoopParams`;
        names in :data:`~hybridtable.measurement.rig.PHYSICS_PARAMS`) that
        represent this model there, and, in words, what they leave out:

        - ``damping_n_s_per_m`` -> added to ``contact_damping_n_s_per_m``;
        - ``stiffness_n_per_m`` -> ``contact_stiffness_n_per_m``;
        - ``series_compliance_m_per_n`` ``s`` -> the series stiffness
          ``k / (1 + k s)`` (exact for a massless structure);
        - ``extra_delay_s`` -> added to ``sensor_delay_s``;
        - ``bias_n``: a constant offset moves no pole (nothing to change);
        - any other change (a nonlinear law, friction, a filter, a mode, the
          sensor's mount, a user's wrapped system) is left out and named.

        The changes of :attr:`loop` are not among them: the caller applies
        them (:class:`~hybridtable.measurement.rig.RigPhysics` ``loop``).
        """
        changes, left = self._contact_changes(params)
        sensor, sensor_left = self._sensor_changes(params, exact=False)
        return changes | sensor, left + sensor_left + self._systems_left()

    def realize(self, params: HybridLoopParams) -> tuple[HybridLoopParams, RigPhysics | None]:
        """The loop of this model on the stated loop ``params``, for one contact.

        Returns the loop's parameters and, when a change is not one of them (a
        nonlinear contact law, friction, a sensor's filter, mount or offset, a
        structural mode, a user's wrapped system), the
        :class:`~hybridtable.measurement.rig.RigPhysics` whose systems carry it;
        ``None`` when the parameters carry every change, so that the loop's fast
        engine (:func:`~hybridtable.loop.fast.simulate_fast`) runs the model.

        The contact's stiffness and damping and the sensor's delay (held at zero
        below the smallest a rig states) change the physics, unknown to the compensator
        (:meth:`~hybridtable.loop.params.HybridLoopParams.with_physics`); the
        computer integrates with ``mass_ratio`` times the stated mass; then
        :attr:`loop` applies in order.

        The contact and the sensor each become loop parameters when all of
        their changes are (a contact damper, stiffness or series compliance; a
        sensor delay), else their system carries them all.

        Raises
        ------
        ParameterError
            A change the systems cannot carry on this loop (a sensor's filter or
            offset on a continuous rig computer).
        """
        contact, contact_left = self._contact_changes(params)
        sensor, sensor_left = self._sensor_changes(params, exact=True)
        # the contact and the sensor each: its loop parameters, or its system
        exact = (contact if not contact_left else {}) | (sensor if not sensor_left else {})
        p = params.with_physics(**exact) if exact else params
        if self.mass_ratio != 1.0:
            p = p.with_(spacecraft_mass_kg=model_mass_kg(p.spacecraft_mass_kg, self.mass_ratio))
        for change in self.loop:
            p = change(p)
        if not (contact_left or sensor_left or self._systems_left()):
            return p, None
        if sensor_left and p.sample_rate_hz is None:
            raise ParameterError(
                f"{sensor_left[0]} is a system of a sampled rig computer: the loop needs a "
                "sample rate"
            )
        systems = replace(
            self,
            loop=(),
            contact=self.contact if contact_left else {},
            sensor=self.sensor if sensor_left else {},
        )
        return p, systems.physics()

    def closed_loop_run(self, run: Run) -> Run:
        """``run`` with the spacecraft mass the model integrates with
        (:func:`~hybridtable.measurement.rig.run_with_model_mass`)."""
        return run_with_model_mass(run, self.mass_ratio)
