"""Parameters of one hybrid-loop run (:class:`HybridLoopParams`), SI units: a
scenario nested one config per component, as Tedrake's ``manipulation``
scenarios are::

    HybridLoopParams
      plant: Plant                     what is physically there
        spacecraft: SpacecraftParams     mass_kg
        contact: ContactParams           stiffness_n_per_m, damping_n_s_per_m
        table: TableParams               response_frequency_hz, damping_ratio
      rig: RigComputer                 the rig's computer
        sensor: SensorParams             sensor_delay_s
        sample_rate_hz, time_step_s
        compensator: CompensatorConfig   name, what it believes, dead band, clamp, gate, passivity
      approach: Approach               initial_velocity_m_per_s, initial_gap_m, the table's state

Each system of the loop takes its own config (``params.plant.contact`` is the
contact's). Each quantity also has one flat name (:data:`FIELDS`): the
vocabulary of the command-line flags, the plausible ranges
(:data:`hybridtable.limits.LIMITS`), sweep axes, scenario and model files. The
flat names build and change a scenario (``HybridLoopParams(spacecraft_mass_kg=...,
contact_stiffness_n_per_m=...)``, ``params.with_(sensor_delay_s=0.01)``) and read
it (``params.sensor_delay_s`` is ``params.rig.sensor.sensor_delay_s``).

Why one module: the configs, the flat names (:data:`FIELDS`) that each
config's checks are worded in, and the scenario that builds and reads them
through those names are one concept; apart, each would import the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from hybridtable._nested import NestedParams, flat_properties
from hybridtable._validation import check_choice, check_nonnegative, check_positive
from hybridtable.compensators.paper import CONTACT_GATES, CompensatorParams
from hybridtable.compensators.registry import compensator_names
from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m, mass_for_contact_frequency_kg
from hybridtable.laws.spacecraft import DEFAULT_INTEGRATOR, INTEGRATORS
from hybridtable.limits import check_plausible, limit_of, limit_words
from hybridtable.systems.contact import ContactParams
from hybridtable.systems.sensor import SensorParams
from hybridtable.systems.spacecraft import SpacecraftParams
from hybridtable.systems.table import TableParams

__all__ = [
    "TABLE_INITIAL_STATES",
    "BELIEFS",
    "FIELDS",
    "Approach",
    "CompensatorConfig",
    "HybridLoopParams",
    "Plant",
    "RigComputer",
    "believed",
]


TABLE_INITIAL_STATES: tuple[str, ...] = ("tracking", "command", "rest", "given")

#: What the compensator believes -> the true value it believes unless told
#: (``None``): the SDC's lead is the sensor delay, the MDC's stiffness and
#: damping are the contact's (:meth:`HybridLoopParams.beliefs`).
BELIEFS: dict[str, str] = {
    "lead_time_s": "sensor_delay_s",
    "compensator_stiffness_n_per_m": "contact_stiffness_n_per_m",
    "compensator_damping_n_s_per_m": "contact_damping_n_s_per_m",
}

#: Each quantity's flat name -> where it lives in :class:`HybridLoopParams`.
FIELDS: dict[str, tuple[str, ...]] = {
    "spacecraft_mass_kg": ("plant", "spacecraft", "mass_kg"),
    "contact_stiffness_n_per_m": ("plant", "contact", "stiffness_n_per_m"),
    "contact_damping_n_s_per_m": ("plant", "contact", "damping_n_s_per_m"),
    "sensor_delay_s": ("rig", "sensor", "sensor_delay_s"),
    "table_response_hz": ("plant", "table", "response_frequency_hz"),
    "table_damping_ratio": ("plant", "table", "damping_ratio"),
    "compensator": ("rig", "compensator", "name"),
    "lead_time_s": ("rig", "compensator", "lead_time_s"),
    "compensator_stiffness_n_per_m": ("rig", "compensator", "stiffness_n_per_m"),
    "compensator_damping_n_s_per_m": ("rig", "compensator", "damping_n_s_per_m"),
    "force_deadband_n": ("rig", "compensator", "force_deadband_n"),
    "clamp_nonnegative": ("rig", "compensator", "clamp_nonnegative"),
    "contact_gate": ("rig", "compensator", "contact_gate"),
    "initial_velocity_m_per_s": ("approach", "initial_velocity_m_per_s"),
    "initial_gap_m": ("approach", "initial_gap_m"),
    "table_initial_state": ("approach", "table_initial_state"),
    "table_initial_position_m": ("approach", "table_initial_position_m"),
    "table_initial_velocity_m_per_s": ("approach", "table_initial_velocity_m_per_s"),
    "sample_rate_hz": ("rig", "sample_rate_hz"),
    "time_step_s": ("rig", "time_step_s"),
    "passivity": ("rig", "compensator", "passivity"),
    "computer_integrator": ("rig", "integrator"),
}


def believed(params: Any, belief: str, truth: float | None = None) -> float:
    """What the compensator believes for ``belief`` (a key of :data:`BELIEFS`)
    in any parameter set with both fields (the 1-D and 6-DoF loops', a CoR
    table's conditions): the stated value, or the true one it stands for
    (``truth``, where a search varies it without a new parameter set; default:
    the set's own)."""
    value = getattr(params, belief)
    if value is not None:
        return value
    return getattr(params, BELIEFS[belief]) if truth is None else truth


def _plausible(config: Any, prefix: tuple[str, ...], names: tuple[str, ...]) -> None:
    """Each flat name in ``names`` (under ``prefix``) inside its plausible range
    (:mod:`hybridtable.limits`), so that no absurd value reaches a simulation
    that would run forever."""
    for name in names:
        value = config
        for key in FIELDS[name][len(prefix) :]:
            value = getattr(value, key)
        if value is not None:
            check_plausible(name, value)


def _set(config: Any, name: str, value: Any) -> None:
    object.__setattr__(config, name, value)


@dataclass(frozen=True)
class Plant:
    """What is physically there: the spacecraft model, the contact, the table.

    Parameters
    ----------
    spacecraft : SpacecraftParams
        The spacecraft model's mass m (``spacecraft_mass_kg``), > 0.
    contact : ContactParams
        True contact stiffness k_con (``contact_stiffness_n_per_m``), > 0, and
        damping (``contact_damping_n_s_per_m``), >= 0.
    table : TableParams
        Table response frequency f_resp (``table_response_hz``), > 0,
        ``math.inf`` for an ideal table; damping ratio (``table_damping_ratio``).
    """

    spacecraft: SpacecraftParams
    contact: ContactParams
    table: TableParams = TableParams(math.inf, 0.8)

    def __post_init__(self) -> None:
        _plausible(
            self,
            ("plant",),
            (
                "spacecraft_mass_kg",
                "contact_stiffness_n_per_m",
                "contact_damping_n_s_per_m",
                "table_response_hz",
                "table_damping_ratio",
            ),
        )


@dataclass(frozen=True)
class CompensatorConfig:
    """The compensator the rig's computer runs, and what it believes.

    Parameters
    ----------
    name : str
        A registered compensator (``compensator``,
        :func:`hybridtable.compensators.registry.compensator_names`): the
        paper's "none", "SDC", "MDC", "SDMDC", or a plug-in.
    lead_time_s : float or None
        SDC lead time; ``None`` means the sensor delay (the paper's choice).
    stiffness_n_per_m, damping_n_s_per_m : float or None
        What the MDC believes (``compensator_stiffness_n_per_m``,
        ``compensator_damping_n_s_per_m``); ``None`` means the true contact
        values (:data:`BELIEFS`, resolved by :meth:`HybridLoopParams.beliefs`).
    force_deadband_n : float
        Measured forces at or below this are "no contact".
    clamp_nonnegative : bool
        Clamp the compensated force at zero.
    contact_gate : {"measured_force", "table_position"}
        How the compensator tells contact (:mod:`hybridtable.compensators.paper`).
    passivity : bool
        Guard the compensator with the time-domain passivity observer and
        controller (:mod:`hybridtable.compensators.passivity`).
    """

    name: str = "none"
    lead_time_s: float | None = None
    stiffness_n_per_m: float | None = None
    damping_n_s_per_m: float | None = None
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False
    contact_gate: str = "measured_force"
    passivity: bool = False

    def __post_init__(self) -> None:
        _set(self, "force_deadband_n", check_nonnegative("force_deadband_n", self.force_deadband_n))
        _set(
            self, "name", check_choice("compensator", self.name, compensator_names(), any_case=True)
        )
        check_choice("contact_gate", self.contact_gate, CONTACT_GATES)
        for key, name in (
            ("lead_time_s", "lead_time_s"),
            ("stiffness_n_per_m", "compensator_stiffness_n_per_m"),
            ("damping_n_s_per_m", "compensator_damping_n_s_per_m"),
        ):
            if getattr(self, key) is not None:
                _set(self, key, check_nonnegative(name, getattr(self, key)))
        _plausible(
            self,
            ("rig", "compensator"),
            (
                "lead_time_s",
                "compensator_stiffness_n_per_m",
                "compensator_damping_n_s_per_m",
                "force_deadband_n",
            ),
        )


@dataclass(frozen=True)
class RigComputer:
    """The rig's computer: the force it reads, its rate, its compensator.

    Parameters
    ----------
    sensor : SensorParams
        The force-sensor delay T_fms (``sensor_delay_s``), >= 0.
    sample_rate_hz : float or None
        ``None``: a continuous rig computer. Otherwise the rate of its loop; a
        sensor delay between ticks reads the two neighbouring samples
        interpolated (:func:`~hybridtable.systems.sensor.sample_taps`).
    time_step_s : float or None
        Continuous mode: the largest integration step and delay-line period
        (``None``: :attr:`HybridLoopParams.step_s`).
    compensator : CompensatorConfig
        The compensator it runs and what it believes.
    integrator : str
        The rule a sampled computer steps its spacecraft model by
        (:data:`~hybridtable.laws.spacecraft.INTEGRATORS`; default the run
        format's semi-implicit Euler). A continuous computer integrates the
        model exactly: only the default applies.
    """

    sensor: SensorParams = SensorParams()
    sample_rate_hz: float | None = None
    time_step_s: float | None = None
    # Built on use, not at import: a compensator plug-in may import this module.
    compensator: CompensatorConfig = field(default_factory=CompensatorConfig)
    integrator: str = DEFAULT_INTEGRATOR

    def __post_init__(self) -> None:
        for name, kind in (("sensor", SensorParams), ("compensator", CompensatorConfig)):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError(f"{name} must be a {kind.__name__}")
        for name in ("sample_rate_hz", "time_step_s"):
            if getattr(self, name) is not None:
                _set(self, name, check_positive(name, getattr(self, name)))
        _plausible(self, ("rig",), ("sensor_delay_s", "sample_rate_hz", "time_step_s"))
        check_choice("computer_integrator", self.integrator, tuple(INTEGRATORS))
        if self.sample_rate_hz is None and self.integrator != DEFAULT_INTEGRATOR:
            raise ParameterError(
                f"computer_integrator {self.integrator!r} needs a sampled rig computer "
                "(a sample rate); a continuous one integrates its model exactly"
            )

    @property
    def sample_period_s(self) -> float | None:
        """1 / sample_rate_hz, or None for a continuous rig computer."""
        return None if self.sample_rate_hz is None else 1.0 / self.sample_rate_hz


@dataclass(frozen=True)
class Approach:
    """How the run starts: the spacecraft's approach and the table's state.

    Parameters
    ----------
    initial_velocity_m_per_s : float
        Approach velocity of the spacecraft model, > 0.
    initial_gap_m : float
        Gap between the devices at t = 0, >= 0.
    table_initial_state : {"tracking", "command", "rest", "given"}
        ``"tracking"``: the table starts in steady tracking of the approach
        ramp (lag ``2 zeta / omega`` behind the command, same velocity), so the
        contact sees no start-up transient. ``"command"``: at the initial
        command position with the approach velocity (a rig that starts its
        record while already moving). ``"rest"``: at the initial command, at
        rest. ``"given"``: at ``table_initial_position_m`` with
        ``table_initial_velocity_m_per_s`` (a contact event cut from a long log,
        whose table was following an earlier command).
    table_initial_position_m, table_initial_velocity_m_per_s : float or None
        The table's state at t = 0 when ``table_initial_state="given"`` (m, m/s).
    """

    initial_velocity_m_per_s: float = 0.1
    initial_gap_m: float = 0.001
    table_initial_state: str = "tracking"
    table_initial_position_m: float | None = None
    table_initial_velocity_m_per_s: float | None = None

    def __post_init__(self) -> None:
        v = check_positive("initial_velocity_m_per_s", self.initial_velocity_m_per_s)
        _set(self, "initial_velocity_m_per_s", v)
        _set(self, "initial_gap_m", check_nonnegative("initial_gap_m", self.initial_gap_m))
        check_choice("table_initial_state", self.table_initial_state, TABLE_INITIAL_STATES)
        given = (self.table_initial_position_m, self.table_initial_velocity_m_per_s)
        if self.table_initial_state == "given":
            if None in given:
                raise ParameterError(
                    'table_initial_state "given" needs table_initial_position_m and '
                    "table_initial_velocity_m_per_s"
                )
            check_plausible("p_act_m", given[0], where="table_initial_position_m")
            check_plausible("v_des_m_per_s", given[1], where="table_initial_velocity_m_per_s")
        elif given != (None, None):
            raise ParameterError(
                "table_initial_position_m and table_initial_velocity_m_per_s need "
                'table_initial_state "given"'
            )
        _plausible(self, ("approach",), ("initial_velocity_m_per_s", "initial_gap_m"))


@flat_properties
@dataclass(frozen=True, init=False)
class HybridLoopParams(NestedParams):
    """Every parameter of one hybrid-loop run, SI units, one config per
    component (the module's docstring draws the tree).

    Build it nested (``HybridLoopParams(plant=Plant(...), rig=RigComputer(...))``)
    or by the quantities' flat names (:data:`FIELDS`), or both: the flat names
    change the configs given (or the defaults)::

        HybridLoopParams(spacecraft_mass_kg=2533.0, contact_stiffness_n_per_m=1e5,
                         sensor_delay_s=0.005, compensator="SDMDC")

    Every flat name reads as a property (``params.sensor_delay_s``), and
    :meth:`with_` changes by flat name or by config. The plant is required
    (``spacecraft_mass_kg`` and ``contact_stiffness_n_per_m`` at least); the rig
    computer defaults to a continuous one with no delay and no compensator,
    the approach to 0.1 m/s from 1 mm with the table tracking.
    """

    plant: Plant
    rig: RigComputer = field(default_factory=RigComputer)
    approach: Approach = Approach()

    PARTS: ClassVar[dict[str, type]] = {"plant": Plant, "rig": RigComputer, "approach": Approach}
    FIELDS: ClassVar[dict[str, tuple[str, ...]]] = FIELDS
    REQUIRED: ClassVar[dict[str, str]] = {
        "plant": "plant= or spacecraft_mass_kg and contact_stiffness_n_per_m"
    }
    EXAMPLE: ClassVar[str] = "spacecraft_mass_kg"

    # -- derived quantities ------------------------------------------------
    @classmethod
    def from_contact_frequency(
        cls, contact_frequency_hz: float, contact_stiffness_n_per_m: float, **kwargs
    ) -> HybridLoopParams:
        """Parameters with the mass that gives the contact natural frequency
        ``f_con = sqrt(k / m) / (2 pi)`` (how the paper specifies its runs)."""
        f = check_positive("contact_frequency_hz", contact_frequency_hz)
        k = check_positive("contact_stiffness_n_per_m", contact_stiffness_n_per_m)
        check_plausible("contact_frequency_hz", f)
        check_plausible("contact_stiffness_n_per_m", k)
        m = mass_for_contact_frequency_kg(k, f)
        if not limit_of("spacecraft_mass_kg").contains(m):
            raise ParameterError(
                f"contact_frequency_hz = {f:g} Hz with contact_stiffness_n_per_m = {k:g} N/m "
                f"makes spacecraft_mass_kg = {m:.3g} kg, outside its plausible range "
                f"{limit_words('spacecraft_mass_kg')}"
            )
        return cls(spacecraft_mass_kg=m, contact_stiffness_n_per_m=k, **kwargs)

    @property
    def contact_frequency_hz(self) -> float:
        """Undamped contact natural frequency sqrt(k/m) / 2 pi."""
        return math.sqrt(self.contact_stiffness_n_per_m / self.spacecraft_mass_kg) / (2 * math.pi)

    @property
    def step_s(self) -> float:
        """The continuous mode's step: ``time_step_s`` or its default."""
        if self.time_step_s is not None:
            return self.time_step_s
        return min(2e-4, 1.0 / (5000.0 * self.contact_frequency_hz))

    @property
    def sample_period_s(self) -> float | None:
        """1 / sample_rate_hz, or None for a continuous loop."""
        return self.rig.sample_period_s

    @property
    def effective_delay_s(self) -> float:
        """tau_eff = T_fms + 2 zeta / omega_resp, the loop's low-frequency delay."""
        return self.sensor_delay_s + self.plant.table.ramp_lag_s

    # -- what the compensator believes -----------------------------------------
    def beliefs(self) -> dict[str, float]:
        """What the compensator believes, resolved: each field of :data:`BELIEFS`,
        or, where it is ``None``, the true value it stands for (the compensator
        believes the truth unless told otherwise)."""
        return {belief: believed(self, belief) for belief in BELIEFS}

    def with_beliefs_pinned(self) -> HybridLoopParams:
        """A copy whose compensator beliefs are explicit (:meth:`beliefs`), so
        that a later change of the true values leaves them where they are."""
        return self.with_(**self.beliefs())

    def with_physics(self, **changes) -> HybridLoopParams:
        """A copy with true (physical) values changed while the compensator
        keeps believing what it believed before the change (a hidden effect:
        the rig's software does not know of it).

        Raises
        ------
        ParameterError
            If ``changes`` names a belief (:data:`BELIEFS`): that is the
            compensator's, not physics; change it with :meth:`with_`.
        """
        told = [name for name in changes if name in BELIEFS]
        if told:
            raise ParameterError(
                f"with_physics: {', '.join(told)} is what the compensator believes, "
                "not physics (use with_)"
            )
        return self.with_beliefs_pinned().with_(**changes)

    def with_contact_damping_ratio(self, damping_ratio: float) -> HybridLoopParams:
        """A copy whose contact damping is ``damping_ratio`` of the critical one:
        ``c = 2 zeta sqrt(k m)`` (N s/m), ``zeta >= 0``."""
        zeta = check_nonnegative("contact_damping_ratio", damping_ratio)
        check_plausible("contact_damping_ratio", zeta)
        c = zeta * critical_damping_n_s_per_m(
            self.contact_stiffness_n_per_m, self.spacecraft_mass_kg
        )
        return self.with_(contact_damping_n_s_per_m=c)

    def compensator_params(self) -> CompensatorParams:
        """The paper's compensator of this loop, with what it believes (:meth:`beliefs`)."""
        believed = self.beliefs()
        return CompensatorParams(
            kind=self.compensator,
            lead_time_s=believed["lead_time_s"],
            stiffness_n_per_m=believed["compensator_stiffness_n_per_m"],
            damping_n_s_per_m=believed["compensator_damping_n_s_per_m"],
            force_deadband_n=self.force_deadband_n,
            clamp_nonnegative=self.clamp_nonnegative,
            contact_gate=self.contact_gate,
        )

    def initial_conditions(self) -> dict[str, float]:
        """Initial spacecraft and table states."""
        x0 = -self.initial_gap_m
        v0 = self.initial_velocity_m_per_s
        if self.table_initial_state == "given":
            pa, va = self.table_initial_position_m, self.table_initial_velocity_m_per_s
        elif self.table_initial_state == "rest":
            pa, va = x0, 0.0
        elif self.table_initial_state == "command":
            pa, va = x0, v0
        else:
            pa, va = x0 - self.plant.table.ramp_lag_s * v0, v0
        return {"p_des_m": x0, "v_des_m_per_s": v0, "p_act_m": pa, "v_act_m_per_s": va}
