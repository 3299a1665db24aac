"""The F/T sensor's frame turned from the one the rig computer assumes (a
six-axis rig's).

Physics: the sensor is mounted turned by a small rotation: it reports the
wrench in its own axes, which the rig computer takes for the target frame's,
so a push along the docking axis reads partly across it.

Model: the reading is the contact's wrench ``[m; f]`` turned by ``R =
exp(theta)``: ``[R m; R f]``, ``theta = (roll, pitch, yaw)`` in rad (a sensor
frame turned by ``R^T``;
:meth:`~hybridtable.six_dof.physics6.DockingPhysics.turn_sensor`).

Signature: a lateral force and moments that follow the axial force pulse in
proportion (``f_x ~ pitch f_z``, ``f_y ~ -roll f_z``), also on axis.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import CONTACT, rotation_parameters, rotation_vector

__all__ = ["EFFECT"]

#: The effect ``sensor_misalignment`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="sensor_misalignment",
    description="the F/T sensor's frame is turned from the assumed one: its reading turned (6-DoF)",
    parameters=rotation_parameters("sensor", "the reading"),
    signature=Signature(
        ("fx_mea", "fy_mea", "mx_mea", "my_mea", "mz_mea"),
        CONTACT,
        "lateral force and moments in proportion to the axial force pulse",
    ),
    apply6=lambda physics, v, s: physics.turn_sensor(rotation_vector("sensor", v)),
    touches=("sensor.frame",),
    separation_hint="an on-axis run: only a turned sensor reads a lateral force there",
    default_for=(),
)
