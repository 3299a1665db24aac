"""A spacecraft mass in the rig computer other than the run's JSON says.

Physics: the rig computer integrates the spacecraft's motion with a mass
``r`` times the JSON's ``spacecraft_mass_kg`` (``r`` dimensionless), so the
commanded velocity change in contact is off by ``1 / r``.

Model: ``ModelSpec.mass_ratio = r`` (the closed loop runs with the changed
mass, :func:`hybridtable.measurement.rig.model_mass_kg`); ``r = 1`` is
nominal. The replay of the physical part cannot see it: the effect is fitted
in the closed loop only (``stage="closed_loop"``).

Signature: in ``v_des_m_per_s`` during compression and restitution, the
spacecraft's velocity change is off by the mass ratio.
"""

from __future__ import annotations

from dataclasses import replace

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, V_DES

__all__ = ["EFFECT"]


#: The effect ``mass_error`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="mass_error",
    description="the spacecraft model integrates with another mass than the run's "
    "JSON says (closed loop only)",
    parameters=(
        EffectParameter(
            "mass_ratio",
            "1",
            "mass used over the JSON's spacecraft_mass_kg",
            lower=0.5,
            upper=2.0,
            scale=0.005,
            null=1.0,
        ),
    ),
    signature=Signature(
        (V_DES,),
        CONTACT,
        "closed loop: the spacecraft's velocity change in contact is off by the "
        "mass ratio; the replay is unaffected",
    ),
    apply=lambda spec, v, s: replace(spec, mass_ratio=v["mass_ratio"]),
    stage="closed_loop",
    touches=("spacecraft.mass",),
    separation_hint="none needed: the closed loop tells the mass from the physics",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
)
