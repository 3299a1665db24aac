"""An offset in the force reading.

Physics: the force sensor reads ``b`` (N) more than the force (a zero drift
or a tare error).

Model: the ``MeasurementChain`` of the sensor back-end gets ``bias_n = b``
(``ModelSpec.sensor``); ``b = 0`` is nominal.

Signature: in ``f_mea_n``, a constant error in every phase (approach,
compression, restitution, free flight), also without contact.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import F_MEA

__all__ = ["EFFECT"]


#: The effect ``force_bias`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="force_bias",
    description="an offset in the force reading",
    parameters=(
        EffectParameter(
            "bias_n",
            "N",
            "offset b of the reading",
            lower=lambda s: -0.2 * s.peak_force_n,
            upper=lambda s: 0.2 * s.peak_force_n,
            scale=lambda s: 0.002 * s.peak_force_n,
            null=0.0,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        ("approach", "compression", "restitution", "free_flight"),
        "a constant force error in every phase, also without contact",
    ),
    apply=lambda spec, v, s: spec.with_sensor(bias_n=v["bias_n"]),
    touches=("sensor.bias",),
    separation_hint="a longer record without contact",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: along the normal (the compression force is -fz)
    apply6=lambda physics, v, s: physics.biased([0.0, 0.0, 0.0, 0.0, 0.0, -v["bias_n"]]),
)
