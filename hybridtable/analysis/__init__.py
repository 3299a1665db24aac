"""Linear models and stability margins of the hybrid loop, from the Drake diagram.

- :mod:`hybridtable.analysis.linearize`: continuous in-contact loop (Pade delay) by Drake's
  ``Linearize`` of the whole diagram;
- :mod:`hybridtable.analysis.blockwise`: the same, block-wise, assembled per point
  (:class:`ContactLoopLinearizer`);
- :mod:`hybridtable.analysis.exact_delay`: the same loop with the exact delay ``e^{-sT}``;
- :mod:`hybridtable.analysis.sampled`: sampled-data model of a rig computer (ZOH, ``z^-M``);
- :mod:`hybridtable.analysis.margins`: contact pole, predicted CoR, phase margin, effective
  delay, critical sensor delay and table frequency;
- :mod:`hybridtable.analysis.sweep`: all of it over a (delay, table frequency) grid;
- :mod:`hybridtable.analysis.validation`: predictions against the nonlinear simulation;
- :mod:`hybridtable.reports.margin_plots` and :mod:`hybridtable.reports.margins`: heatmaps,
  curves, Bode plot; Markdown summary.
"""

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.exact_delay import ExactDelayMargins, exact_contact_root, exact_margins
from hybridtable.analysis.linearize import LinearLoop, add_contact_loop, linearize_contact_loop
from hybridtable.analysis.margins import (
    LoopMargins,
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    loop_margins,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.analysis.sweep import CompensatorSweep, SweepResult, sweep_margins
from hybridtable.analysis.validation import ValidationPoint, validate_point, validate_sweep
from hybridtable.errors import LinearizationError

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
