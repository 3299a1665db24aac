"""What a campaign can measure in each run: the contact's metrics from a
simulation, and the margins of the linearized loop.

Simulation metrics (:class:`~hybridtable.loop.metrics.ContactMetrics`) need one
run through the contact; margin metrics
(:mod:`hybridtable.analysis.margins`) need the linear model only, so a spec
asking for margins alone simulates nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Metric", "METRICS", "DEFAULT_METRICS", "SIMULATION", "MARGINS"]

SIMULATION = "simulation"
MARGINS = "margins"


@dataclass(frozen=True)
class Metric:
    """One column a run can fill.

    Attributes
    ----------
    name : str
    unit : str
        SI unit ("1": dimensionless, "": a flag).
    source : {"simulation", "margins"}
    doc : str
    kind : {"number", "bool"}
    """

    name: str
    unit: str
    source: str
    doc: str
    kind: str = "number"


_ALL = (
    Metric("cor", "1", SIMULATION, "coefficient of restitution |v_out| / |v_in|"),
    Metric("energy_ratio", "1", SIMULATION, "kinetic energy after / before the contact (CoR^2)"),
    Metric("energy_gain_j", "J", SIMULATION, "kinetic energy after minus before the contact"),
    Metric(
        "energy_created",
        "1",
        SIMULATION,
        "largest excess of the kinetic energy over its value before the contact, relative",
    ),
    Metric("peak_force_n", "N", SIMULATION, "largest actual contact force"),
    Metric("peak_compensated_force_n", "N", SIMULATION, "largest force fed to the model"),
    Metric("contact_duration_s", "s", SIMULATION, "time the contact force was on"),
    Metric("v_in_m_per_s", "m/s", SIMULATION, "spacecraft velocity before the contact"),
    Metric("v_out_m_per_s", "m/s", SIMULATION, "spacecraft velocity after the contact"),
    Metric("stable", "", MARGINS, "the linearized loop in contact is stable", "bool"),
    Metric("predicted_cor", "1", MARGINS, "CoR from the contact pole of the linear model"),
    Metric("phase_margin_deg", "deg", MARGINS, "phase margin at the contact crossover"),
    Metric("damping_ratio", "1", MARGINS, "damping ratio of the contact pole"),
    Metric("growth_rate_per_s", "1/s", MARGINS, "largest real part of the loop's poles"),
    Metric(
        "energy_growth_per_contact",
        "1",
        MARGINS,
        "energy ratio over half a period of the contact pole (CoR^2 - 1)",
    ),
    Metric("effective_delay_s", "s", MARGINS, "delay the phase margin amounts to"),
    Metric("crossover_rad_per_s", "rad/s", MARGINS, "gain crossover frequency"),
    Metric(
        "critical_sensor_delay_s",
        "s",
        MARGINS,
        "smallest sensor delay at which the loop is unstable (inf: none)",
    ),
)

#: Every metric, by name.
METRICS: dict[str, Metric] = {m.name: m for m in _ALL}

#: What a spec measures when it does not say.
DEFAULT_METRICS: tuple[str, ...] = (
    "cor",
    "energy_gain_j",
    "peak_force_n",
    "contact_duration_s",
)
