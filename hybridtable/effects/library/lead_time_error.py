"""The SDC's lead is not the stated one.

Physics: the rig computer's lead compensator predicts the force ``T_lead + e``
ahead (s) where ``T_lead`` is stated (the sensor delay unless stated); a lead
pushed below zero is held at zero.

Model: a change of the loop's ``lead_time_s`` (``ModelSpec.with_loop``), from
what the compensator believes; ``e = 0`` is nominal.

Signature: in the closed loop's ``v_des_m_per_s`` in contact, the compensated
force leads by the error. ``explain`` tries it by default; recorded runs solve
the lead in their audit.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import CONTACT, V_DES

__all__ = ["EFFECT"]


def _apply(spec, v, s):
    def change(p):
        return p.with_(lead_time_s=max(0.0, p.beliefs()["lead_time_s"] + v["lead_error_s"]))

    return spec.with_loop(change)


#: The effect ``lead_time_error``.
EFFECT = Effect(
    "lead_time_error",
    "the SDC's lead is not the stated one",
    (
        EffectParameter(
            "lead_error_s",
            "s",
            "lead used minus the stated one",
            -0.02,
            0.05,
            0.001,
            0.0,
            quantity="T_lead",
        ),
    ),
    Signature((V_DES,), CONTACT, "closed loop: the compensated force leads by the error"),
    _apply,
    apply6=lambda physics, v, s: physics.plus(lead_time_s=v["lead_error_s"]),
    stage="closed_loop",
    touches=("computer.lead",),
    default_for=("explain",),  # runs: the audit solves the lead
)
