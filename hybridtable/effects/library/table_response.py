"""The table responds faster or slower than stated.

Physics: the table's second-order response frequency is ``r`` times the stated
one (``r`` dimensionless), its lag behind a ramp ``1 / r`` times.

Model: a change of the loop's ``table_response_hz`` (``ModelSpec.with_loop``),
so that the replay's and the closed loop's table and the fast engine's all
move; ``r = 1`` is nominal; fitted in ``ln r``.

Signature: in ``p_act_m`` (and ``f_mea_n``) in contact, the table's position
lags the command by ``1 / r`` of the stated lag. ``explain`` tries it by
default; ``diagnose`` when named (``--effects table_response``).
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


#: The effect ``table_response``.
EFFECT = Effect(
    "table_response",
    "the table responds faster or slower than stated (its lag is the inverse)",
    (
        ratio_parameter(
            "table_response_ratio",
            "true response frequency over the stated",
            0.1,
            20.0,
            "table lag",
        ),
    ),
    Signature((P_ACT, F_MEA), CONTACT, "the table's position lags the command by 1/ratio"),
    scale_loop_field("table_response_hz", "table_response_ratio"),
    touches=("table.response",),
    default_for=("explain",),
    apply6=lambda physics, v, s: physics.times(table_response_hz=v["table_response_ratio"]),
)
