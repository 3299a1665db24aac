"""What a campaign can measure in each run: the contact's metrics from a
simulation, and the margins of the linearized loop.

Simulation metrics (:class:`~hybridtable.loop.metrics.ContactMetrics`, and for
a 6-DoF campaign :class:`~hybridtable.six_dof.metrics.DockingMetrics`) need one
run through the contact; margin metrics
(:mod:`hybridtable.analysis.margins`) need the linear model only, so a spec
asking for margins alone simulates nothing. Each metric says which loops
(:data:`LOOPS`) measure it: ``energy_ratio`` or ``peak_force_n`` mean the same
in both, ``cor`` is the 1-D loop's and ``cor_normal`` the 6-DoF loop's.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Metric", "METRICS", "DEFAULT_METRICS", "SIMULATION", "MARGINS", "LOOPS"]
__all__ += ["DEFAULT_DOCKING_METRICS", "metrics_of"]

SIMULATION = "simulation"
MARGINS = "margins"

#: The loops a campaign runs: the 1-D loop, the 6-DoF docking loop.
LOOPS: tuple[str, ...] = ("1d", "six_dof")
_BOTH = LOOPS
_SIX = ("six_dof",)


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
    loops : tuple of str
        The loops that measure it (:data:`LOOPS`).
    finite : bool
        Every run that is ``ok`` gives a finite number (a simulation metric).
    """

    name: str
    unit: str
    source: str
    doc: str
    kind: str = "number"
    loops: tuple[str, ...] = ("1d",)
    finite: bool = True


_ALL = (
    Metric("cor", "1", SIMULATION, "coefficient of restitution |v_out| / |v_in|"),
    Metric(
        "energy_ratio",
        "1",
        SIMULATION,
        "kinetic energy after / before the contact (1-D: CoR^2; 6-DoF: with rotation)",
        loops=_BOTH,
    ),
    Metric(
        "energy_gain_j",
        "J",
        SIMULATION,
        "kinetic energy after minus before the contact",
        loops=_BOTH,
    ),
    Metric(
        "energy_created",
        "1",
        SIMULATION,
        "largest excess of the kinetic energy over its value before the contact, relative",
    ),
    Metric("peak_force_n", "N", SIMULATION, "largest actual contact force", loops=_BOTH),
    Metric(
        "peak_compensated_force_n", "N", SIMULATION, "largest force fed to the model", loops=_BOTH
    ),
    Metric("contact_duration_s", "s", SIMULATION, "time the contact force was on", loops=_BOTH),
    Metric(
        "v_in_m_per_s",
        "m/s",
        SIMULATION,
        "velocity before the contact (6-DoF: the port's, along the docking axis)",
        loops=_BOTH,
    ),
    Metric(
        "v_out_m_per_s",
        "m/s",
        SIMULATION,
        "velocity after the contact (6-DoF: the port's, along the docking axis)",
        loops=_BOTH,
    ),
    Metric(
        "cor_normal",
        "1",
        SIMULATION,
        "|v_out| / |v_in| of the docking port along the docking axis",
        loops=_SIX,
    ),
    Metric(
        "energy_excess",
        "1",
        SIMULATION,
        "energy ratio minus the ideal rig's (no delay, ideal table; a second run): > 0 the rig "
        "created energy, < 0 it took energy out",
        loops=_SIX,
    ),
    Metric(
        "rotational_energy_j", "J", SIMULATION, "rotational energy after the contact", loops=_SIX
    ),
    Metric(
        "peak_moment_n_m",
        "N m",
        SIMULATION,
        "largest moment of the contact about the port",
        loops=_SIX,
    ),
    Metric(
        "lateral_velocity_m_per_s",
        "m/s",
        SIMULATION,
        "the port's speed across the docking axis after the contact",
        loops=_SIX,
    ),
    Metric(
        "lateral_drift_m",
        "m",
        SIMULATION,
        "how far the port slid across the docking axis during the contact",
        loops=_SIX,
    ),
    Metric(
        "captured",
        "",
        SIMULATION,
        "the contact held the spacecraft, its port at rest against the target",
        "bool",
        loops=_SIX,
    ),
    Metric(
        "identified_stiffness_n_per_m",
        "N/m",
        SIMULATION,
        "the contact stiffness an online identifier ended with (NaN: none ran)",
        loops=_SIX,
        finite=False,
    ),
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

#: What a 6-DoF spec measures when it does not say.
DEFAULT_DOCKING_METRICS: tuple[str, ...] = (
    "cor_normal",
    "energy_ratio",
    "peak_force_n",
    "peak_moment_n_m",
    "lateral_velocity_m_per_s",
    "captured",
)


def metrics_of(loop: str) -> dict[str, Metric]:
    """The metrics a ``loop`` (:data:`LOOPS`) measures, by name."""
    return {name: m for name, m in METRICS.items() if loop in m.loops}
