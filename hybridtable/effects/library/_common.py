"""What the built-in effects share: residual channels, contact phases, the
stiffness parameter, the bounds of a structural mode and extra fit starts.

Every quantity is in SI units; a :class:`~hybridtable.effects.effect.RigScale`
gives the nominal magnitudes of the rig the bounds are relative to.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from hybridtable.effects.effect import EffectParameter
from hybridtable.effects.spec import RigScale
from hybridtable.laws.contact import critical_damping_n_s_per_m

__all__ = [
    "F_MEA",
    "P_ACT",
    "V_DES",
    "CONTACT",
    "stiffness_parameter",
    "resonance_starts",
    "spectral_starts",
    "delay_starts",
    "lag_upper",
    "lag_starts",
    "mode_lower",
    "mode_upper",
    "ratio_parameter",
    "scale_loop_field",
    "critical_damping_n_s_per_m",
    "ROTATION_AXES",
    "rotation_parameters",
    "rotation_vector",
]


#: Residual channel of the measured contact force, N.
F_MEA = "f_mea_n"
#: Residual channel of the table's measured position, m.
P_ACT = "p_act_m"
#: Residual channel of the spacecraft model's velocity command, m/s (closed loop).
V_DES = "v_des_m_per_s"
#: The phases in contact: the deflection growing, then shrinking.
CONTACT = ("compression", "restitution")


def stiffness_parameter(name: str, description: str) -> EffectParameter:
    """A stiffness parameter from 0.2 to 5 times the nominal, null at the nominal.

    Parameters
    ----------
    name : str
        Parameter name, ending in its unit (``..._n_per_m``).
    description : str
        What the stiffness is, for reports.

    Returns
    -------
    EffectParameter
        Unit N/m; bounds [0.2 k, 5 k], typical change 0.01 k, null k, with
        ``k`` the rig's nominal contact stiffness (N/m).
    """
    return EffectParameter(
        name,
        "N/m",
        description,
        lower=lambda s: 0.2 * s.stiffness_n_per_m,
        upper=lambda s: 5.0 * s.stiffness_n_per_m,
        scale=lambda s: 0.01 * s.stiffness_n_per_m,
        null=lambda s: s.stiffness_n_per_m,
    )


def spectral_starts(
    channel: str, names: tuple[str, str], lower, upper
) -> Callable[[RigScale, Sequence[Mapping[str, np.ndarray]]], list[dict[str, float]]]:
    """The ``starts`` of a mode's fit (``names``: its frequency in Hz and its
    damping ratio) from the peak of ``channel``'s residual spectrum.

    The starts are three damping ratios (0.02, 0.08, 0.2) at the peak of the
    power summed over the residuals given (if it lies in
    ``[lower(scale), upper(scale)]``, Hz), then four frequencies spaced
    geometrically between the bounds at a damping ratio of 0.05. A residual
    shorter than 16 ticks, or of another length than the first one's, adds no
    power.
    """
    freq, zeta = names

    def starts(
        scale: RigScale, residuals: Sequence[Mapping[str, np.ndarray]]
    ) -> list[dict[str, float]]:
        lo, hi = lower(scale), upper(scale)
        out = [{freq: f, zeta: 0.05} for f in np.geomspace(lo * 1.5, hi / 1.5, 4)]
        power, freqs = None, None
        for res in residuals:
            e = np.asarray(res[channel], dtype=float)
            if e.size < 16:
                continue
            e = (e - e.mean()) * np.hanning(e.size)
            n = 1 << int(math.ceil(math.log2(4 * e.size)))
            spec = np.abs(np.fft.rfft(e, n)) ** 2
            f = np.fft.rfftfreq(n, scale.sample_period_s)
            if power is None:
                power, freqs = spec, f
            elif len(spec) == len(power):
                power = power + spec
        if power is not None:
            band = (freqs >= lo) & (freqs <= hi)
            if band.any():
                peak = float(freqs[band][np.argmax(power[band])])
                out = [{freq: peak, zeta: z} for z in (0.02, 0.08, 0.2)] + out
        return out

    return starts


def lag_upper(scale: RigScale, ticks: float) -> float:
    """Largest sensor lag or extra delay of a fit, s: ``ticks`` sample periods
    or a fifth of the contact's duration (:attr:`RigScale.contact_duration_s`),
    whichever is longer (a slow contact can hide a long lag behind few ticks)."""
    return max(ticks * scale.sample_period_s, 0.2 * scale.contact_duration_s)


def _tick_grid(upper_ticks: float) -> list[int]:
    """1, 2, 3, then Fibonacci-spaced whole ticks up to ``upper_ticks``."""
    out, a, b = [1, 2, 3], 3, 5
    while b <= upper_ticks:
        out.append(b)
        a, b = b, a + b
    return [j for j in out if j <= upper_ticks]


def delay_starts(scale: RigScale, residuals) -> list[dict[str, float]]:
    """Starts of the delay's fit: whole ticks around the nominal delay.

    Parameters
    ----------
    scale : RigScale
        Nominal magnitudes of the rig (sample period ``h`` and sensor delay
        ``T``, s).
    residuals : sequence of mapping
        Nominal residuals (unused; the signature of a ``starts`` callable).

    Returns
    -------
    list of dict
        ``{"extra_delay_s": j h}`` for ``j`` in -2, -1 (those that keep the
        total delay ``T + j h`` non-negative), 1, 2, 3 and Fibonacci-spaced
        ticks up to :func:`lag_upper` (s).
    """
    h = scale.sample_period_s
    lo = -scale.sensor_delay_s
    up = lag_upper(scale, 5.0) / h
    ticks = [-2, -1, *_tick_grid(up)]
    return [{"extra_delay_s": j * h} for j in ticks if j * h >= lo]


def lag_starts(scale: RigScale, residuals) -> list[dict[str, float]]:
    """Starts of a low pass's fit: time constants of whole ticks, Fibonacci-spaced
    up to :func:`lag_upper` (``{"time_constant_s": s}``; residuals unused)."""
    h = scale.sample_period_s
    return [{"time_constant_s": j * h} for j in _tick_grid(lag_upper(scale, 10.0) / h)]


def mode_lower(scale: RigScale) -> float:
    """Lowest frequency of a structural mode, Hz: half the table's servo
    frequency, at least 1 Hz (1 Hz if the servo frequency is not finite)."""
    f = scale.table_frequency_hz
    return max(1.0, 0.5 * f) if math.isfinite(f) else 1.0


def mode_upper(scale: RigScale) -> float:
    """Highest frequency of a structural mode, Hz: 0.45 / h, just below the
    Nyquist frequency of the sample period ``h`` (s)."""
    return 0.45 / scale.sample_period_s


#: Starts of a table mode's fit: the peak of the position residual's spectrum.
resonance_starts = spectral_starts(P_ACT, ("frequency_hz", "damping_ratio"), mode_lower, mode_upper)


def ratio_parameter(
    name: str, description: str, lower: float, upper: float, quantity: str
) -> EffectParameter:
    """A ratio to the stated value (unit 1), null 1, fitted in its logarithm with
    a typical change of 0.1 (10 %), moving the loop ``quantity`` (in words)."""
    return EffectParameter(
        name, "1", description, lower, upper, 0.1, 1.0, log=True, quantity=quantity
    )


def scale_loop_field(field: str, parameter: str):
    """The ``apply`` of an effect that multiplies the loop's ``field`` (a field of
    :class:`~hybridtable.loop.params.HybridLoopParams`) by its ``parameter``."""

    def apply(spec, values, scale):
        ratio = values[parameter]
        return spec.with_loop(lambda p: p.with_(**{field: getattr(p, field) * ratio}))

    return apply


#: The three small rotations of a frame: (word, axis).
ROTATION_AXES: tuple[tuple[str, str], ...] = (("roll", "x"), ("pitch", "y"), ("yaw", "z"))


def rotation_parameters(prefix: str, what: str) -> tuple[EffectParameter, ...]:
    """``{prefix}_roll_rad``, ``_pitch_rad``, ``_yaw_rad``: a frame's small
    rotation vector (rad, within +-0.1, typical 1 mrad, null 0), ``what``
    naming the frame."""
    return tuple(
        EffectParameter(
            f"{prefix}_{word}_rad",
            "rad",
            f"rotation of {what} about {axis}",
            lower=-0.1,
            upper=0.1,
            scale=1e-3,
            null=0.0,
        )
        for word, axis in ROTATION_AXES
    )


def rotation_vector(prefix: str, values: Mapping[str, float]) -> list[float]:
    """The rotation vector of :func:`rotation_parameters`' values."""
    return [values[f"{prefix}_{word}_rad"] for word, _ in ROTATION_AXES]
