"""Hunt-Crossley damping: ``f = k d (1 + alpha v)``.

Physics: damping proportional to the deflection ``d`` (m) as well as the
deflection rate ``v`` (m/s), with factor ``alpha`` (s/m), as in impacts of
solids; the coefficient of restitution is about ``1 - 2/3 alpha v_in``.

Model: the ``ContactLaw`` of the contact back-end gets
``hunt_crossley_s_per_m = alpha`` (``ModelSpec.contact``); ``alpha = 0`` is
the nominal spring.

Signature: in ``f_mea_n`` during compression and restitution, like viscous
damping but without the jump at the touch: the damping force vanishes with
the deflection.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA

__all__ = ["EFFECT"]


#: The effect ``hunt_crossley`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="hunt_crossley",
    description="Hunt-Crossley damping, proportional to the deflection: f = k d (1 + alpha v)",
    parameters=(
        EffectParameter(
            "damping_factor_s_per_m",
            "s/m",
            "Hunt-Crossley factor alpha (CoR ~ 1 - 2/3 alpha v_in)",
            lower=0.0,
            upper=lambda s: 10.0 / s.velocity_m_per_s,
            scale=lambda s: 0.05 / s.velocity_m_per_s,
            null=0.0,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "like viscous damping but no jump at the touch: the damping force vanishes "
        "with the deflection",
    ),
    apply=lambda spec, v, s: spec.with_contact(hunt_crossley_s_per_m=v["damping_factor_s_per_m"]),
    touches=("contact.hunt_crossley",),
    separation_hint="a faster approach (the touch is steeper: a jump for viscous "
    "damping, none for Hunt-Crossley)",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: each pad's Hunt-Crossley factor (Drake's dissipation)
    apply6=lambda physics, v, s: physics.plus(
        contact_dissipation_s_per_m=v["damping_factor_s_per_m"]
    ),
)
