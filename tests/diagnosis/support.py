"""Helpers of the diagnosis tests."""

from __future__ import annotations

from pydrake.systems.primitives import MatrixGain

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.systems.blocks import chain_output

__all__ = ["sensor_gain_effect"]


def sensor_gain_effect(name: str, typical_change: float) -> Effect:
    """A user's effect the library does not have: the force sensor reads ``g``
    times the force (a gain behind the sensor's ``measured_force``), ``g`` from
    0.5 to 2, null at 1, fitted in steps of about ``typical_change``."""
    return Effect(
        name=name,
        description="the force sensor reads g times the force",
        parameters=(
            EffectParameter(
                "gain",
                "1",
                "reading / force",
                lower=0.5,
                upper=2.0,
                scale=typical_change,
                null=1.0,
            ),
        ),
        signature=Signature(("f_mea_n",), ("compression", "restitution"), "force scaled"),
        apply=lambda spec, v, s: spec.wrap(
            "sensor",
            lambda p, sensor: chain_output(sensor, MatrixGain([[v["gain"]]]), "measured_force"),
        ),
    )
