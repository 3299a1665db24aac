"""hybridtable: delay compensation for hybrid-simulation motion tables, on Drake.

The 1-D hybrid loop of the seed paper (spacecraft model, force-sensor delay,
compensator, table response, contact) as a Drake systems diagram, its metrics,
and the command-line tool ``hybridtable``.
"""

from hybridtable.compensators.paper import COMPENSATORS, Compensator, CompensatorParams
from hybridtable.errors import ParameterError, SimulationError
from hybridtable.loop.builder import HybridLoop, add_hybrid_loop, build_hybrid_loop
from hybridtable.loop.metrics import ContactMetrics, contact_metrics
from hybridtable.loop.params import (
    Approach,
    CompensatorConfig,
    HybridLoopParams,
    Plant,
    RigComputer,
)
from hybridtable.loop.simulation import SimulationResult, collect_result, run_loop, simulate
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable, TableParams

__all__ = [
    "Approach",
    "CompensatorConfig",
    "Plant",
    "RigComputer",
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
    "collect_result",
    "contact_metrics",
    "run_loop",
    "simulate",
]
