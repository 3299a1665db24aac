"""Simulation campaigns built from the loop: the paper's operating points and
the compensator sweep.

- :mod:`~hybridtable.studies.paper`: the paper's Tables 1 and 2 as loop parameters;
- :mod:`~hybridtable.studies.compensator_sweep`: every compensator over the
  Table 2 grid under stiffness mismatch, noise and damping.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "compensator_sweep": (
            "SweepResult",
            "SweepSettings",
            "sweep_runs",
            "sweep_result",
        ),
        "paper": (
            "load_tables",
            "paper_params",
            "table1_params",
            "table2_params",
        ),
    },
)
