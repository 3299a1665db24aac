"""A force-sensor delay other than the nominal one.

Physics: the measured force arrives ``dT`` (s) later (or earlier) than the
run's JSON says, any fraction of a tick (a delay between ticks interpolates
the two neighbouring samples).

Model: the ``MeasurementChain`` of the sensor back-end gets
``extra_delay_s = dT`` (``ModelSpec.sensor``), added to the nominal delay
``T`` (s); ``dT = 0`` is nominal, ``dT >= -T``.

Signature: in ``f_mea_n`` during compression and restitution, the measured
pulse shifted in time: an error about ``dT`` times the force rate, positive
at the touch and negative at the release.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA, delay_starts, lag_upper

__all__ = ["EFFECT"]


#: The effect ``extra_delay`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="extra_delay",
    description="the force sensor's delay differs from the nominal one (any fraction of a tick)",
    parameters=(
        EffectParameter(
            "extra_delay_s",
            "s",
            "true delay minus nominal delay",
            lower=lambda s: -s.sensor_delay_s,
            upper=lambda s: lag_upper(s, 5.0),
            scale=lambda s: 0.5 * s.sample_period_s,
            null=0.0,
            quantity="delay",
        ),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "the measured pulse shifted in time: error ~ delay x force rate, + at "
        "the touch and - at the release",
    ),
    apply=lambda spec, v, s: spec.with_sensor(extra_delay_s=v["extra_delay_s"]),
    touches=("sensor.delay",),
    starts=delay_starts,
    separation_hint="a faster or shorter contact (a larger approach velocity or a "
    "smaller spacecraft mass)",
    apply6=lambda physics, v, s: physics.plus(sensor_delay_s=v["extra_delay_s"]),
)
