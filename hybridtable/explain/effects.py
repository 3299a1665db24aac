"""What may make a rig's CoR differ from what its stated conditions predict, and the registry.

A :class:`CorEffect` changes the loop the conditions state
(:meth:`~hybridtable.explain.conditions.Conditions.loop_params`) into the rig's
true loop, by named parameters with units, bounds and a null value at which the
effect vanishes. The built-ins are in :mod:`hybridtable.explain.library`; the
registry (:mod:`hybridtable.explain.registry`) holds them and the plug-ins.

Unlike :mod:`hybridtable.diagnosis.effects` (which changes the rig's Drake
back-ends and is fitted to recorded signals), these act on the loop's
parameters: a table of CoRs is a few numbers, and the loop's fast engine
(:mod:`hybridtable.loop.fast`) gives each in a few milliseconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from hybridtable.errors import ParameterError
from hybridtable.explain.conditions import Conditions
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "CorParameter",
    "CorEffect",
]

#: Applies an effect: (stated conditions, the loop so far, the effect's values) -> the loop.
Apply = Callable[[Conditions, HybridLoopParams, Mapping[str, float]], HybridLoopParams]


@dataclass(frozen=True)
class CorParameter:
    """One parameter of a :class:`CorEffect`.

    Parameters
    ----------
    name : str
        snake_case with the unit (``extra_delay_s``).
    unit : str
        The unit, ``"1"`` for a ratio.
    null : float
        The value at which the effect vanishes.
    lower, upper : float
        The physically plausible range the fit stays in.
    scale : float
        A typical change, in the parameter's unit (the fit's step and the
        identifiability analysis's unit).
    log : bool
        A ratio, fitted in its logarithm (``lower`` > 0).
    quantity : str
        The loop quantity it changes, in words (``"delay"``, ``"f_con"``): the
        identifiable combinations are stated in these.
    """

    name: str
    unit: str
    null: float
    lower: float
    upper: float
    scale: float
    log: bool = False
    quantity: str = ""

    def __post_init__(self) -> None:
        if not self.lower <= self.null <= self.upper:
            raise ParameterError(
                f"{self.name}: null {self.null} is outside [{self.lower}, {self.upper}]"
            )
        if self.log and self.lower <= 0.0:
            raise ParameterError(f"{self.name}: a log parameter needs lower > 0")
        if not self.scale > 0.0:
            raise ParameterError(f"{self.name}: scale must be > 0")

    def to_unit(self, u: float) -> float:
        """The value at the fit's coordinate ``u`` (``null + u scale``, or ``null e^(u scale)``)."""
        return self.null * math.exp(u * self.scale) if self.log else self.null + u * self.scale

    def from_value(self, value: float) -> float:
        """The fit's coordinate of ``value`` (inverse of :meth:`to_unit`)."""
        if self.log:
            return math.log(value / self.null) / self.scale
        return (value - self.null) / self.scale

    def bounds(self) -> tuple[float, float]:
        """The range in the fit's coordinate."""
        return self.from_value(self.lower), self.from_value(self.upper)


@dataclass(frozen=True)
class CorEffect:
    """A change of the loop that a CoR table may reveal.

    Parameters
    ----------
    name : str
        snake_case.
    description : str
        One sentence: what is physically different.
    parameters : tuple of CorParameter
        Its parameters.
    apply : callable
        ``apply(conditions, params, values) -> params``: the loop with the effect.
    """

    name: str
    description: str
    parameters: tuple[CorParameter, ...]
    apply: Apply

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ParameterError(f"effect name {self.name!r} must be snake_case")
        if not self.parameters:
            raise ParameterError(f"effect {self.name!r} has no parameters")

    @property
    def null_values(self) -> dict[str, float]:
        """Parameter -> its null value."""
        return {p.name: p.null for p in self.parameters}
