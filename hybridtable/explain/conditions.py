"""The stated conditions of one row of a CoR table: what the lab says its rig was.

A measured CoR table states, per row or once for the whole table, the contact
(stiffness, frequency, approach velocity) and the rig (sensor delay, the SDC's
lead, the table's response, the rig computer's rate). What it does not state
is taken from the seed paper's simulated Table 1 (:data:`PAPER_CONDITIONS`) and
listed as assumed in every explanation.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from functools import lru_cache

from hybridtable._validation import check_nonnegative, check_positive, check_positive_or_inf
from hybridtable.laws.contact import mass_for_contact_frequency_kg
from hybridtable.limits import TABLE1_DEFAULTS
from hybridtable.loop.params import HybridLoopParams, believed

__all__ = ["CONDITION_FIELDS", "PAPER_CONDITIONS", "Conditions"]


@dataclass(frozen=True)
class Conditions:
    """The stated conditions of one measured CoR, SI units.

    Parameters
    ----------
    contact_stiffness_n_per_m : float
        Contact stiffness k_con, N/m, > 0.
    contact_frequency_hz : float
        Contact natural frequency f_con = sqrt(k_con / m) / (2 pi), Hz, > 0; with
        the stiffness it fixes the spacecraft model's mass.
    initial_velocity_m_per_s : float
        Approach velocity, m/s, > 0 (a linear loop's CoR does not depend on it).
    sensor_delay_s : float
        Force-sensor delay T_fms, s, >= 0.
    lead_time_s : float or None
        The SDC's lead T_lead, s, >= 0; ``None``: the sensor delay (the paper's choice).
    table_response_hz : float
        Table response frequency, Hz, > 0 (``inf``: an ideal table).
    table_damping_ratio : float
        Table damping ratio, >= 0.
    sample_rate_hz : float or None
        The rig computer's rate, Hz; ``None``: a continuous rig computer. A
        delay between two of its ticks reads the neighbouring samples mixed.
    """

    contact_stiffness_n_per_m: float = TABLE1_DEFAULTS["contact_stiffness_n_per_m"]
    contact_frequency_hz: float = TABLE1_DEFAULTS["contact_frequency_hz"]
    initial_velocity_m_per_s: float = TABLE1_DEFAULTS["initial_velocity_m_per_s"]
    sensor_delay_s: float = TABLE1_DEFAULTS["sensor_delay_s"]
    lead_time_s: float | None = None
    table_response_hz: float = TABLE1_DEFAULTS["table_response_hz"]
    table_damping_ratio: float = TABLE1_DEFAULTS["table_damping_ratio"]
    sample_rate_hz: float | None = None

    def __post_init__(self) -> None:
        s = object.__setattr__
        for name in (
            "contact_stiffness_n_per_m",
            "contact_frequency_hz",
            "initial_velocity_m_per_s",
        ):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in ("sensor_delay_s", "table_damping_ratio"):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.lead_time_s is not None:
            s(self, "lead_time_s", check_nonnegative("lead_time_s", self.lead_time_s))
        s(
            self,
            "table_response_hz",
            check_positive_or_inf("table_response_hz", self.table_response_hz),
        )
        if self.sample_rate_hz is not None:
            s(self, "sample_rate_hz", check_positive("sample_rate_hz", self.sample_rate_hz))

    @property
    def lead_s(self) -> float:
        """The SDC's lead, s (the sensor delay when not stated)."""
        return believed(self, "lead_time_s")

    @property
    def spacecraft_mass_kg(self) -> float:
        """The spacecraft model's mass that gives the stated frequency, kg."""
        return mass_for_contact_frequency_kg(
            self.contact_stiffness_n_per_m, self.contact_frequency_hz
        )

    @property
    def table_lag_s(self) -> float:
        """The table's lag behind a ramp command, 2 zeta / omega, s (0 for an ideal table)."""
        if math.isinf(self.table_response_hz):
            return 0.0
        return 2.0 * self.table_damping_ratio / (2.0 * math.pi * self.table_response_hz)

    def loop_params(self, compensator: str) -> HybridLoopParams:
        """The hybrid loop the conditions state, for ``compensator`` (built once
        per conditions and compensator: a fit asks for it at every evaluation)."""
        return _loop_params(self, compensator)

    def to_dict(self) -> dict[str, float | None]:
        """The fields, SI units (``lead_time_s`` resolved)."""
        out = asdict(self)
        out["lead_time_s"] = self.lead_s
        return out


@lru_cache(maxsize=4096)
def _loop_params(conditions: Conditions, compensator: str) -> HybridLoopParams:
    return HybridLoopParams(
        spacecraft_mass_kg=conditions.spacecraft_mass_kg,
        contact_stiffness_n_per_m=conditions.contact_stiffness_n_per_m,
        sensor_delay_s=conditions.sensor_delay_s,
        table_response_hz=conditions.table_response_hz,
        table_damping_ratio=conditions.table_damping_ratio,
        compensator=compensator,
        lead_time_s=conditions.lead_s,
        initial_velocity_m_per_s=conditions.initial_velocity_m_per_s,
        sample_rate_hz=conditions.sample_rate_hz,
    )


#: The condition fields a CoR table (or a flag) may state.
CONDITION_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(Conditions))

#: What is assumed when neither the table nor a flag states it: the seed paper's
#: simulated Table 1 (k_con 1e5 N/m, f_con 1 Hz, 0.1 m/s, 25 Hz table with
#: damping ratio 0.8, 5 ms delay, lead = delay, continuous rig computer).
PAPER_CONDITIONS: dict[str, float | None] = {f.name: f.default for f in fields(Conditions)}
