"""Simulation campaigns built from the loop: the paper's operating points and
the compensator sweep.

- :mod:`~hybridtable.studies.paper`: the paper's Tables 1 and 2 as loop parameters;
- :mod:`~hybridtable.studies.compensator_sweep`: every compensator over the
  Table 2 grid under stiffness mismatch, noise and damping.
"""

from hybridtable.studies.compensator_sweep import SweepResult, SweepSettings, run_sweep
from hybridtable.studies.paper import load_tables, paper_params, table1_params, table2_params

__all__ = [
    "SweepResult",
    "SweepSettings",
    "load_tables",
    "paper_params",
    "run_sweep",
    "table1_params",
    "table2_params",
]
