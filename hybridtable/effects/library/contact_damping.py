"""Viscous damping in the contact: ``f = k d + c v``.

Physics: the contact dissipates energy in proportion to the deflection rate
``v`` (m/s) with a damping coefficient ``c`` (N s/m), as a dashpot in
parallel with the contact spring ``k`` (N/m); the coefficient of restitution
falls below 1.

Model: the ``ContactLaw`` of the contact back-end gets
``damping_n_s_per_m = c`` (``ModelSpec.contact``); ``c = 0`` is the nominal
spring.

Signature: in ``f_mea_n`` during compression and restitution, the force is
higher in compression and lower in restitution, with a jump ``c v`` at the
touch; the force-deflection loop encloses energy.

On a six-axis rig (``apply6``) the pad ring's ``contact_damping_n_s_per_m``
gains ``c``: each pad a dashpot ``c / pad_count`` beside its spring.

To add an effect of your own, copy this module, edit ``EFFECT`` and add one
line to ``hybridtable/diagnosis/library/__init__.py``.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA

__all__ = ["EFFECT"]


#: The effect ``contact_damping`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="contact_damping",
    description="viscous damping in the contact: f = k d + c v",
    parameters=(
        EffectParameter(
            "damping_n_s_per_m",
            "N s/m",
            "viscous contact damping c",
            lower=0.0,
            upper=lambda s: s.critical_damping_n_s_per_m,
            scale=lambda s: 0.01 * s.critical_damping_n_s_per_m,
            null=0.0,
            quantity="damping",
        ),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "force higher in compression, lower in restitution; a jump c v at the touch; "
        "the force-deflection loop encloses energy",
    ),
    apply=lambda spec, v, s: spec.with_contact(damping_n_s_per_m=v["damping_n_s_per_m"]),
    touches=("contact.damping",),
    separation_hint="a run at another approach velocity (the damping force grows with it)",
    # on a six-axis rig: a dashpot beside the pads' springs (c / pad_count each)
    apply6=lambda physics, v, s: physics.plus(contact_damping_n_s_per_m=v["damping_n_s_per_m"]),
)
