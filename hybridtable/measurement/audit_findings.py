"""What an audit of the rig computer reports: findings, per-run estimates, the audit.

:mod:`hybridtable.measurement.audit` solves a record for the values its computer
used; this module holds what it finds (:class:`Finding`: a JSON value and the
value used, with its standard error), the per-run estimates
(:class:`ComputerEstimate`) and the :class:`Audit` of a set of runs, which
turns the findings into the changes that make a model's computer do the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from hybridtable.laws.spacecraft import DEFAULT_INTEGRATOR, INTEGRATORS

__all__ = [
    "RELATIVE_TOLERANCE",
    "SIGNIFICANCE",
    "FINDING_EFFECTS",
    "differs",
    "UNITS",
    "Finding",
    "ComputerEstimate",
    "Audit",
]


#: Smallest relative difference between a value the computer used and its
#: JSON value that is reported (a JSON rounded to 4 significant digits passes).
RELATIVE_TOLERANCE = 1e-4

#: Standard errors an estimate must differ by to be reported.
SIGNIFICANCE = 5.0


def differs(used: float, se: float, expected: float, scale: float) -> bool:
    """A value the computer used is a finding: more than :data:`SIGNIFICANCE`
    standard errors ``se`` and :data:`RELATIVE_TOLERANCE` of ``scale`` off
    the JSON's ``expected``."""
    d = abs(used - expected)
    return math.isfinite(used) and d > SIGNIFICANCE * se and d > RELATIVE_TOLERANCE * abs(scale)


#: The name a finding takes in a diagnosis verdict, by the JSON key it concerns.
FINDING_EFFECTS: dict[str, str] = {
    "spacecraft_mass_kg": "mass_error",
    "lead_time_s": "lead_time_error",
    "contact_stiffness_n_per_m": "compensator_stiffness_error",
    "force_deadband_n": "deadband_error",
    "sample_rate_hz": "sample_rate_error",
    "initial_gap_m": "initial_state_error",
    "initial_velocity_m_per_s": "initial_state_error",
    "compensation_gain": "compensation_law_error",
    "compensation_offset_n": "compensation_law_error",
    "compensation_law": "compensation_law_error",
    "clamp": "compensation_law_error",
    "spacecraft_model": "spacecraft_model_error",
    "integrator": "integrator_error",
}

#: Units of the values a finding reports.
UNITS: dict[str, str] = {
    "spacecraft_mass_kg": "kg",
    "lead_time_s": "s",
    "contact_stiffness_n_per_m": "N/m",
    "force_deadband_n": "N",
    "sample_rate_hz": "Hz",
    "initial_gap_m": "m",
    "initial_velocity_m_per_s": "m/s",
    "compensation_gain": "1",
    "compensation_offset_n": "N",
    "compensation_law": "N",
    "clamp": "N",
    "spacecraft_model": "m/s",
    "integrator": "1",
}


@dataclass(frozen=True)
class Finding:
    """A value the rig's computer used that its JSON does not say.

    Attributes
    ----------
    key : str
        The JSON key (``"lead_time_s"``) or, for what the JSON has no key for,
        a name of the arithmetic (``"compensation_gain"``, ``"clamp"``).
    json_value, used_value : float
        What the JSON implies and what the computer did, in ``unit``.
    uncertainty : float
        Standard error of ``used_value`` (``unit``).
    runs : tuple of str
        Runs showing it.
    text : str
        One plain sentence.
    """

    key: str
    json_value: float
    used_value: float
    uncertainty: float
    runs: tuple[str, ...]
    text: str

    def __post_init__(self) -> None:
        for name in ("json_value", "used_value", "uncertainty"):
            object.__setattr__(self, name, float(getattr(self, name)))

    @property
    def effect(self) -> str:
        """The finding's name in a diagnosis verdict (``"mass_error"``)."""
        return FINDING_EFFECTS[self.key]

    @property
    def unit(self) -> str:
        return UNITS[self.key]

    @property
    def relative_error(self) -> float:
        """``used / json - 1`` (NaN if the JSON value is 0)."""
        if self.json_value == 0.0 or not math.isfinite(self.json_value):
            return math.nan
        return self.used_value / self.json_value - 1.0

    def to_json(self) -> dict:
        return {
            "key": self.key,
            "effect": self.effect,
            "json": self.json_value,
            "used": self.used_value,
            "uncertainty": self.uncertainty,
            "relative_error": self.relative_error,
            "unit": self.unit,
            "runs": list(self.runs),
            "text": self.text,
        }


