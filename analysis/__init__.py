"""Linear models and stability margins of the hybrid loop, from the Drake diagram.

- :mod:`analysis.linearize`: continuous in-contact loop (Pade delay) by Drake's
  ``Linearize``, whole diagram or block-wise (:class:`ContactLoopLinearizer`);
- :mod:`analysis.exact_delay`: the same loop with the exact delay ``e^{-sT}``;
- :mod:`analysis.sampled`: sampled-data model of a rig computer (ZOH, ``z^-M``);
- :mod:`analysis.margins`: contact pole, predicted CoR, phase margin, effective
  delay, critical sensor delay and table frequency;
- :mod:`analysis.sweep`: all of it over a (delay, table frequency) grid;
- :mod:`analysis.validation`: predictions against the nonlinear simulation;
- :mod:`analysis.report`: heatmaps, curves, Bode plot, Markdown summary.
"""

from analysis.exact_delay import ExactDelayMargins, exact_contact_root, exact_margins
from analysis.linearize import (
    ContactLoopLinearizer,
    LinearizationError,
    LinearLoop,
    add_contact_loop,
    linearize_contact_loop,
)
from analysis.margins import (
    LoopMargins,
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    loop_margins,
)
from analysis.sampled import SampledLoopLinearizer
from analysis.sweep import CompensatorSweep, SweepResult, sweep_margins
from analysis.validation import ValidationPoint, validate_point, validate_sweep

__all__ = [
    "CompensatorSweep",
    "ContactLoopLinearizer",
    "ExactDelayMargins",
    "LinearLoop",
    "LinearizationError",
    "LoopMargins",
    "SampledLoopLinearizer",
    "SweepResult",
    "ValidationPoint",
    "add_contact_loop",
    "critical_sensor_delay",
    "critical_table_frequency",
    "exact_contact_root",
    "exact_margins",
    "growth_of",
    "linearize_contact_loop",
    "loop_margins",
    "sweep_margins",
    "validate_point",
    "validate_sweep",
]
