"""The rig computer's spacecraft model with its centre of mass off the
scenario's (a six-axis rig's).

Physics: the hybrid rig's spacecraft is the rig computer's model; a centre of
mass entered wrongly (a mass-properties sheet of another configuration, a
lever arm measured from another datum) moves the point the contact's wrench
turns the model about. The contact, the table and the sensor are the
scenario's; what changes is the command the model sends.

Model: the computer's port sits at ``[lateral_offset_m - (x, y),
port_distance_m - z]`` from its centre of mass (body frame, m;
:meth:`~hybridtable.six_dof.physics6.DockingPhysics.computer`), its mass
and inertia the scenario's. An effect of the rig computer
(``stage="closed_loop"``): the replay, driven by the recorded command, cannot
see it; the audit of the computer's arithmetic solves for the port's
position from the record (:mod:`hybridtable.six_dof.audit6`).

Signature: the commanded attitude and the port's twist respond to the
compensated wrench with another lever arm: a moment about the port turns the
model otherwise, a force through the port turns it about another point.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT

__all__ = ["EFFECT"]

_AXES = ("x", "y", "z")

#: The effect ``com_offset`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="com_offset",
    description="the rig computer's spacecraft has its centre of mass off the scenario's "
    "(6-DoF, the computer's; found by the audit)",
    parameters=tuple(
        EffectParameter(
            f"com_{axis}_m",
            "m",
            f"the computer's centre of mass from the scenario's, body {axis}",
            lower=-1.0,
            upper=1.0,
            scale=1e-3,
            null=0.0,
        )
        for axis in _AXES
    ),
    signature=Signature(
        ("qx_des", "qy_des", "qz_des", "wx_des", "wy_des", "wz_des"),
        CONTACT,
        "the model's attitude and twist respond to the wrench with another lever arm",
    ),
    apply6=lambda physics, v, s: physics.shift_com([v[f"com_{a}_m"] for a in _AXES]),
    stage="closed_loop",
    touches=("spacecraft.com",),
    separation_hint="none needed: the audit solves for the centre of mass from the record",
    default_for=(),
)
