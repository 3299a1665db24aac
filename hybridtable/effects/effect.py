"""One effect: a physical law the nominal rig model may be missing, declared once.

An :class:`Effect` is a change of the rig model, expressed as a change of a
:class:`~hybridtable.effects.spec.ModelSpec`, with named parameters
(:class:`EffectParameter`: unit, bounds, typical change, the null value at
which the effect vanishes) and the signature it leaves in recorded runs. Both
front ends use the same effect:

- ``diagnose`` and ``compare --add`` fit it to recorded runs: the spec's
  systems are replayed against the record (``stage="replay"``), or, for an
  effect of the rig computer (``stage="closed_loop"``), run closed loop;
- ``explain`` fits it to a table of CoRs: each row's loop is run through one
  contact under the spec (:meth:`~hybridtable.effects.spec.ModelSpec.realize`:
  the fast engine where every change is a loop parameter, the Drake diagram
  otherwise);
- on 6-DoF runs (``simulate6 --record --add``, ``compare --add`` of a
  ``hybridtable-run6/1`` run), its ``apply6`` changes the six-axis rig's
  physical part (:class:`~hybridtable.six_dof.physics6.DockingPhysics`): the
  same law where it acts along the contact's normal (a stiffer contact, a
  longer delay), and the effects only a six-axis rig has (friction across the
  face, a turned sensor frame, the table's axes turned). An effect has
  ``apply``, ``apply6`` or both (:attr:`Effect.loops`).

The built-in library is :mod:`hybridtable.effects.library` (one module per
effect); :mod:`hybridtable.effects.registry` holds it and the users' effects.
``default_for`` names the front ends that try an effect when the user names
none (each keeps the set its studies were validated on; a user's effect is
tried by both).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError

__all__ = ["STAGES", "FRONT_ENDS", "EffectParameter", "ParameterAt", "Signature", "Effect"]


#: Where an effect is seen: in the replay of the physical part, or only in
#: the closed loop.
STAGES: tuple[str, ...] = ("replay", "closed_loop")

#: The front ends that fit effects: to recorded runs, to a table of CoRs.
FRONT_ENDS: tuple[str, ...] = ("diagnose", "explain")


Bound = float | Callable[[RigScale], float]


def _value(bound: Bound, scale: RigScale) -> float:
    return float(bound(scale)) if callable(bound) else float(bound)


@dataclass(frozen=True)
class EffectParameter:
    """A parameter of an effect.

    Parameters
    ----------
    name : str
        Name with its unit (``damping_n_s_per_m``).
    unit : str
        Unit, for reports (``"N s/m"``; ``"1"`` for a pure number).
    description : str
    lower, upper : float or callable
        Bounds of the fit (a callable gets the :class:`RigScale`).
    scale : float or callable
        A typical change (the fit's unit step).
    null : float or callable or None
        The value at which the effect vanishes (``None``: no such value, e.g.
        the frequency of a mode).
    initial : float or callable or None
        Start of the fit (default: ``null``, else the middle of the bounds).
    log : bool
        A ratio, fitted in its logarithm: ``scale`` is then a typical change
        of ``ln value`` (``lower`` > 0).
    quantity : str
        The loop quantity it changes, in words (``"delay"``, ``"f_con"``):
        ``explain`` states the combinations a CoR table identifies in these.
    """

    name: str
    unit: str
    description: str
    lower: Bound
    upper: Bound
    scale: Bound
    null: Bound | None = None
    initial: Bound | None = None
    log: bool = False
    quantity: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ParameterError(f"parameter name {self.name!r} must be snake_case")
        if self.log and not callable(self.lower) and not float(self.lower) > 0.0:
            raise ParameterError(f"{self.name}: a log parameter needs lower > 0")
        if not callable(self.scale) and not float(self.scale) > 0.0:
            raise ParameterError(f"{self.name}: scale must be > 0")
        fixed = [b for b in (self.lower, self.null, self.upper) if b is not None]
        if len(fixed) == 3 and not any(callable(b) for b in fixed):
            if not float(self.lower) <= float(self.null) <= float(self.upper):
                raise ParameterError(
                    f"{self.name}: null {self.null} is outside [{self.lower}, {self.upper}]"
                )

    def bounds(self, scale: RigScale) -> tuple[float, float]:
        return _value(self.lower, scale), _value(self.upper, scale)

    def typical(self, scale: RigScale) -> float:
        return _value(self.scale, scale)

    def null_value(self, scale: RigScale) -> float | None:
        return None if self.null is None else _value(self.null, scale)

    def start(self, scale: RigScale) -> float:
        if self.initial is not None:
            return _value(self.initial, scale)
        if self.null is not None:
            return _value(self.null, scale)
        lo, hi = self.bounds(scale)
        return 0.5 * (lo + hi)

    def value_at(self, u: float, scale: RigScale, origin: float | None = None) -> float:
        """The value at the fit's coordinate ``u``: ``origin + u typical``, or
        ``origin e^(u typical)`` for a log parameter (``origin``: default the
        null value, else the start)."""
        origin = self._origin(scale) if origin is None else origin
        step = self.typical(scale)
        return origin * math.exp(u * step) if self.log else origin + u * step

    def coordinate(self, value: float, scale: RigScale, origin: float | None = None) -> float:
        """The fit's coordinate of ``value`` (inverse of :meth:`value_at`)."""
        origin = self._origin(scale) if origin is None else origin
        step = self.typical(scale)
        return math.log(value / origin) / step if self.log else (value - origin) / step

    def _origin(self, scale: RigScale) -> float:
        null = self.null_value(scale)
        return self.start(scale) if null is None else null

    def at(self, scale: RigScale) -> ParameterAt:
        """The parameter's numbers at ``scale``."""
        lower, upper = self.bounds(scale)
        return ParameterAt(self, scale, self._origin(scale), lower, upper, self.typical(scale))


@dataclass(frozen=True)
class ParameterAt:
    """An :class:`EffectParameter` with its numbers at one rig's scale.

    ``null`` is the value at the fit's origin (the null value, else the start);
    ``scale`` its typical change (the fit's unit step,
    :class:`~hybridtable.effects.fitting.Coordinates`).
    """

    parameter: EffectParameter
    rig: RigScale
    null: float
    lower: float
    upper: float
    scale: float

    @property
    def name(self) -> str:
        return self.parameter.name

    @property
    def unit(self) -> str:
        return self.parameter.unit

    @property
    def log(self) -> bool:
        return self.parameter.log

    @property
    def quantity(self) -> str:
        return self.parameter.quantity


@dataclass(frozen=True)
class Signature:
    """Where an effect shows: residual channels, phases, and in words."""

    channels: tuple[str, ...]
    phases: tuple[str, ...]
    text: str


Apply = Callable[[ModelSpec, Mapping[str, float], RigScale], ModelSpec]
#: ``apply6(physics, values, scale) -> physics`` on a
#: :class:`~hybridtable.six_dof.physics6.DockingPhysics`.
Apply6 = Callable[[Any, Mapping[str, float], RigScale], Any]


Starts = Callable[[RigScale, Sequence[Mapping[str, np.ndarray]]], list[dict[str, float]]]


@dataclass(frozen=True)
class Effect:
    """A candidate physical effect.

    Parameters
    ----------
    name : str
    description : str
    parameters : tuple of EffectParameter
        One or two (the fits stay cheap and identifiable).
    signature : Signature
    apply : callable or None
        ``apply(spec, values, scale) -> spec``: the 1-D model with the effect at
        the parameter values ``values`` (a mapping name -> value); None for an
        effect only a six-axis rig has.
    stage : {"replay", "closed_loop"}
        Where the effect is seen (and fitted).
    touches : tuple of str
        What the effect changes (e.g. ``"contact.stiffness"``); two effects
        that touch the same thing are not combined.
    starts : callable, optional
        ``starts(scale, residuals) -> [values, ...]``: extra starting points
        of the fit, from the nominal residuals (``residuals[i]`` has
        ``"time_s"``, ``"f_mea_n"``, ``"p_act_m"`` of run ``i``).
    separation_hint : str
        What kind of run tells the effect apart from look-alikes.
    default_for : tuple of str
        The front ends (:data:`FRONT_ENDS`) that try the effect when the user
        names none; any front end fits it when named.
    apply6 : callable or None
        ``apply6(physics, values, scale) -> physics``: the six-axis rig's
        physical part with the effect (:mod:`hybridtable.six_dof.physics6`);
        None for an effect of the 1-D loop only.
    """

    name: str
    description: str
    parameters: tuple[EffectParameter, ...]
    signature: Signature
    apply: Apply | None = None
    stage: str = "replay"
    touches: tuple[str, ...] = ()
    starts: Starts | None = None
    separation_hint: str = ""
    default_for: tuple[str, ...] = FRONT_ENDS
    apply6: Apply6 | None = None

    def __post_init__(self) -> None:
        if not self.name or not self.name.replace("_", "").isalnum():
            raise ParameterError(f"effect name must be a word (got {self.name!r})")
        if self.stage not in STAGES:
            raise ParameterError(f"effect {self.name}: stage must be one of {', '.join(STAGES)}")
        if not self.parameters:
            raise ParameterError(f"effect {self.name}: needs at least one parameter")
        if self.apply is None and self.apply6 is None:
            raise ParameterError(f"effect {self.name}: needs apply (1-D), apply6 (6-DoF) or both")
        if self.apply is None and self.default_for:
            raise ParameterError(
                f"effect {self.name}: default_for names 1-D front ends, but it has no apply"
            )
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ParameterError(f"effect {self.name}: duplicate parameter names")
        object.__setattr__(self, "touches", tuple(self.touches) or (f"effect.{self.name}",))
        unknown = set(self.default_for) - set(FRONT_ENDS)
        if unknown:
            raise ParameterError(
                f"effect {self.name}: default_for must name {' or '.join(FRONT_ENDS)} "
                f"(got {', '.join(sorted(unknown))})"
            )

    @property
    def loops(self) -> tuple[str, ...]:
        """Where it can be used: ``"1-D"`` (``apply``), ``"6-DoF"`` (``apply6``)."""
        return ("1-D",) * (self.apply is not None) + ("6-DoF",) * (self.apply6 is not None)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    def parameter(self, name: str) -> EffectParameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise ParameterError(
            f"effect {self.name} has no parameter {name!r} "
            f"(its parameters: {', '.join(self.parameter_names)})"
        )

    def start(self, scale: RigScale) -> dict[str, float]:
        return {p.name: p.start(scale) for p in self.parameters}

    def fit_starts(
        self, scale: RigScale, residuals: Sequence[Mapping[str, np.ndarray]]
    ) -> list[dict[str, dict[str, float]]]:
        """Extra starting points of this effect's fit (its :attr:`starts`, from
        the nominal residuals ``residuals``), as fit starts ``{name: values}``."""
        if self.starts is None:
            return []
        return [{self.name: s} for s in self.starts(scale, residuals)]

    def at_bounds(self, values: Mapping[str, float], scale: RigScale) -> list[str]:
        """The parameters of ``values`` (a fit's) at a bound of theirs (to 1e-6
        of the range), in words: an effect whose fit ends on its boundary
        wants to be something it cannot be, and may stand in for another."""
        out = []
        for p in self.parameters:
            if p.name not in values:
                continue
            lo, hi = p.bounds(scale)
            v, tol = float(values[p.name]), 1e-6 * (hi - lo)
            if abs(v - lo) <= tol or abs(v - hi) <= tol:
                out.append(f"{p.name} at its bound {v:.4g}")
        return out

    def null_values(self, scale: RigScale) -> dict[str, float] | None:
        """Parameter values at which the effect vanishes (None if it has none)."""
        out = {p.name: p.null_value(scale) for p in self.parameters}
        return None if any(v is None for v in out.values()) else out

    def check_values(self, values: Mapping[str, float], scale: RigScale) -> dict[str, float]:
        """``values`` completed with the start values, checked against the bounds.

        Raises
        ------
        ParameterError
            Naming an unknown parameter or a value out of bounds.
        """
        out = self.start(scale)
        for name, value in values.items():
            p = self.parameter(name)
            lo, hi = p.bounds(scale)
            v = float(value)
            if not (math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(
                    f"{self.name}: {name} = {value} out of bounds [{lo:.6g}, {hi:.6g}] {p.unit}"
                )
            out[name] = v
        return out

    def conflicts_with(self, other: Effect) -> bool:
        return self is other or bool(set(self.touches) & set(other.touches))
