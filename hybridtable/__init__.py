"""hybridtable: delay compensation for hybrid-simulation motion tables, on Drake.

The 1-D hybrid loop of the seed paper (spacecraft model, force-sensor delay,
compensator, table response, contact) as a Drake systems diagram, its metrics,
and the command-line tool ``hybridtable``.
"""

from hybridtable._validation import ParameterError
from hybridtable.compensator import COMPENSATORS, Compensator, CompensatorParams
from hybridtable.contact import ContactParams, UnilateralSpringContact
from hybridtable.loop import HybridLoop, HybridLoopParams, add_hybrid_loop, build_hybrid_loop
from hybridtable.metrics import ContactMetrics, contact_metrics
from hybridtable.sensor import ForceSensorDelay, SensorParams
from hybridtable.simulation import SimulationError, SimulationResult, run_loop, simulate
from hybridtable.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.table import SecondOrderTable, TableParams

__all__ = [
    "COMPENSATORS",
    "Compensator",
    "CompensatorParams",
    "ContactMetrics",
    "ContactParams",
    "ForceSensorDelay",
    "HybridLoop",
    "HybridLoopParams",
    "ParameterError",
    "SecondOrderTable",
    "SensorParams",
    "SimulationError",
    "SimulationResult",
    "Spacecraft",
    "SpacecraftParams",
    "TableParams",
    "UnilateralSpringContact",
    "add_hybrid_loop",
    "build_hybrid_loop",
    "contact_metrics",
    "run_loop",
    "simulate",
]
