"""A lightly damped structural mode between the table's servo and its
contact device.

Physics: the servo moves the base of a mode of natural frequency ``f_r``
(Hz) and damping ratio ``zeta_r`` (1); the contact device, which the position
sensor and the contact see, is the mode's mass:
``p'' = w_r^2 (p_s - p) + 2 zeta_r w_r (v_s - v)``, ``w_r = 2 pi f_r``.

Model: the table back-end becomes a ``ResonantTable`` with
``frequency_hz = f_r`` and ``damping_ratio = zeta_r`` (``ModelSpec.table``).
The effect has no null value (a mode of any frequency is a change); its fit
starts at the peak of the position residual's spectrum.

On a six-axis rig (``apply6``) the table model carries the mode on each of
its six pose coordinates (the Stewart platform refuses it: its dynamics are
its plant's).

Signature: in ``p_act_m`` (and ``f_mea_n`` in contact), ringing at the mode's
frequency after the start and the touch.
"""

from __future__ import annotations

import math

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import (
    F_MEA,
    P_ACT,
    mode_lower,
    mode_upper,
    resonance_starts,
)

__all__ = ["EFFECT"]


#: The effect ``table_resonance`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="table_resonance",
    description="a lightly damped structural mode between the table's servo and its contact device",
    parameters=(
        EffectParameter(
            "frequency_hz",
            "Hz",
            "natural frequency of the mode",
            lower=mode_lower,
            upper=mode_upper,
            scale=lambda s: 0.01 * mode_upper(s),
            initial=lambda s: math.sqrt(mode_lower(s) * mode_upper(s)),
        ),
        EffectParameter(
            "damping_ratio",
            "1",
            "damping ratio of the mode",
            lower=0.005,
            upper=1.0,
            scale=0.01,
            initial=0.05,
        ),
    ),
    signature=Signature(
        (P_ACT, F_MEA),
        ("approach", "compression", "restitution", "free_flight"),
        "ringing of the table position at the mode's frequency after the start "
        "and the touch, and in the force while in contact",
    ),
    apply=lambda spec, v, s: spec.with_table(
        frequency_hz=v["frequency_hz"], damping_ratio=v["damping_ratio"]
    ),
    touches=("table.mode",),
    starts=resonance_starts,
    separation_hint="a run with a sharper start (a larger approach velocity)",
    default_for=("diagnose",),  # a CoR table tries it when named (--effects)
    # on a six-axis rig: the mode on each pose coordinate of the table model
    apply6=lambda physics, v, s: physics.resonant(v["frequency_hz"], v["damping_ratio"]),
)
