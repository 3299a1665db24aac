"""hybridtable: delay compensation for hybrid-simulation motion tables, on Drake.

The 1-D hybrid loop of the seed paper (spacecraft model, force-sensor delay,
compensator, table response, contact) as a Drake systems diagram, its metrics,
and the command-line tool ``hybridtable``.
"""

from hybridtable._lazy import lazy_exports

# Each name is imported from its module when first used, so that importing one
# module of the package (the command line, a plug-in, a worker) does not load
# Drake and the whole loop.
__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "compensators.paper": ("COMPENSATORS", "Compensator", "CompensatorParams"),
        "errors": ("ParameterError", "SimulationError"),
        "loop.builder": ("HybridLoop", "add_hybrid_loop", "build_hybrid_loop"),
        "loop.metrics": ("ContactMetrics", "contact_metrics"),
        "loop.params": (
            "Approach",
            "CompensatorConfig",
            "HybridLoopParams",
            "Plant",
            "RigComputer",
        ),
        "loop.simulation": ("SimulationResult", "collect_result", "run_loop", "simulate"),
        "systems.contact": ("ContactParams", "UnilateralSpringContact"),
        "systems.sensor": ("ForceSensorDelay", "SensorParams"),
        "systems.spacecraft": ("Spacecraft", "SpacecraftParams"),
        "systems.table": ("SecondOrderTable", "TableParams"),
    },
)
