"""The built-in CoR effects: the ways the paper's loop can differ from what a lab states.

=========================  =============================  ===========================================
effect                     parameter                      what is different on the rig
=========================  =============================  ===========================================
contact_frequency_error    contact_frequency_ratio        f_con (the model's mass, or a stiffness the
                                                          MDC tracks) is ratio x the stated one
extra_delay                extra_delay_s                  the sensor delay is longer (shorter) than
                                                          stated; the SDC's lead stays
lead_time_error            lead_error_s                   the SDC's lead differs from the stated one
table_response             table_response_ratio           the table's response frequency is ratio x
                                                          the stated one (its lag 1/ratio x)
table_damping              table_damping_factor           the table's damping ratio is factor x stated
stiffness_error            compensator_stiffness_ratio    the MDC believes ratio x the true stiffness
contact_damping            damping_n_s_per_m              one physical damper in the contact (the
                                                          same N s/m at every stiffness)
contact_damping_ratio      contact_damping_ratio          damping proportional to the contact: the
                                                          same damping ratio at every stiffness
=========================  =============================  ===========================================

An effect on the physics (extra delay, hidden damping) is not known to the
compensator: it keeps believing what it did before the effect
(:meth:`~hybridtable.loop.params.HybridLoopParams.with_physics`), e.g. the MDC
compensates with the stated, undamped contact. A delay or lead pushed below
zero is held at zero.
"""

from __future__ import annotations

from collections.abc import Mapping

from hybridtable.explain.conditions import Conditions
from hybridtable.explain.effects import CorEffect, CorParameter
from hybridtable.laws.contact import critical_damping_n_s_per_m
from hybridtable.loop.params import HybridLoopParams

__all__ = ["builtin_cor_effects"]


def _frequency(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    return p.with_(spacecraft_mass_kg=p.spacecraft_mass_kg / v["contact_frequency_ratio"] ** 2)


def _extra_delay(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    return p.with_physics(sensor_delay_s=max(0.0, p.sensor_delay_s + v["extra_delay_s"]))


def _lead(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    lead = p.beliefs()["lead_time_s"]
    return p.with_(lead_time_s=max(0.0, lead + v["lead_error_s"]))


def _table(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    return p.with_(table_response_hz=p.table_response_hz * v["table_response_ratio"])


def _table_damping(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    return p.with_(table_damping_ratio=p.table_damping_ratio * v["table_damping_factor"])


def _stiffness(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    believed = p.beliefs()["compensator_stiffness_n_per_m"]
    return p.with_(compensator_stiffness_n_per_m=believed * v["compensator_stiffness_ratio"])


def _unknown_damping(p: HybridLoopParams, extra_n_s_per_m: float) -> HybridLoopParams:
    return p.with_physics(contact_damping_n_s_per_m=p.contact_damping_n_s_per_m + extra_n_s_per_m)


def _damping(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    return _unknown_damping(p, v["damping_n_s_per_m"])


def _damping_ratio(c: Conditions, p: HybridLoopParams, v: Mapping[str, float]) -> HybridLoopParams:
    critical = critical_damping_n_s_per_m(p.contact_stiffness_n_per_m, p.spacecraft_mass_kg)
    return _unknown_damping(p, v["contact_damping_ratio"] * critical)


def builtin_cor_effects() -> list[CorEffect]:
    """The built-in effects, in the registry's order (see the module's docstring)."""
    return [
        CorEffect(
            "contact_frequency_error",
            "the contact frequency is not the stated one (the model's mass, or a stiffness "
            "the MDC tracks)",
            (CorParameter("contact_frequency_ratio", "1", 1.0, 0.2, 5.0, 0.1, True, "f_con"),),
            _frequency,
        ),
        CorEffect(
            "extra_delay",
            "the force reading is later than the stated sensor delay; the SDC's lead stays",
            (CorParameter("extra_delay_s", "s", 0.0, -0.02, 0.05, 0.001, False, "delay"),),
            _extra_delay,
        ),
        CorEffect(
            "lead_time_error",
            "the SDC's lead is not the stated one",
            (CorParameter("lead_error_s", "s", 0.0, -0.02, 0.05, 0.001, False, "T_lead"),),
            _lead,
        ),
        CorEffect(
            "table_response",
            "the table responds faster or slower than stated (its lag is the inverse)",
            (CorParameter("table_response_ratio", "1", 1.0, 0.1, 20.0, 0.1, True, "table lag"),),
            _table,
        ),
        CorEffect(
            "table_damping",
            "the table's damping ratio is not the stated one",
            (CorParameter("table_damping_factor", "1", 1.0, 0.1, 3.0, 0.1, True, "table lag"),),
            _table_damping,
        ),
        CorEffect(
            "stiffness_error",
            "the MDC believes another stiffness than the contact's",
            (
                CorParameter(
                    "compensator_stiffness_ratio", "1", 1.0, 0.1, 5.0, 0.1, True, "MDC stiffness"
                ),
            ),
            _stiffness,
        ),
        CorEffect(
            "contact_damping",
            "a damper in the contact, the same at every stiffness, unknown to the MDC",
            (CorParameter("damping_n_s_per_m", "N s/m", 0.0, 0.0, 1.0e5, 100.0, False, "damping"),),
            _damping,
        ),
        CorEffect(
            "contact_damping_ratio",
            "damping proportional to the contact (one damping ratio at every stiffness), "
            "unknown to the MDC",
            (
                CorParameter(
                    "contact_damping_ratio", "1", 0.0, 0.0, 0.5, 0.002, False, "damping ratio"
                ),
            ),
            _damping_ratio,
        ),
    ]
