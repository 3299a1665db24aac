"""A user's own CoR-level effect, written once for ``diagnose`` and ``explain``:
the table lags the command longer (or shorter) than stated.

Physics: the table's lag behind a ramp is ``r`` times the stated one (``r``
dimensionless): its second-order response frequency is the stated one divided
by ``r``. ``r = 1`` is the stated table; fitted in ``ln r``.

Model: a change of the loop's ``table_response_hz`` (``ModelSpec.with_loop``),
so that the replay's table, the closed loop's and ``explain``'s fast engine
all move. ``default_for`` is left at its default: both front ends try it.

Use: ``--plugin tests/effects/plugins/table_lag.py:EFFECT``.
"""

from hybridtable.effects import Effect, EffectParameter, Signature

__all__ = ["EFFECT"]


def _apply(spec, values, scale):
    ratio = values["table_lag_ratio"]
    return spec.with_loop(lambda p: p.with_(table_response_hz=p.table_response_hz / ratio))


EFFECT = Effect(
    name="table_lag",
    description="the table lags the command r times as long as stated",
    parameters=(
        EffectParameter(
            "table_lag_ratio",
            "1",
            "true lag of the table over the stated lag",
            lower=0.2,
            upper=5.0,
            scale=0.1,
            null=1.0,
            log=True,
            quantity="table lag",
        ),
    ),
    signature=Signature(
        ("p_act_m", "f_mea_n"),
        ("compression", "restitution"),
        "in contact the table's position lags the command by r times the stated lag",
    ),
    apply=_apply,
    stage="replay",
    touches=("table.lag",),
)
