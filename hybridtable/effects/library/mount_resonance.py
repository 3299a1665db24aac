"""The force sensor on a compliant, lightly damped mount: its reading rings.

Physics: the sensor (a load cell, a six-axis F/T sensor) sits on a structure
of natural frequency ``f`` (Hz) and damping ratio ``zeta`` (1); what it reads
of the force ``u`` follows ``y'' = w^2 (u - y) - 2 zeta w y'``, ``w = 2 pi
f``: the table's second-order law (:mod:`hybridtable.laws.table`), at unit
gain. Unlike a low pass or a delay, whose poles are real, the mount has a
complex pair: the reading overshoots a sharp touch and rings after it and
after the release.

Model: the ``MeasurementChain`` of the sensor back-end gets
``mount_frequency_hz = f`` and ``mount_damping_ratio = zeta``
(``ModelSpec.sensor``), after its low pass and before its delay, exact for a
force linear between the ticks; on a six-axis rig, each channel of the F/T
sensor alike (:meth:`~hybridtable.six_dof.physics6.DockingPhysics.mount`).
The effect has no null value (a mode of any frequency is a change); its fit
starts at the peak of the force residual's spectrum.

Signature: in ``f_mea_n``, ringing at the mount's frequency after the touch
and the release; the touch overshoots.
"""

from __future__ import annotations

import math

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.effects.library._common import F_MEA, mode_upper, spectral_starts

__all__ = ["EFFECT"]

#: The lowest mount frequency a fit tries, Hz.
LOWEST_HZ = 1.0

#: The largest damping ratio of a mount that rings: ``1 / sqrt(2)``, above
#: which the mode's frequency response has no peak. A mount more damped is a
#: low pass (``sensor_filter``), and a fit of both to one would be a look-alike
#: pair: an overdamped mode at 35 Hz mimics a 9 ms first-order lag.
RINGING_LIMIT = math.sqrt(0.5)

_NAMES = ("mount_frequency_hz", "mount_damping_ratio")


#: The effect ``mount_resonance`` (registered by :mod:`hybridtable.effects.registry`).
EFFECT = Effect(
    name="mount_resonance",
    description="the force sensor sits on a compliant, lightly damped mount: its reading rings",
    parameters=(
        EffectParameter(
            _NAMES[0],
            "Hz",
            "natural frequency f of the mount",
            lower=LOWEST_HZ,
            upper=mode_upper,
            scale=0.02,  # 2 % of the frequency (fitted in its logarithm)
            initial=lambda s: (LOWEST_HZ * mode_upper(s)) ** 0.5,
            log=True,
        ),
        EffectParameter(
            _NAMES[1],
            "1",
            "damping ratio zeta of the mount (below 1/sqrt(2): above it the mode has no "
            "resonant peak, a low pass: sensor_filter)",
            lower=0.005,
            upper=RINGING_LIMIT,
            scale=0.01,
            initial=0.05,
        ),
    ),
    signature=Signature(
        (F_MEA,),
        ("compression", "restitution", "free_flight"),
        "the reading overshoots the touch and rings at the mount's frequency after "
        "the touch and the release",
    ),
    apply=lambda spec, v, s: spec.with_sensor(
        mount_frequency_hz=v[_NAMES[0]], mount_damping_ratio=v[_NAMES[1]]
    ),
    touches=("sensor.mount",),
    starts=spectral_starts(F_MEA, _NAMES, lambda s: LOWEST_HZ, mode_upper),
    separation_hint="a sharper touch (a faster approach, a stiffer contact): the mount "
    "rings after it, a low pass or a delay does not",
    default_for=(),  # the 1-D front ends try it when named (--effects); 6-DoF always
    apply6=lambda physics, v, s: physics.mount(v[_NAMES[0]], v[_NAMES[1]]),
)
