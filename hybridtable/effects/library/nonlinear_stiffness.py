"""A power-law contact: ``f = k_ref d_ref (d / d_ref)^n``.

Physics: the contact spring is not linear (``n = 1.5``: Hertzian contact of
curved surfaces); ``k_ref`` (N/m) is the secant stiffness ``f / d`` at the
reference deflection ``d_ref`` (m), the peak deflection of an undamped
contact at the fastest approach.

Model: the ``ContactLaw`` of the contact back-end gets ``exponent = n``,
``stiffness_n_per_m = k_ref`` and ``reference_deflection_m = d_ref``
(``ModelSpec.contact``); ``n = 1``, ``k_ref = k`` is the nominal spring.

On a six-axis rig (``apply6``) each pad's spring is the power law, the ring's
total secant stiffness ``k_ref`` at the press ``d_ref`` (every pad alike on
the axis).

Signature: in ``f_mea_n`` during compression and restitution, the force pulse
changes shape (steeper or flatter at small deflection), symmetric in
compression and restitution.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA, stiffness_parameter

__all__ = ["EFFECT"]


#: The effect ``nonlinear_stiffness`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="nonlinear_stiffness",
    description="power-law contact: f = k_ref d_ref (d / d_ref)^n, d_ref the peak "
    "deflection of an undamped contact at the fastest approach",
    parameters=(
        EffectParameter(
            "exponent",
            "1",
            "exponent n (1: linear; 1.5: Hertzian)",
            lower=0.5,
            upper=3.0,
            scale=0.02,
            null=1.0,
        ),
        stiffness_parameter("reference_stiffness_n_per_m", "secant stiffness f / d at d_ref"),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "the force pulse changes shape (steeper or flatter at small deflection), "
        "symmetric in compression and restitution",
    ),
    apply=lambda spec, v, s: spec.with_contact(
        exponent=v["exponent"],
        stiffness_n_per_m=v["reference_stiffness_n_per_m"],
        reference_deflection_m=s.peak_deflection_m,
    ),
    touches=("contact.stiffness",),
    separation_hint="runs at two approach velocities (the secant stiffness changes "
    "with the peak deflection only for a power law)",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: each pad's spring the power law, the ring's total k_ref
    apply6=lambda physics, v, s: physics.with_(
        contact_stiffness_n_per_m=v["reference_stiffness_n_per_m"],
        contact_exponent=v["exponent"],
        reference_press_m=s.peak_deflection_m,
    ),
)
