"""The old CoR effect types of ``explain`` (:class:`CorEffect`, :class:`CorParameter`),
kept so that a plug-in written for them still loads: each becomes an
:class:`~hybridtable.effects.effect.Effect` of the one registry.

New effects are :class:`~hybridtable.effects.effect.Effect` s (``docs/explain.md``):
one effect is a candidate for ``diagnose`` and ``explain`` alike. An old one's
``apply(conditions, params, values) -> params`` becomes a change of the loop's
parameters (:meth:`~hybridtable.effects.spec.ModelSpec.with_loop`), given the
conditions the loop's parameters state; it is seen by ``explain`` and, as a
change of the rig computer, by ``diagnose``'s closed loop.
:func:`register_cor_effect` and the entry-point group
``hybridtable.cor_effects`` still register them
(:mod:`hybridtable.effects.registry`), with a :class:`DeprecationWarning`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.errors import ParameterError
from hybridtable.loop.params import HybridLoopParams

__all__ = ["CorParameter", "CorEffect", "as_effect", "ENTRY_POINT_GROUP"]

#: The old entry-point group of CoR effects (still loaded, deprecated).
ENTRY_POINT_GROUP = "hybridtable.cor_effects"

#: The old apply: (stated conditions, the loop so far, the effect's values) -> the loop.
Apply = Callable[[Any, HybridLoopParams, Mapping[str, float]], HybridLoopParams]


@dataclass(frozen=True)
class CorParameter:
    """The old parameter of a CoR effect (see
    :class:`~hybridtable.effects.effect.EffectParameter`, which it becomes)."""

    name: str
    unit: str
    null: float
    lower: float
    upper: float
    scale: float
    log: bool = False
    quantity: str = ""

    def as_parameter(self) -> EffectParameter:
        """The same parameter as an :class:`EffectParameter`."""
        return EffectParameter(
            self.name,
            self.unit,
            self.name,
            self.lower,
            self.upper,
            self.scale,
            self.null,
            log=self.log,
            quantity=self.quantity,
        )


@dataclass(frozen=True)
class CorEffect:
    """The old CoR effect: a change of the stated loop (see :func:`as_effect`)."""

    name: str
    description: str
    parameters: tuple[CorParameter, ...]
    apply: Apply


def _conditions(p: HybridLoopParams) -> SimpleNamespace:
    """The conditions a loop states, by the fields of a CoR table's
    :class:`~hybridtable.explain.conditions.Conditions` (what an old ``apply``
    was given)."""
    return SimpleNamespace(
        contact_stiffness_n_per_m=p.contact_stiffness_n_per_m,
        contact_frequency_hz=p.contact_frequency_hz,
        initial_velocity_m_per_s=p.initial_velocity_m_per_s,
        sensor_delay_s=p.sensor_delay_s,
        table_response_hz=p.table_response_hz,
        table_damping_ratio=p.table_damping_ratio,
        lead_time_s=p.beliefs()["lead_time_s"],
        sample_rate_hz=None,
        spacecraft_mass_kg=p.spacecraft_mass_kg,
        lead_s=p.beliefs()["lead_time_s"],
    )


def as_effect(old: CorEffect) -> Effect:
    """``old`` as an :class:`~hybridtable.effects.effect.Effect` of the rig computer
    (``stage="closed_loop"``), tried by ``explain`` unless named."""
    if isinstance(old, Effect):
        return old
    if not isinstance(old, CorEffect):
        raise ParameterError(f"a CoR effect must be an Effect, got {type(old).__name__}")

    def apply(spec, values, scale):
        return spec.with_loop(lambda p: old.apply(_conditions(p), p, values))

    return Effect(
        old.name,
        old.description,
        tuple(p.as_parameter() for p in old.parameters),
        Signature(("v_des_m_per_s",), ("compression", "restitution"), old.description),
        apply,
        stage="closed_loop",
        default_for=("explain",),
    )
