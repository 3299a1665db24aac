"""Friction across the contact face other than the scenario's (a six-axis rig's).

Physics: the pads slide on the target's face with a Coulomb coefficient
``mu + d_mu`` where the scenario states ``mu`` (often 0: a face assumed
lubricated), ``d_mu >= 0``: the face grips more than stated. Off axis, the
tangential force it makes turns the spacecraft and moves it sideways. (A face
that grips less than stated would need the stated coefficient in the bounds,
which the effect's scale does not carry: not modelled.)

Model: the docking contact's ``friction_coefficient`` is the scenario's plus
``extra_friction_coefficient``; Drake's regularized friction
(:mod:`hybridtable.six_dof.contact`).

Signature: in the measured force across the face (fx, fy) and the moments
about the face's axes while the pads press and slide; nothing on axis.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT

__all__ = ["EFFECT"]

#: The effect ``friction_across_face`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="friction_across_face",
    description="the contact face's Coulomb friction differs from the scenario's (6-DoF)",
    parameters=(
        EffectParameter(
            "extra_friction_coefficient",
            "1",
            "true friction coefficient minus the stated one",
            lower=0.0,
            upper=1.5,
            scale=0.05,
            null=0.0,
        ),
    ),
    signature=Signature(
        ("fx_mea", "fy_mea", "mx_mea", "my_mea"),
        CONTACT,
        "a force across the face and moments about its axes while the pads slide",
    ),
    apply6=lambda physics, v, s: physics.plus(friction_coefficient=v["extra_friction_coefficient"]),
    touches=("contact.friction",),
    separation_hint="an approach with a larger lateral miss or tilt (more sliding)",
    default_for=(),
)
