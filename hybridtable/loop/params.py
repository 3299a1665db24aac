"""Parameters of one hybrid-loop run (:class:`HybridLoopParams`), SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from hybridtable._validation import (
    check_choice,
    check_nonnegative,
    check_positive,
    check_positive_or_inf,
)
from hybridtable.compensators.paper import CONTACT_GATES, CompensatorParams
from hybridtable.compensators.registry import compensator_names
from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m, mass_for_contact_frequency_kg
from hybridtable.limits import check_plausible, limit_of, limit_words
from hybridtable.systems.contact import ContactParams
from hybridtable.systems.sensor import SensorParams
from hybridtable.systems.spacecraft import SpacecraftParams
from hybridtable.systems.table import TableParams

__all__ = [
    "TABLE_INITIAL_STATES",
    "BELIEFS",
    "HybridLoopParams",
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


def believed(params: Any, belief: str) -> float:
    """What the compensator believes for ``belief`` (a key of :data:`BELIEFS`)
    in any parameter set with both fields (the 1-D and 6-DoF loops', a CoR
    table's conditions): the stated value, or the true one it stands for."""
    value = getattr(params, belief)
    return getattr(params, BELIEFS[belief]) if value is None else value


#: The fields checked against their plausible range (:data:`hybridtable.limits.LIMITS`).
_PLAUSIBLE_FIELDS: tuple[str, ...] = (
    "spacecraft_mass_kg",
    "contact_stiffness_n_per_m",
    "contact_damping_n_s_per_m",
    "sensor_delay_s",
    "table_response_hz",
    "table_damping_ratio",
    "lead_time_s",
    "compensator_stiffness_n_per_m",
    "compensator_damping_n_s_per_m",
    "force_deadband_n",
    "initial_velocity_m_per_s",
    "initial_gap_m",
    "sample_rate_hz",
    "time_step_s",
)


@dataclass(frozen=True)
class HybridLoopParams:
    """Every parameter of one hybrid-loop run, SI units.

    Parameters
    ----------
    spacecraft_mass_kg : float
        Spacecraft model mass m, > 0.
    contact_stiffness_n_per_m : float
        True contact stiffness k_con, > 0.
    contact_damping_n_s_per_m : float
        True contact damping, >= 0.
    sensor_delay_s : float
        Force-sensor delay T_fms, >= 0.
    table_response_hz : float
        Table response frequency f_resp, > 0, ``math.inf`` for an ideal table.
    table_damping_ratio : float
        Table damping ratio, >= 0.
    compensator : str
        A registered compensator (:func:`hybridtable.compensators.registry.compensator_names`):
        the paper's "none", "SDC", "MDC", "SDMDC", or a plug-in.
    lead_time_s : float or None
        SDC lead time; ``None`` means ``sensor_delay_s`` (the paper's choice).
    compensator_stiffness_n_per_m, compensator_damping_n_s_per_m : float or None
        What the MDC believes; ``None`` means the true contact values
        (:data:`BELIEFS`, resolved by :meth:`beliefs`).
    force_deadband_n : float
        Measured forces at or below this are "no contact".
    clamp_nonnegative : bool
        Clamp the compensated force at zero.
    contact_gate : {"measured_force", "table_position"}
        How the compensator tells contact (:mod:`hybridtable.compensators.paper`).
    initial_velocity_m_per_s : float
        Approach velocity of the spacecraft model, > 0.
    initial_gap_m : float
        Gap between the devices at t = 0, >= 0.
    table_initial_state : {"tracking", "command", "rest"}
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
    sample_rate_hz : float or None
        ``None``: continuous rig computer. Otherwise the rate of the rig's
        computer loop.
    time_step_s : float
        Continuous mode: the largest integration step and delay-line period.
    passivity : bool
        Guard the compensator with the time-domain passivity observer and
        controller (:mod:`hybridtable.compensators.passivity`).
    """

    spacecraft_mass_kg: float
    contact_stiffness_n_per_m: float
    contact_damping_n_s_per_m: float = 0.0
    sensor_delay_s: float = 0.0
    table_response_hz: float = math.inf
    table_damping_ratio: float = 0.8
    compensator: str = "none"
    lead_time_s: float | None = None
    compensator_stiffness_n_per_m: float | None = None
    compensator_damping_n_s_per_m: float | None = None
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False
    contact_gate: str = "measured_force"
    initial_velocity_m_per_s: float = 0.1
    initial_gap_m: float = 0.001
    table_initial_state: str = "tracking"
    table_initial_position_m: float | None = None
    table_initial_velocity_m_per_s: float | None = None
    sample_rate_hz: float | None = None
    time_step_s: float | None = None
    passivity: bool = False

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "spacecraft_mass_kg", check_positive("spacecraft_mass_kg", self.spacecraft_mass_kg))
        for name in ("contact_stiffness_n_per_m", "initial_velocity_m_per_s"):
            s(self, name, check_positive(name, getattr(self, name)))
        if self.time_step_s is not None:
            s(self, "time_step_s", check_positive("time_step_s", self.time_step_s))
        for name in (
            "contact_damping_n_s_per_m",
            "sensor_delay_s",
            "table_damping_ratio",
            "force_deadband_n",
            "initial_gap_m",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        s(
            self,
            "table_response_hz",
            check_positive_or_inf("table_response_hz", self.table_response_hz),
        )
        check_choice("compensator", self.compensator, compensator_names())
        check_choice("contact_gate", self.contact_gate, CONTACT_GATES)
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
        for name in (
            "lead_time_s",
            "compensator_stiffness_n_per_m",
            "compensator_damping_n_s_per_m",
        ):
            if getattr(self, name) is not None:
                s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.sample_rate_hz is not None:
            s(self, "sample_rate_hz", check_positive("sample_rate_hz", self.sample_rate_hz))
        # Every number inside its plausible range (hybridtable.limits), so that
        # no absurd value reaches a simulation that would run forever.
        for name in _PLAUSIBLE_FIELDS:
            if getattr(self, name) is not None:
                check_plausible(name, getattr(self, name))
        if self.sample_rate_hz is not None:
            # Raises a clear error when the delay is not a whole number of ticks.
            from hybridtable.systems.sensor import delay_samples

            delay_samples(self.sensor_delay_s, self.sample_period_s)

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
        return None if self.sample_rate_hz is None else 1.0 / self.sample_rate_hz

    @property
    def effective_delay_s(self) -> float:
        """tau_eff = T_fms + 2 zeta / omega_resp, the loop's low-frequency delay."""
        return self.sensor_delay_s + self.table().ramp_lag_s

    def with_(self, **changes) -> HybridLoopParams:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

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

    def spacecraft(self) -> SpacecraftParams:
        return SpacecraftParams(mass_kg=self.spacecraft_mass_kg)

    def table(self) -> TableParams:
        return TableParams(self.table_response_hz, self.table_damping_ratio)

    def contact(self) -> ContactParams:
        return ContactParams(self.contact_stiffness_n_per_m, self.contact_damping_n_s_per_m)

    def sensor(self) -> SensorParams:
        return SensorParams(self.sensor_delay_s)

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
            pa, va = x0 - self.table().ramp_lag_s * v0, v0
        return {"p_des_m": x0, "v_des_m_per_s": v0, "p_act_m": pa, "v_act_m_per_s": va}
