"""The MDC believes another stiffness than the contact's.

Physics: the rig computer's model-based compensator uses ``r`` times the
stiffness it would believe (the stated one, else the contact's), ``r``
dimensionless; its force term is off by ``r``.

Model: a change of the loop's ``compensator_stiffness_n_per_m``
(``ModelSpec.with_loop``), from what the compensator believes; ``r = 1`` is
nominal; fitted in ``ln r``. (The audit of recorded runs names the same
finding ``compensator_stiffness_error``.)

Signature: in the closed loop's ``v_des_m_per_s`` in contact. ``explain``
tries it by default; recorded runs solve the MDC's stiffness in their audit.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import CONTACT, V_DES, ratio_parameter

__all__ = ["EFFECT"]


def _apply(spec, v, s):
    def change(p):
        believed = p.beliefs()["compensator_stiffness_n_per_m"]
        return p.with_(compensator_stiffness_n_per_m=believed * v["compensator_stiffness_ratio"])

    return spec.with_loop(change)


#: The effect ``compensator_stiffness_error``.
EFFECT = Effect(
    "compensator_stiffness_error",
    "the MDC believes another stiffness than the contact's",
    (
        ratio_parameter(
            "compensator_stiffness_ratio",
            "stiffness the MDC uses over the true one",
            0.1,
            5.0,
            "MDC stiffness",
        ),
    ),
    Signature((V_DES,), CONTACT, "closed loop: the MDC's force term is off by the ratio"),
    _apply,
    apply6=lambda physics, v, s: physics.times(
        compensator_stiffness_n_per_m=v["compensator_stiffness_ratio"]
    ),
    stage="closed_loop",
    touches=("computer.stiffness",),
    default_for=("explain",),  # runs: the audit solves the MDC's stiffness
)
