"""The 6-DoF docking loop: a rigid spacecraft, Drake's compliant contact of two
docking devices, a table model or the Stewart platform moved by full-pose
inverse kinematics, a 6-axis F/T sensor, and the paper's compensators on the
wrench with a 6x6 stiffness (``docs/six_dof.md``).

- :mod:`~hybridtable.six_dof.params`: the parameters of a run;
- :mod:`~hybridtable.six_dof.pose`: rotation vectors;
- :mod:`~hybridtable.six_dof.contact`: the docking devices and Drake's contact;
- :mod:`~hybridtable.six_dof.spacecraft`: the rigid-body spacecraft model;
- :mod:`~hybridtable.six_dof.table`: the table model;
- :mod:`~hybridtable.six_dof.sensor`: the F/T sensor's delay and noise;
- :mod:`~hybridtable.six_dof.compensator`, :mod:`~hybridtable.six_dof.registry`:
  the wrench compensators;
- :mod:`~hybridtable.six_dof.builder`, :mod:`~hybridtable.six_dof.simulation`,
  :mod:`~hybridtable.six_dof.metrics`: the loop, a run, its metrics.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "params": [
            "ApproachParams",
            "DockingContactParams",
            "DockingLoopParams",
            "RigidBodyParams",
        ],
        "contact": ["DockingContact"],
        "builder": ["DockingLoop", "add_docking_loop", "build_docking_loop"],
        "metrics": ["DockingMetrics"],
        "simulation": ["DockingRun", "simulate6"],
        "registry": ["register_wrench_compensator", "wrench_compensator_names"],
    },
)
