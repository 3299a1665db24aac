"""Coulomb friction in the contact: ``+ F sign(v)`` while in contact.

Physics: a constant force ``F`` (N) opposes the deflection rate ``v`` (m/s)
while the bodies touch (e.g. sliding of a guide); its sign is smoothed,
``tanh(v / v_F)``, over ``v_F`` = 2 % of the approach velocity (m/s).

Model: the ``ContactLaw`` of the contact back-end gets
``friction_force_n = F`` and ``friction_velocity_m_per_s = v_F``
(``ModelSpec.contact``); ``F = 0`` is nominal.

On a six-axis rig (``apply6``) the pad ring's ``normal_friction_force_n``
gains ``F`` (``F / pad_count`` on each touching pad, against its own
penetration rate), smoothed over the same ``v_F``.

Signature: in ``f_mea_n`` during compression and restitution, a step ``+F``
at the touch, ``+F`` in compression and ``-F`` in restitution; the contact
releases early.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA

__all__ = ["EFFECT"]


#: The effect ``coulomb_friction`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="coulomb_friction",
    description="a constant force F against the deflection rate while in contact "
    "(sign smoothed over 2 % of the approach velocity)",
    parameters=(
        EffectParameter(
            "friction_force_n",
            "N",
            "Coulomb friction force F",
            lower=0.0,
            upper=lambda s: 0.3 * s.peak_force_n,
            scale=lambda s: 0.005 * s.peak_force_n,
            null=0.0,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "a step +F at the touch, +F in compression, -F in restitution, the contact releases early",
    ),
    apply=lambda spec, v, s: spec.with_contact(
        friction_force_n=v["friction_force_n"],
        friction_velocity_m_per_s=0.02 * s.velocity_m_per_s,
    ),
    touches=("contact.friction",),
    separation_hint="a run at another approach velocity (friction does not grow "
    "with it, damping does)",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: F / pad_count on each touching pad, along the normal
    apply6=lambda physics, v, s: physics.plus(normal_friction_force_n=v["friction_force_n"]).with_(
        normal_friction_velocity_m_per_s=0.02 * s.velocity_m_per_s
    ),
)
