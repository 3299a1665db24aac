"""The table's damping ratio is not the stated one.

Physics: the table's second-order damping ratio is ``r`` times the stated one
(``r`` dimensionless): its lag behind a ramp and its overshoot change.

Model: a change of the loop's ``table_damping_ratio`` (``ModelSpec.with_loop``);
``r = 1`` is nominal; fitted in ``ln r``.

Signature: in ``p_act_m`` (and ``f_mea_n``) in contact, the table's lag and
overshoot. ``explain`` tries it by default; ``diagnose`` when named.
"""

from __future__ import annotations

from hybridtable.effects.effect import Effect, Signature
from hybridtable.effects.library._common import (
    CONTACT,
    F_MEA,
    P_ACT,
    ratio_parameter,
    scale_loop_field,
)

__all__ = ["EFFECT"]


#: The effect ``table_damping``.
EFFECT = Effect(
    "table_damping",
    "the table's damping ratio is not the stated one",
    (
        ratio_parameter(
            "table_damping_factor", "true damping ratio over the stated", 0.1, 3.0, "table lag"
        ),
    ),
    Signature((P_ACT, F_MEA), CONTACT, "the table's lag and overshoot change"),
    scale_loop_field("table_damping_ratio", "table_damping_factor"),
    touches=("table.damping",),
    default_for=("explain",),
    apply6=lambda physics, v, s: physics.times(table_damping_ratio=v["table_damping_factor"]),
)
