"""The CoR a rig gives under a set of effects: one run of the loop per row.

ln CoR of a row is the loop its conditions state
(:meth:`~hybridtable.explain.conditions.Conditions.loop_params`) under the
effects' :class:`~hybridtable.effects.spec.ModelSpec`
(:meth:`~hybridtable.effects.spec.ModelSpec.realize`). Where every change is
one of the loop's parameters, :func:`hybridtable.loop.fast.simulate_fast` runs
it (the Drake diagram's CoR to its integrator's error, in milliseconds); on a
sampled rig computer a delay between two ticks (stated, or an extra delay being
fitted) reads the two neighbouring samples mixed, as the sampled sensor of
every engine does (``docs/run-format.md``). Any other change (a nonlinear
contact law, a filter, a mode, a user's system) runs through the Drake diagram
with the systems that carry it (about 0.1 s a row). A loop that diverges or never lets go gets
:data:`FAILED_LN_COR`, so a fit is pushed away from it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from hybridtable.effects.effect import Effect, ParameterAt
from hybridtable.effects.fitting import Coordinates, Values, jacobian
from hybridtable.effects.registry import build_spec
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError, SimulationError
from hybridtable.explain.conditions import Conditions
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.fast import simulate_fast
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import run_loop
from hybridtable.measurement.rig import RigPhysics

__all__ = [
    "FAILED_LN_COR",
    "JACOBIAN_STEP",
    "Case",
    "EffectAt",
    "table_scale",
    "loop_of",
    "ln_cor",
    "CorModel",
]

#: ln CoR given to a loop that diverges or does not let go (CoR e^1.5 = 4.5).
FAILED_LN_COR = 1.5

#: The period an effect's scale takes for a continuous rig computer (s): a delay's
#: typical change is then half of it, 1 ms; finer steps fall into the continuous
#: engine's ln CoR jitter (~5e-5: its delay line's period moves with the delay),
#: which the fits' and the sensitivities' finite differences would read.
CONTINUOUS_REFERENCE_PERIOD_S = 2e-3

#: Step of the sensitivities d ln CoR / d u (coordinate units: a twentieth of a
#: typical change).
JACOBIAN_STEP = 0.05

#: A row to predict: (compensator, stated conditions).
Case = tuple[str, Conditions]


@dataclass(frozen=True)
class EffectAt:
    """An :class:`~hybridtable.effects.effect.Effect` as a CoR table fits it: its
    parameters' numbers at the table's scale (:func:`table_scale`)."""

    effect: Effect
    rig: RigScale

    @property
    def name(self) -> str:
        return self.effect.name

    @property
    def description(self) -> str:
        return self.effect.description

    @cached_property
    def parameters(self) -> tuple[ParameterAt, ...]:
        return tuple(p.at(self.rig) for p in self.effect.parameters)

    def probe_values(self) -> dict[str, float]:
        """Every parameter one typical change from its null, within its bounds: a
        point where the effect acts (at its null values it vanishes)."""
        return CorModel((self,)).values(np.ones(len(self.parameters)))

    def spec(self, values: Mapping[str, float], base: ModelSpec | None = None) -> ModelSpec:
        """``base`` (default nominal) with the effect at ``values`` (missing: null);
        at its null values the effect vanishes, and ``base`` is returned as it is
        (the loop then runs on the fast engine where ``base`` does)."""
        own = {p.name: values.get(p.name, p.null) for p in self.parameters}
        nulls = self.effect.null_values(self.rig)
        if nulls is not None and all(own[n] == v for n, v in nulls.items()):
            return base or ModelSpec()
        return build_spec([(self.effect, own)], self.rig, base)


def table_scale(cases: Sequence[Case]) -> RigScale:
    """The scale the effects' bounds are taken at: the first row's loop at the
    table's fastest approach, with the rig computer's period; a continuous
    computer has no tick, and takes :data:`CONTINUOUS_REFERENCE_PERIOD_S`."""
    params = cases[0][1].loop_params(cases[0][0])
    v = max(c.initial_velocity_m_per_s for _, c in cases)
    period = params.sample_period_s or CONTINUOUS_REFERENCE_PERIOD_S
    return RigScale.from_params(params.with_(initial_velocity_m_per_s=v), period)


def loop_of(
    case: Case, effects: Sequence[EffectAt], values: Mapping[str, float]
) -> tuple[HybridLoopParams, RigPhysics | None]:
    """The true loop of ``case`` under ``effects`` with parameter ``values``.

    Returns its parameters and, when a change is not one of them, the systems
    that carry it (:meth:`~hybridtable.effects.spec.ModelSpec.realize`).
    """
    compensator, conditions = case
    spec = ModelSpec()
    for effect in effects:
        spec = effect.spec(values, spec)
    return spec.realize(conditions.loop_params(compensator))


def _ln_cor_systems(params: HybridLoopParams, physics: RigPhysics) -> float:
    systems = {}
    for part in ("table", "contact", "sensor"):
        if getattr(physics, part) is not None:
            systems[part] = getattr(physics, f"make_{part}")(params)
    try:
        return math.log(run_loop(build_hybrid_loop(params, **systems)).metrics.cor)
    except (SimulationError, ValueError, ZeroDivisionError):
        return FAILED_LN_COR


@lru_cache(maxsize=200_000)
def _ln_cor_of(params: HybridLoopParams) -> float:
    try:
        return math.log(simulate_fast(params).cor)
    except (SimulationError, ParameterError, ValueError, ZeroDivisionError):
        return FAILED_LN_COR


def ln_cor(params: HybridLoopParams, physics: RigPhysics | None = None) -> float:
    """ln CoR of one loop (:data:`FAILED_LN_COR` if it diverges or never lets go):
    on the fast engine, or with ``physics`` through the Drake diagram with its
    systems."""
    if physics is not None:
        return _ln_cor_systems(params, physics)
    return _ln_cor_of(params)


class CorModel:
    """ln CoR of cases under a fixed list of effects, as a function of their parameters.

    Parameters
    ----------
    effects : sequence of EffectAt
        The effects, applied in this order.

    Notes
    -----
    The parameters are handled in the fit's coordinates ``u`` (``u = 0``: every
    effect null; one unit: one ``scale`` of the parameter, of its logarithm for a
    ratio): :attr:`space`, the one fit's
    :class:`~hybridtable.effects.fitting.Coordinates`.
    """

    def __init__(self, effects: Sequence[EffectAt]) -> None:
        self.effects = tuple(effects)
        self.parameters: tuple[ParameterAt, ...] = tuple(
            p for e in self.effects for p in e.parameters
        )
        #: The fit's coordinates about every effect's null (the one fit's, with
        #: the parameters of a CoR table's scale).
        self.space = Coordinates(
            tuple((e.name, p.parameter) for e in self.effects for p in e.parameters),
            self.effects[0].rig if self.effects else None,
            {e.name: {p.name: p.null for p in e.parameters} for e in self.effects},
        )
        self._systems: dict[tuple, float] = {}

    @property
    def names(self) -> list[str]:
        """The effects' names."""
        return [e.name for e in self.effects]

    def nested(self, values: Mapping[str, float]) -> Values:
        """Parameter -> value as effect -> parameter -> value (missing: left out)."""
        return {
            e.name: {p.name: values[p.name] for p in e.parameters if p.name in values}
            for e in self.effects
        }

    @staticmethod
    def flat(values: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
        """Effect -> parameter -> value as parameter -> value."""
        return {k: x for v in values.values() for k, x in v.items()}

    def values(self, u: Sequence[float]) -> dict[str, float]:
        """Parameter name -> value at coordinates ``u``."""
        return self.flat(self.space.values(u))

    def coordinates(self, values: Mapping[str, float]) -> np.ndarray:
        """The coordinates ``u`` of parameter ``values`` (missing: null)."""
        return self.space.coordinates(self.nested(values))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of ``u``."""
        return self.space.bounds()

    def predict(self, cases: Sequence[Case], u: Sequence[float]) -> np.ndarray:
        """ln CoR of each case at coordinates ``u``."""
        return self.predict_values(cases, self.values(u))

    def predict_values(self, cases: Sequence[Case], values: Mapping[str, float]) -> np.ndarray:
        """ln CoR of each case at parameter ``values`` (missing: null); rows of the
        same conditions are one run (a long table of few conditions costs those)."""
        values, memo = dict(values), {}
        for c in cases:
            if c not in memo:
                memo[c] = self._ln_cor(c, values)
        return np.array([memo[c] for c in cases])

    def _ln_cor(self, case: Case, values: dict[str, float]) -> float:
        try:
            params, physics = loop_of(case, self.effects, values)
        except ParameterError:  # e.g. a lead just above zero, below any a rig states
            return FAILED_LN_COR
        if physics is None:
            return ln_cor(params)
        key = (case, tuple(values.items()))  # the diagram's systems are new each time
        if key not in self._systems:
            self._systems[key] = ln_cor(params, physics=physics)
        return self._systems[key]

    def jacobian(
        self,
        cases: Sequence[Case],
        u: Sequence[float],
        step: float = JACOBIAN_STEP,
        columns: Sequence[int] | None = None,
    ) -> np.ndarray:
        """d ln CoR / d u of each case for the coordinates ``columns`` (default:
        all): :func:`~hybridtable.effects.fitting.jacobian` about ``u``; a
        parameter with no room to move gets a column of zeros."""
        values = self.values(u)
        cols = range(len(self.parameters)) if columns is None else columns
        out = np.zeros((len(cases), len(cols)))
        for k, j in enumerate(cols):
            e = next(e for e in self.effects if self.parameters[j] in e.parameters)
            p = self.parameters[j]
            space = Coordinates(((e.name, p.parameter),), e.rig, {e.name: {p.name: values[p.name]}})
            col = jacobian(
                lambda v, n=e.name: self.predict_values(cases, values | v[n]), space, step
            )
            if col is not None:
                out[:, k] = col[:, 0]
        return out
