"""A first-order low pass in the force-measurement chain.

Physics: the force sensor, its amplifier or an anti-alias filter lags the
force with a time constant ``tau`` (s): ``1 / (tau s + 1)``.

Model: the ``MeasurementChain`` of the sensor back-end gets
``time_constant_s = tau`` (``ModelSpec.sensor``); ``tau = 0`` is the nominal
delayed sampler.

Signature: in ``f_mea_n`` during compression, restitution and free flight,
the reading lags and the touch is rounded, with a tail after the release.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import F_MEA, lag_starts, lag_upper

__all__ = ["EFFECT"]


#: The effect ``sensor_filter`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="sensor_filter",
    description="first-order low pass of the force-measurement chain",
    parameters=(
        EffectParameter(
            "time_constant_s",
            "s",
            "time constant tau of the low pass",
            lower=0.0,
            upper=lambda s: lag_upper(s, 10.0),
            scale=lambda s: 0.5 * s.sample_period_s,
            null=0.0,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        ("compression", "restitution", "free_flight"),
        "the reading lags and the touch is rounded; a tail after the release",
    ),
    apply=lambda spec, v, s: spec.with_sensor(time_constant_s=v["time_constant_s"]),
    touches=("sensor.filter",),
    starts=lag_starts,
    separation_hint="a faster or shorter contact (a larger approach velocity or a "
    "smaller spacecraft mass): a low pass rounds the touch, a delay only shifts it",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: each channel of the F/T sensor (a compliant mount, a filter)
    apply6=lambda physics, v, s: physics.low_pass(v["time_constant_s"]),
)
