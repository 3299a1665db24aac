"""Linear models and stability margins of the hybrid loop, from the Drake diagram.

- :mod:`hybridtable.analysis.linearize`: continuous in-contact loop (Pade delay) by Drake's
  ``Linearize`` of the whole diagram;
- :mod:`hybridtable.analysis.blockwise`: the same, block-wise, assembled per point
  (:class:`ContactLoopLinearizer`);
- :mod:`hybridtable.analysis.exact_delay`: the same loop with the exact delay ``e^{-sT}``;
- :mod:`hybridtable.analysis.sampled`: sampled-data model of a rig computer (ZOH, ``z^-M``);
- :mod:`hybridtable.analysis.margins`: contact pole, predicted CoR, phase margin, effective
  delay, critical sensor delay and table frequency;
- :mod:`hybridtable.analysis.critical`: the one search for the delay at which a figure of a
  loop (1-D or 6-DoF) reaches its limit;
- :mod:`hybridtable.analysis.robustness`: gain, phase and delay margins (python-control's
  ``stability_margins``), the delay a CoR limit allows;
- :mod:`hybridtable.analysis.linear_export`: the linear loop as a file python-control loads;
- :mod:`hybridtable.analysis.sweep`: all of it over a (delay, table frequency) grid;
- :mod:`hybridtable.analysis.validation`: predictions against the nonlinear simulation;
- :mod:`hybridtable.reports.margin_plots` and :mod:`hybridtable.reports.margins`: heatmaps,
  curves, Bode plot; Markdown summary.
"""

from hybridtable._lazy import lazy_exports
from hybridtable.errors import LinearizationError as LinearizationError

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "blockwise": ("ContactLoopLinearizer",),
        "exact_delay": (
            "ExactDelayMargins",
            "exact_contact_root",
            "exact_margins",
        ),
        "linearize": (
            "LinearLoop",
            "add_contact_loop",
            "linearize_contact_loop",
        ),
        "margins": (
            "LoopMargins",
            "critical_sensor_delay",
            "critical_table_frequency",
            "growth_of",
            "loop_margins",
        ),
        "robustness": (
            "GainDelayMargins",
            "cor_limited_delay",
            "gain_delay_margins",
        ),
        "linear_export": (
            "linear_model_document",
            "load_linear_model",
            "save_linear_model",
        ),
        "sampled": ("SampledLoopLinearizer",),
        "sweep": (
            "CompensatorSweep",
            "SweepResult",
            "margins_from_rows",
        ),
        "validation": (
            "ValidationPoint",
            "validate_point",
            "validate_sweep",
        ),
    },
)
__all__ = sorted([*__all__, "LinearizationError"])
