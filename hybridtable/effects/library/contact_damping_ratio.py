"""Damping proportional to the contact: one damping ratio at every stiffness.

Physics: a damper ``c = zeta 2 sqrt(k m)`` (N s/m) in the contact, ``zeta``
the damping ratio (dimensionless), unknown to the MDC; a table across
stiffnesses tells it from one damper of fixed N s/m (``contact_damping``),
recorded runs of one rig cannot.

Model: added to the loop's ``contact_damping_n_s_per_m`` as a change of the
physics (``ModelSpec.with_loop``, through ``with_physics``: the compensator
keeps believing the stated contact); ``zeta = 0`` is nominal.

Signature: in ``f_mea_n`` as ``contact_damping``, in proportion to
``sqrt(k m)``. ``explain`` tries it by default; ``diagnose`` when named.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA, critical_damping_n_s_per_m

__all__ = ["EFFECT"]


def _apply(spec, v, s):
    def change(p):
        critical = critical_damping_n_s_per_m(p.contact_stiffness_n_per_m, p.spacecraft_mass_kg)
        extra = v["contact_damping_ratio"] * critical
        return p.with_physics(contact_damping_n_s_per_m=p.contact_damping_n_s_per_m + extra)

    return spec.with_loop(change)


#: The effect ``contact_damping_ratio``.
EFFECT = Effect(
    "contact_damping_ratio",
    "damping proportional to the contact (one damping ratio at every stiffness), "
    "unknown to the MDC",
    (
        EffectParameter(
            "contact_damping_ratio",
            "1",
            "damping over the critical 2 sqrt(k m)",
            0.0,
            0.5,
            0.002,
            0.0,
            quantity="damping ratio",
        ),
    ),
    Signature((F_MEA,), CONTACT, "like contact_damping, in proportion to sqrt(k m)"),
    _apply,
    touches=("contact.damping_ratio",),
    default_for=("explain",),
)
