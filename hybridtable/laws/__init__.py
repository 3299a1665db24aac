"""The physical laws of the rig, each written once, used by every engine.

Each module holds one law as plain functions. The switching laws
(``compensation``, ``contact``, written with :func:`~hybridtable.laws.select.select`)
run on ``float`` (the fast exact-discrete engine, the 6-DoF rig computer), on
``AutoDiffXd`` (``Linearize``), on numpy arrays (the 6-DoF wrench, the
replay's samples) and on ``pydrake.symbolic`` expressions, from which the
Drake systems of :mod:`hybridtable.systems` and :mod:`hybridtable.compensators`
are compiled (:func:`~hybridtable.laws.compiled.compiled_system`: the diagram
evaluates the law in C++ without a Python callback per step) and the fast
engine's tick functions generated (:func:`~hybridtable.laws.compiled.python_function`).
``table``, ``spacecraft`` and ``separation`` are numeric (matrices of a tick,
the stop rule). Rules that belong to a parameter set stay with it: what the
compensator believes in :mod:`hybridtable.loop.params`, the computer's mass in
:mod:`hybridtable.measurement.rig`, the F/T payload compensation in
:mod:`hybridtable.stewart.ft_sensor`.

========================  ===================================================
module                    law
========================  ===================================================
``select``                a branch on a signal, for numbers and expressions
``compensation``          the rig computer's compensation (gate, SDC lead,
                          MDC term, clamp; Eq. 2-7), 1-D and 6-DoF
``contact``               the unilateral spring-damper contact
``spacecraft``            the rig computer's model over a tick (semi-implicit Euler)
``table``                 a second-order response over a held tick
``separation``            run until separated: when a run ends, diverged or not
``compiled``              a law as a compiled Drake system with named ports, or
                          as one plain Python function (the fast engine's ticks)
========================  ===================================================
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "compensation": (
            "GATES",
            "CompensationLaw",
            "above_deadband",
            "compensate",
            "backward_difference",
            "nonnegative",
        ),
        "compiled": ("CompiledLaw", "compiled_system", "python_function", "LawSystem"),
        "contact": (
            "critical_damping_n_s_per_m",
            "spring_contact_force",
            "spring_contact_force_rate",
        ),
        "select": ("select", "both"),
        "separation": (
            "DIVERGED_FORCE_RATIO",
            "MAX_INTEGRATOR_STEPS",
            "SeparationRule",
            "check_steps_taken",
        ),
        "spacecraft": ("computer_step",),
        "table": ("held_tick", "second_order_matrices", "second_order_tick"),
    },
)
