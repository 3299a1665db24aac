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

from hybridtable.systems.blocks import ChainedOutput, RecordedOffset, chain_output
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.contact_law import ContactLaw, ContactLawParams
from hybridtable.systems.measurement_chain import MeasurementChain, MeasurementChainParams
from hybridtable.systems.noise import (
    MeasurementNoise,
    MeasurementNoiseParams,
    with_measurement_noise,
)
from hybridtable.systems.resonant_table import ResonantTable, StructuralModeParams
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams, delay_samples
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable, TableParams

__all__ = [
    "ChainedOutput",
    "ContactLaw",
    "ContactLawParams",
    "ContactParams",
    "ForceSensorDelay",
    "MeasurementChain",
    "MeasurementChainParams",
    "MeasurementNoise",
    "MeasurementNoiseParams",
    "RecordedOffset",
    "ResonantTable",
    "SecondOrderTable",
    "SensorParams",
    "Spacecraft",
    "SpacecraftParams",
    "StructuralModeParams",
    "TableParams",
    "UnilateralSpringContact",
    "chain_output",
    "delay_samples",
    "with_measurement_noise",
]
