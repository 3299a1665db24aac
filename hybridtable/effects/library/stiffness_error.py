"""A contact stiffness other than the nominal: ``f = k' d``.

Physics: the contact spring (or the rig's structure in series with it) is
stiffer or softer than the run's JSON says; ``k'`` in N/m.

Model: the ``ContactLaw`` of the contact back-end gets
``stiffness_n_per_m = k'`` (``ModelSpec.contact``); ``k' = k`` is nominal.

Signature: in ``f_mea_n`` during compression and restitution, the force pulse
is higher (stiffer) or lower, and shorter or longer.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA, stiffness_parameter

__all__ = ["EFFECT"]


#: The effect ``stiffness_error`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="stiffness_error",
    description="the contact stiffness differs from the nominal one",
    parameters=(stiffness_parameter("contact_stiffness_n_per_m", "true contact stiffness k"),),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "force pulse higher (stiffer) or lower, and shorter or longer",
    ),
    apply=lambda spec, v, s: spec.with_contact(stiffness_n_per_m=v["contact_stiffness_n_per_m"]),
    touches=("contact.stiffness",),
    separation_hint="a run with another contact spring, or a measurement of the "
    "contact point's position (a series compliance and a softer contact act as "
    "the same effective stiffness)",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: the pads' total stiffness
    apply6=lambda physics, v, s: physics.with_(
        contact_stiffness_n_per_m=v["contact_stiffness_n_per_m"]
    ),
)
