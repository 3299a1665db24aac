"""The built-in candidate effects of ``hybridtable diagnose``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from hybridtable.diagnosis.effects import Effect, EffectParameter, RigScale, Signature

__all__ = ["builtin_effects"]


# -- the library ---------------------------------------------------------------
def _stiffness_parameter(name: str, description: str) -> EffectParameter:
    """A stiffness parameter from 0.2 to 5 times the nominal, null at the nominal."""
    return EffectParameter(
        name,
        "N/m",
        description,
        lower=lambda s: 0.2 * s.stiffness_n_per_m,
        upper=lambda s: 5.0 * s.stiffness_n_per_m,
        scale=lambda s: 0.01 * s.stiffness_n_per_m,
        null=lambda s: s.stiffness_n_per_m,
    )


def _resonance_starts(
    scale: RigScale, residuals: Sequence[Mapping[str, np.ndarray]]
) -> list[dict[str, float]]:
    """Starts of the mode's fit: the peak of the position residual's spectrum
    within the bounds, and a coarse grid."""
    lo = _mode_lower(scale)
    hi = _mode_upper(scale)
    starts = [
        {"frequency_hz": f, "damping_ratio": 0.05} for f in np.geomspace(lo * 1.5, hi / 1.5, 4)
    ]
    power, freqs = None, None
    for res in residuals:
        e = np.asarray(res["p_act_m"], dtype=float)
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
            starts = [
                {"frequency_hz": peak, "damping_ratio": z} for z in (0.02, 0.08, 0.2)
            ] + starts
    return starts


def _delay_starts(scale: RigScale, residuals) -> list[dict[str, float]]:
    h = scale.sample_period_s
    lo = -scale.sensor_delay_s
    return [{"extra_delay_s": j * h} for j in (-2, -1, 1, 2, 3) if j * h >= lo]


def _mode_lower(scale: RigScale) -> float:
    f = scale.table_frequency_hz
    return max(1.0, 0.5 * f) if math.isfinite(f) else 1.0


def _mode_upper(scale: RigScale) -> float:
    return 0.45 / scale.sample_period_s


def builtin_effects() -> list[Effect]:
    """The built-in effects, in registration order (ties of the ranking go to the first)."""
    F_MEA, P_ACT, V_DES = "f_mea_n", "p_act_m", "v_des_m_per_s"
    CONTACT = ("compression", "restitution")
    return [
        Effect(
            name="contact_damping",
            description="viscous damping in the contact: f = k d + c v",
            parameters=(
                EffectParameter(
                    "damping_n_s_per_m",
                    "N s/m",
                    "viscous contact damping c",
                    lower=0.0,
                    upper=lambda s: s.critical_damping_n_s_per_m,
                    scale=lambda s: 0.01 * s.critical_damping_n_s_per_m,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "force higher in compression, lower in restitution; a jump c v at the touch; "
                "the force-deflection loop encloses energy",
            ),
            apply=lambda spec, v, s: spec.with_contact(damping_n_s_per_m=v["damping_n_s_per_m"]),
            touches=("contact.damping",),
            separation_hint="a run at another approach velocity (the damping force grows with it)",
        ),
        Effect(
            name="hunt_crossley",
            description="Hunt-Crossley damping, proportional to the deflection: "
            "f = k d (1 + alpha v)",
            parameters=(
                EffectParameter(
                    "damping_factor_s_per_m",
                    "s/m",
                    "Hunt-Crossley factor alpha (CoR ~ 1 - 2/3 alpha v_in)",
                    lower=0.0,
                    upper=lambda s: 10.0 / s.velocity_m_per_s,
                    scale=lambda s: 0.05 / s.velocity_m_per_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "like viscous damping but no jump at the touch: the damping force vanishes "
                "with the deflection",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                hunt_crossley_s_per_m=v["damping_factor_s_per_m"]
            ),
            touches=("contact.hunt_crossley",),
            separation_hint="a faster approach (the touch is steeper: a jump for viscous "
            "damping, none for Hunt-Crossley)",
        ),
        Effect(
            name="nonlinear_stiffness",
            description="power-law contact: f = k_ref d_ref (d / d_ref)^n, d_ref the peak "
            "deflection of an undamped contact at the fastest approach",
            parameters=(
                EffectParameter(
                    "exponent",
                    "1",
                    "exponent n (1: linear; 1.5: Hertzian)",
                    lower=0.5,
                    upper=3.0,
                    scale=0.02,
                    null=1.0,
                ),
                _stiffness_parameter(
                    "reference_stiffness_n_per_m", "secant stiffness f / d at d_ref"
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "the force pulse changes shape (steeper or flatter at small deflection), "
                "symmetric in compression and restitution",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                exponent=v["exponent"],
                stiffness_n_per_m=v["reference_stiffness_n_per_m"],
                reference_deflection_m=s.peak_deflection_m,
            ),
            touches=("contact.stiffness",),
            separation_hint="runs at two approach velocities (the secant stiffness changes "
            "with the peak deflection only for a power law)",
        ),
        Effect(
            name="stiffness_error",
            description="the contact stiffness differs from the nominal one",
            parameters=(
                _stiffness_parameter("contact_stiffness_n_per_m", "true contact stiffness k"),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "force pulse higher (stiffer) or lower, and shorter or longer",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                stiffness_n_per_m=v["contact_stiffness_n_per_m"]
            ),
            touches=("contact.stiffness",),
            separation_hint="a run with another contact spring, or a measurement of the "
            "contact point's position (a series compliance and a softer contact act as "
            "the same effective stiffness)",
        ),
        Effect(
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
        ),
        Effect(
            name="coulomb_friction",
            description="a constant force F against the deflection rate while in contact "
            "(sign smoothed over 2 % of the approach velocity)",
            parameters=(
                EffectParameter(
                    "friction_force_n",
                    "N",
                    "Coulomb friction force F",
                    lower=0.0,
                    upper=lambda s: 0.3 * s.peak_force_n,
                    scale=lambda s: 0.005 * s.peak_force_n,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "a step +F at the touch, +F in compression, -F in restitution, the contact "
                "releases early",
            ),
            apply=lambda spec, v, s: spec.with_contact(
                friction_force_n=v["friction_force_n"],
                friction_velocity_m_per_s=0.02 * s.velocity_m_per_s,
            ),
            touches=("contact.friction",),
            separation_hint="a run at another approach velocity (friction does not grow "
            "with it, damping does)",
        ),
        Effect(
            name="sensor_filter",
            description="first-order low pass of the force-measurement chain",
            parameters=(
                EffectParameter(
                    "time_constant_s",
                    "s",
                    "time constant tau of the low pass",
                    lower=0.0,
                    upper=lambda s: 10.0 * s.sample_period_s,
                    scale=lambda s: 0.5 * s.sample_period_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                ("compression", "restitution", "free_flight"),
                "the reading lags and the touch is rounded; a tail after the release",
            ),
            apply=lambda spec, v, s: spec.with_sensor(time_constant_s=v["time_constant_s"]),
            touches=("sensor.filter",),
            separation_hint="a faster or shorter contact (a larger approach velocity or a "
            "smaller spacecraft mass): a low pass rounds the touch, a delay only shifts it",
        ),
        Effect(
            name="extra_delay",
            description="the force sensor's delay differs from the nominal one (any "
            "fraction of a tick)",
            parameters=(
                EffectParameter(
                    "extra_delay_s",
                    "s",
                    "true delay minus nominal delay",
                    lower=lambda s: -s.sensor_delay_s,
                    upper=lambda s: 5.0 * s.sample_period_s,
                    scale=lambda s: 0.5 * s.sample_period_s,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                CONTACT,
                "the measured pulse shifted in time: error ~ delay x force rate, + at "
                "the touch and - at the release",
            ),
            apply=lambda spec, v, s: spec.with_sensor(extra_delay_s=v["extra_delay_s"]),
            touches=("sensor.delay",),
            starts=_delay_starts,
            separation_hint="a faster or shorter contact (a larger approach velocity or a "
            "smaller spacecraft mass)",
        ),
        Effect(
            name="table_resonance",
            description="a lightly damped structural mode between the table's servo and "
            "its contact device",
            parameters=(
                EffectParameter(
                    "frequency_hz",
                    "Hz",
                    "natural frequency of the mode",
                    lower=_mode_lower,
                    upper=_mode_upper,
                    scale=lambda s: 0.01 * _mode_upper(s),
                    initial=lambda s: math.sqrt(_mode_lower(s) * _mode_upper(s)),
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
            starts=_resonance_starts,
            separation_hint="a run with a sharper start (a larger approach velocity)",
        ),
        Effect(
            name="force_bias",
            description="an offset in the force reading",
            parameters=(
                EffectParameter(
                    "bias_n",
                    "N",
                    "offset b of the reading",
                    lower=lambda s: -0.2 * s.peak_force_n,
                    upper=lambda s: 0.2 * s.peak_force_n,
                    scale=lambda s: 0.002 * s.peak_force_n,
                    null=0.0,
                ),
            ),
            signature=Signature(
                (F_MEA,),
                ("approach", "compression", "restitution", "free_flight"),
                "a constant force error in every phase, also without contact",
            ),
            apply=lambda spec, v, s: spec.with_sensor(bias_n=v["bias_n"]),
            touches=("sensor.bias",),
            separation_hint="a longer record without contact",
        ),
        Effect(
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
        ),
    ]
