"""The contact's frequency is not the stated one.

Physics: the contact frequency ``f_con = sqrt(k / m) / 2 pi`` of the rig is
``r`` times the stated one (``r`` dimensionless): the spacecraft model's mass
is ``1 / r^2`` times the stated one, or the rig's stiffness (which the MDC
tracks) ``r^2`` times; a CoR table sees the two alike.

Model: ``ModelSpec.mass_ratio`` divided by ``r^2`` (the rig computer
integrates with that mass): ``mass_error`` by another parameter, the one a CoR
table states its conditions in. ``r = 1`` is nominal; fitted in ``ln r``.

Signature: in the closed loop's ``v_des_m_per_s`` in contact, the contact lasts
``1 / r`` as long. ``explain`` tries it by default; recorded runs decide the
computer's mass in their audit.
"""

from __future__ import annotations

from dataclasses import replace

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import CONTACT, V_DES, ratio_parameter

__all__ = ["EFFECT"]


#: The effect ``contact_frequency_error``.
EFFECT = Effect(
    "contact_frequency_error",
    "the contact frequency is not the stated one (the model's mass, or a stiffness the MDC tracks)",
    (ratio_parameter("contact_frequency_ratio", "true f_con over the stated", 0.2, 5.0, "f_con"),),
    Signature((V_DES,), CONTACT, "closed loop: the contact lasts 1/ratio as long"),
    lambda spec, v, s: replace(
        spec, mass_ratio=spec.mass_ratio / v["contact_frequency_ratio"] ** 2
    ),
    stage="closed_loop",
    touches=("spacecraft.mass",),
    default_for=("explain",),  # runs: the audit decides the mass (mass_error)
)
