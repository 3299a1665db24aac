"""Cross-talk between the channels of a six-axis F/T sensor (a six-axis rig's).

Physics: a six-axis force sensor's calibration matrix is never diagonal in
practice; its largest off-diagonal terms carry the axial load into the other
channels (the bending moments' bridges see the axial strain; a force bridge
sees a part of it). A docking contact is dominated by the normal force, so
its column is what a run can tell.

Model: the reading's ``fx + a fz``, ``fy + b fz``, ``mx + c fz``,
``my + d fz`` (``a``, ``b`` dimensionless, ``c``, ``d`` in m: a moment
channel reading the axial force as if at a lever arm), after any turn of the
sensor: ``G = I + X`` with ``X`` the axial force's column
(:meth:`~hybridtable.six_dof.physics6.DockingPhysics.times_sensor`).

Signature: lateral forces and bending moments that follow the axial force
pulse in proportion; unlike a turned sensor (``sensor_misalignment``), the
moments read a part of the force itself, and the moments' own readings stay
unturned.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT

__all__ = ["EFFECT"]

#: The parameters' rows of the reading ``[mx, my, mz, fx, fy, fz]`` they feed.
_ROWS = {"fz_to_mx_m": 0, "fz_to_my_m": 1, "fz_to_fx": 3, "fz_to_fy": 4}


def _gain(values: Mapping[str, float]) -> np.ndarray:
    """The sensor's gain ``I + X`` (6x6, on ``[m; f]``) of the effect's values."""
    gain = np.eye(6)
    for name, row in _ROWS.items():
        gain[row, 5] = values[name]
    return gain


def _parameter(name: str, unit: str, what: str, typical: float) -> EffectParameter:
    return EffectParameter(name, unit, what, lower=-0.1, upper=0.1, scale=typical, null=0.0)


#: The effect ``sensor_crosstalk`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="sensor_crosstalk",
    description="the F/T sensor's channels read a part of the axial force (6-DoF)",
    parameters=(
        _parameter("fz_to_fx", "1", "the axial force read by the fx channel, per newton", 1e-3),
        _parameter("fz_to_fy", "1", "the axial force read by the fy channel, per newton", 1e-3),
        _parameter("fz_to_mx_m", "m", "the axial force read by the mx channel (a lever arm)", 1e-4),
        _parameter("fz_to_my_m", "m", "the axial force read by the my channel (a lever arm)", 1e-4),
    ),
    signature=Signature(
        ("fx_mea", "fy_mea", "mx_mea", "my_mea"),
        CONTACT,
        "lateral forces and bending moments in proportion to the axial force pulse",
    ),
    apply6=lambda physics, v, s: physics.times_sensor(_gain(v)),
    touches=("sensor.crosstalk",),
    separation_hint="an on-axis run: a turned sensor also turns the moments, cross-talk does not",
    default_for=(),
)
