"""The motion table's axes turned from the target frame (a six-axis rig's):
cross-axis coupling of the table.

Physics: the table's calibration puts its axes at a small rotation
``exp(theta)`` from the target frame W, so a command along one axis moves the
port partly along the others.

Model: commanded to ``[p; theta]`` the table reaches ``[R p; R theta]``
(and the twist likewise), ``R = exp(theta)``, ``theta = (roll, pitch, yaw)``
in rad (:meth:`~hybridtable.six_dof.physics6.DockingPhysics.turn_table`).

Signature: the measured position off the command across the axis of motion,
growing with the distance travelled (``x ~ pitch z``), and the contact's
wrench that follows.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import CONTACT, rotation_parameters, rotation_vector

__all__ = ["EFFECT"]

#: The effect ``table_misalignment`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="table_misalignment",
    description="the table's axes are turned from the target frame: cross-axis coupling (6-DoF)",
    parameters=rotation_parameters("table", "the table axes"),
    signature=Signature(
        ("px_act", "py_act", "pz_act", "fx_mea", "fy_mea"),
        ("approach", *CONTACT),
        "the measured position off the command across the axis of motion",
    ),
    apply6=lambda physics, v, s: physics.turn_table(rotation_vector("table", v)),
    touches=("table.axes",),
    separation_hint="a longer approach (the offset grows with the travel)",
    default_for=(),
)
