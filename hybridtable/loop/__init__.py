"""The 1-D hybrid loop of the paper as a Drake diagram, and its simulation.

::

    spacecraft --state--> table --motion--> contact --force--> sensor delay
        ^                   |                                      |
        |                   +--table_motion--+                     |
        +--compensated_force-- compensator <-+---measured_force----+
                               ^--commanded_state-- spacecraft

- :mod:`~hybridtable.loop.params`: :class:`HybridLoopParams`, every parameter of a run,
  one config per component (:class:`Plant`, :class:`RigComputer`, :class:`Approach`);
- :mod:`~hybridtable.loop.scenario`: a scenario file (TOML) of nested sections,
  one per component, shared with the 6-DoF loop;
- :mod:`~hybridtable.loop.builder`: :func:`add_hybrid_loop` wires the systems of
  :mod:`hybridtable.systems` and a compensator of :mod:`hybridtable.compensators`
  along :data:`~hybridtable.loop.wiring.LOOP_WIRING`, the one table of the
  loop's connections that the linear models of :mod:`hybridtable.analysis` reuse;
- :mod:`~hybridtable.loop.simulation`: :func:`simulate` runs one contact;
- :mod:`~hybridtable.loop.metrics`: CoR, contact duration, peak force, energy gained;
- :mod:`~hybridtable.loop.fast`: :func:`simulate_fast`, the same loop as one exact
  discrete update per rig-computer tick (the campaigns' fast engine).
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "builder": ("LOGGED", "HybridLoop", "add_hybrid_loop", "build_hybrid_loop"),
        "fast": ("fast_unsupported", "simulate_fast"),
        "metrics": ("ContactMetrics", "contact_metrics"),
        "params": ("Approach", "CompensatorConfig", "HybridLoopParams", "Plant", "RigComputer"),
        "simulation": ("SimulationResult", "collect_result", "run_loop", "simulate"),
    },
)
