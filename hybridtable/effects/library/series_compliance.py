"""A compliance in series with the contact: it deflects by ``d - s f``.

Physics: the structure between the table's position sensor and the contact
yields by ``s f`` (``s`` in m/N, ``f`` in N), so the contact spring sees
less than the measured deflection ``d`` (m): an effective stiffness
``k / (1 + k s)`` (quasi-static).

Model: the ``ContactLaw`` of the contact back-end gets
``series_compliance_m_per_n = s`` (``ModelSpec.contact``); ``s = 0`` is
nominal.

On a six-axis rig (``apply6``) the pad ring's ``series_compliance_m_per_n``
gains ``s`` (``s pad_count`` behind each pad). With a linear spring it is a
softer contact, the same law as ``stiffness_error`` below the nominal: the
two are look-alikes that no run of one spring tells apart.

Signature: in ``f_mea_n`` during compression and restitution, a softer
effective contact, never a stiffer one.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, F_MEA

__all__ = ["EFFECT"]


#: The effect ``series_compliance`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="series_compliance",
    description="a compliance s of the structure between the table's position sensor "
    "and the contact: the contact deflects by d - s f",
    parameters=(
        EffectParameter(
            "series_compliance_m_per_n",
            "m/N",
            "series compliance s (1 / structure stiffness)",
            lower=0.0,
            upper=lambda s: 4.0 / s.stiffness_n_per_m,
            scale=lambda s: 0.01 / s.stiffness_n_per_m,
            null=0.0,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        CONTACT,
        "a softer effective contact, k / (1 + k s); never a stiffer one",
    ),
    apply=lambda spec, v, s: spec.with_contact(
        series_compliance_m_per_n=v["series_compliance_m_per_n"]
    ),
    touches=("contact.series",),
    separation_hint="a run with another contact spring, or a measurement of the "
    "contact point's position",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: s behind the ring, s pad_count behind each pad
    apply6=lambda physics, v, s: physics.plus(
        series_compliance_m_per_n=v["series_compliance_m_per_n"]
    ),
)