@dataclass(frozen=True)
class ComputerEstimate:
    """What one run's computer used, solved from its record (SI units; NaN
    where the record cannot tell, e.g. a mass without a contact force).

    ``*_se`` are standard errors; ``deadband_n`` is the interval
    ``[lower, upper)`` the deadband lies in.
    """

    run_id: str
    time_step_s: float
    time_step_se: float
    #: The rule the computer stepped its model by (``"other"``: none of the
    #: model's), and the weight ``theta`` of the new velocity in its position step.
    integrator: str
    position_weight: float
    position_weight_se: float
    initial_gap_m: float
    initial_velocity_m_per_s: float
    mass_kg: float
    mass_se: float
    lead_time_s: float
    lead_time_se: float
    stiffness_n_per_m: float
    stiffness_se: float
    gain: float
    gain_se: float
    offset_n: float
    offset_se: float
    compensation_residual_n: float
    deadband_n: tuple[float, float]
    force_ticks: int
    free_velocity_change_m_per_s: float
    negative_force_ticks: int
    #: With a residual above the CSV's precision and noisy readings: the stated
    #: law's misfit in noise levels of the logged readings over means of ticks (at
    #: most :data:`~hybridtable.measurement.audit_fit.NOISE_LEVELS`: noise the
    #: computer did not see, and the compensation's constants are not solved,
    #: NaN); NaN otherwise.
    compensation_noise_levels: float = math.nan

    def to_json(self) -> dict:
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["deadband_n"] = list(self.deadband_n)
        return out


@dataclass
class Audit:
    """The audit of a set of runs: per-run estimates and the findings."""

    estimates: list[ComputerEstimate]
    findings: list[Finding] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True if the computers did what their JSON says."""
        return not self.findings

    @property
    def integrator(self) -> str:
        """The rule the computers stepped their model by: the format's unless
        a run shows another (the first such run's; ``"other"``: none of the
        model's)."""
        rules = [e.integrator for e in self.estimates if e.integrator != DEFAULT_INTEGRATOR]
        return rules[0] if rules else DEFAULT_INTEGRATOR

    @property
    def effects(self) -> list[str]:
        """The findings' verdict names, each once, in order."""
        out: list[str] = []
        for f in self.findings:
            if f.effect not in out:
                out.append(f.effect)
        return out

    def computer_changes(self, run_id: str) -> dict[str, float | str]:
        """The changes of :class:`~hybridtable.loop.params.HybridLoopParams`
        that make the model's computer do what run ``run_id``'s did (mass, lead
        time, MDC stiffness, deadband, compensator kind and integration rule). A gain, an offset
        or a law the format lacks has no such change."""
        out: dict[str, float | str] = {}
        for f in self.findings:
            if run_id not in f.runs:
                continue
            if f.key == "spacecraft_mass_kg":
                out["spacecraft_mass_kg"] = f.used_value
            elif f.key == "lead_time_s":
                out["lead_time_s"] = f.used_value
            elif f.key == "contact_stiffness_n_per_m":
                out["compensator_stiffness_n_per_m"] = f.used_value
            elif f.key == "force_deadband_n":
                out["force_deadband_n"] = f.used_value
            elif f.key == "integrator":
                rule = next(e.integrator for e in self.estimates if e.run_id == run_id)
                if rule in INTEGRATORS:
                    out["computer_integrator"] = rule
        if "lead_time_s" in out or "compensator_stiffness_n_per_m" in out:
            est = next(e for e in self.estimates if e.run_id == run_id)
            lead = _present(est.lead_time_s, est.lead_time_se, est.time_step_s)
            stiff = _present(est.stiffness_n_per_m, est.stiffness_se, 1.0)
            out["compensator"] = {
                (True, True): "SDMDC",
                (True, False): "SDC",
                (False, True): "MDC",
                (False, False): "none",
            }[(lead, stiff)]
            # what the computer has none of is not a number of it (an MDC
            # stiffness of 0 is no stiffness the loop takes)
            if lead:
                out.setdefault("lead_time_s", max(est.lead_time_s, 0.0))
            else:
                out.pop("lead_time_s", None)
            if stiff:
                out.setdefault("compensator_stiffness_n_per_m", max(est.stiffness_n_per_m, 0.0))
            else:
                out.pop("compensator_stiffness_n_per_m", None)
        return out

    def to_json(self) -> dict:
        return {
            "ok": self.ok,
            "integrator": self.integrator,
            "findings": [f.to_json() for f in self.findings],
            "runs": [e.to_json() for e in self.estimates],
            "relative_tolerance": RELATIVE_TOLERANCE,
            "significance_standard_errors": SIGNIFICANCE,
            "notes": list(self.notes),
        }


def _present(value: float, se: float, scale: float) -> bool:
    return (
        math.isfinite(value)
        and abs(value) > SIGNIFICANCE * se
        and abs(value) > RELATIVE_TOLERANCE * scale
    )
