"""What the audits of a six-axis rig computer report: a finding (a quantity
it used that is not its JSON's) and the audit of its compensation law, with
their sentences and JSON (:mod:`~hybridtable.six_dof.audit_law6` solves it;
:mod:`~hybridtable.six_dof.audit6`, the spacecraft, reports its findings the
same way).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from hybridtable.measurement.audit_findings import RELATIVE_TOLERANCE, SIGNIFICANCE

__all__ = ["COMPENSATION_RESIDUAL", "WRENCH_COMPONENTS", "AuditFinding6", "CompensationAudit6"]

#: The largest RMS residual of the law, over the RMS of the compensated wrench,
#: of a computer that compensates by the format's law (the 1-D audit's 1e-4 of
#: the force's scale; a CSV at six digits leaves about 1e-5).
COMPENSATION_RESIDUAL = 1e-4

#: The wrench's components, in the loop's order (moment first).
WRENCH_COMPONENTS = ("mx", "my", "mz", "fx", "fy", "fz")


@dataclass(frozen=True)
class AuditFinding6:
    """A quantity the six-axis rig computer used that is not the JSON's."""

    effect: str
    values: dict[str, float]
    std: dict[str, float | None]
    sentence: str

    def to_dict(self) -> dict:
        return {
            "effect": self.effect,
            "values": self.values,
            "std": self.std,
            "sentence": self.sentence,
        }


@dataclass(frozen=True)
class CompensationAudit6:
    """What :func:`audit_compensation6` solved for the runs of one compensator
    (``None`` where it did not solve; ``not_audited`` says why)."""

    run_ids: list[str]
    compensator: str
    ticks: int = 0
    stated_lead_s: float = 0.0
    lead_s: float | None = None
    lead_std_s: float | None = None
    stated_factor: float = 0.0
    factor: float | None = None
    factor_std: float | None = None
    gain: float | None = None
    gain_std: float | None = None
    offsets: tuple[float, ...] = ()
    offsets_std: tuple[float, ...] = ()
    relative_residual: float = math.nan
    deadband_n: tuple[float, float] = (-math.inf, math.inf)
    #: With readings the computer did not see (``block`` > 1): the law's misfit
    #: over block means in noise levels (largest component), NaN otherwise.
    noise_levels: float = math.nan
    #: 1: solved tick by tick; more: over means of that many ticks.
    block: int = 1
    #: Over means of ticks: the smallest change of the gain, the lead (s) and
    #: the MDC term's factor that the test of the JSON's law would see.
    detectable: tuple[float, ...] = ()
    not_audited: str = ""
    findings: list[AuditFinding6] = field(default_factory=list)

    def sentence(self) -> str:
        if self.not_audited:
            return f"the rig computer's compensation law is not audited: {self.not_audited}"
        if self.block > 1 and not self.findings:
            return (
                f"the rig computer's compensation is the JSON's {self.compensator} to the noise "
                f"of the logged readings, which it did not see (over means of {self.block} "
                f"ticks, {self.noise_levels:.2g} noise levels; {self.ticks} ticks): its "
                f"constants are not solved from them{self._detectable()}"
            )
        if not self.findings and not all(
            math.isfinite(x) for x in (self.lead_std_s, self.gain_std, self.factor_std or 0.0)
        ):
            return (
                f"the rig computer's compensation: the record ({self.ticks} ticks) does not "
                "determine its lead, gain and MDC term apart"
            )
        if not self.findings:
            return (
                f"the rig computer's compensation is the JSON's {self.compensator} (lead, MDC "
                f"term, gain, offsets, dead band; {self.ticks} ticks, residual "
                f"{self.relative_residual:.2g} of the signal)"
            )
        return "the rig computer's compensation: " + "; ".join(f.sentence for f in self.findings)

    def _detectable(self) -> str:
        """What the test of the JSON's law would not see, in words."""
        if len(self.detectable) < 2 or not math.isfinite(self.detectable[1]):
            return ""
        words = f"; a lead off by less than {self.detectable[1] * 1e3:.2g} ms"
        if len(self.detectable) > 2 and math.isfinite(self.detectable[2]):
            words += f" or an MDC term off by less than {self.detectable[2]:.2g} of it"
        return words + " would not show"

    def to_dict(self) -> dict:
        return {
            "runs": self.run_ids,
            "compensator": self.compensator,
            "ticks": self.ticks,
            "sentence": self.sentence(),
            "not_audited": self.not_audited or None,
            "stated": {"lead_time_s": self.stated_lead_s, "mdc_factor": self.stated_factor},
            "solved": {
                "lead_time_s": self.lead_s,
                "mdc_factor": self.factor,
                "gain": self.gain,
                "offsets": dict(zip(WRENCH_COMPONENTS, self.offsets, strict=False)),
                "deadband_n": [_finite(x) for x in self.deadband_n],
            },
            "std": {
                "lead_time_s": self.lead_std_s,
                "mdc_factor": self.factor_std,
                "gain": self.gain_std,
                "offsets": dict(zip(WRENCH_COMPONENTS, self.offsets_std, strict=False)),
            },
            "relative_residual": _finite(self.relative_residual),
            "block_ticks": self.block,
            "block_noise_levels": _finite(self.noise_levels),
            "undetectable_below": dict(
                zip(
                    ("gain", "lead_time_s", "mdc_factor"),
                    map(_finite, self.detectable),
                    strict=False,
                )
            ),
            "findings": [f.to_dict() for f in self.findings],
            "thresholds": {
                "sigmas": SIGNIFICANCE,
                "relative": RELATIVE_TOLERANCE,
                "law_residual": COMPENSATION_RESIDUAL,
            },
        }


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
