"""Drake systems of the hybrid loop's parts, knowing nothing of the loop.

Each is a Drake system with named snake_case ports (units in its docstring)
and a frozen parameter dataclass in SI units, validated on construction.

========================  ===================================================
module                    system
========================  ===================================================
``spacecraft``            the spacecraft model (Eq. 1), continuous or sampled
``table``                 the second-order motion table (ideal at ``inf`` Hz)
``resonant_table``        the table followed by a lightly damped structural mode
``contact``               the unilateral spring (+ damper) contact
``contact_law``           power law, Hunt-Crossley, friction, series compliance
``sensor``                the force-sensor delay (continuous, sampled, Pade)
``measurement_chain``     low pass, fractional delay and offset of a sampled rig
``noise``                 seeded measurement noise on force and position
``blocks``                a stage behind one output port; a recorded offset
========================  ===================================================

A new table or contact back-end is one new module here with the ports of the
one it replaces (``table``: in ``commanded_state`` (2), out ``motion`` (3);
contact: in ``motion``, out ``force``, ``force_rate``); the loop takes it
through ``add_hybrid_loop(builder, params, table=..., contact=...)``.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "blocks": (
            "ChainedOutput",
            "RecordedOffset",
            "chain_output",
        ),
        "contact": (
            "ContactParams",
            "UnilateralSpringContact",
        ),
        "contact_law": (
            "ContactLaw",
            "ContactLawParams",
        ),
        "measurement_chain": (
            "MeasurementChain",
            "MeasurementChainParams",
        ),
        "noise": (
            "MeasurementNoise",
            "MeasurementNoiseParams",
            "with_measurement_noise",
        ),
        "resonant_table": (
            "ResonantTable",
            "StructuralModeParams",
        ),
        "sensor": (
            "ForceSensorDelay",
            "SensorParams",
        ),
        "spacecraft": (
            "Spacecraft",
            "SpacecraftParams",
        ),
        "table": (
            "SecondOrderTable",
            "TableParams",
        ),
    },
)
