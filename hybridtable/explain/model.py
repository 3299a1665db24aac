"""The CoR a rig gives under a set of effects: the loop's fast engine, one run per row.

ln CoR of a row is the loop its conditions state
(:meth:`~hybridtable.explain.conditions.Conditions.loop_params`), changed by
each effect in turn, run by :func:`hybridtable.loop.fast.simulate_fast` (the
Drake diagram's CoR to its integrator's error, in milliseconds). On a sampled
rig computer the delay is a whole number of ticks; a delay between two (an
extra delay being fitted) takes ln CoR interpolated linearly between them. A
loop that diverges or never lets go gets :data:`FAILED_LN_COR`, so a fit is
pushed away from it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import lru_cache

import numpy as np

from hybridtable.errors import ParameterError, SimulationError
from hybridtable.explain.conditions import Conditions
from hybridtable.explain.effects import CorEffect, CorParameter
from hybridtable.loop.fast import simulate_fast
from hybridtable.loop.params import HybridLoopParams

__all__ = ["FAILED_LN_COR", "Case", "loop_of", "ln_cor", "CorModel"]

#: ln CoR given to a loop that diverges or does not let go (CoR e^1.5 = 4.5).
FAILED_LN_COR = 1.5

#: A row to predict: (compensator, stated conditions).
Case = tuple[str, Conditions]


def loop_of(
    case: Case, effects: Sequence[CorEffect], values: Mapping[str, float]
) -> HybridLoopParams:
    """The true loop of ``case`` under ``effects`` with parameter ``values``, with a
    continuous rig computer: an effect may move the delay between two ticks of the
    conditions' ``sample_rate_hz``, which :func:`ln_cor` then interpolates."""
    compensator, conditions = case
    params = conditions.loop_params(compensator).with_(sample_rate_hz=None)
    for effect in effects:
        params = effect.apply(conditions, params, values)
    return params


@lru_cache(maxsize=200_000)
def _ln_cor_of(params: HybridLoopParams) -> float:
    try:
        return math.log(simulate_fast(params).cor)
    except (SimulationError, ParameterError, ValueError, ZeroDivisionError):
        return FAILED_LN_COR


def _ln_cor_sampled(params: HybridLoopParams, sample_rate_hz: float) -> float:
    h = 1.0 / sample_rate_hz
    ticks = params.sensor_delay_s / h
    params = params.with_(sensor_delay_s=0.0, sample_rate_hz=sample_rate_hz)
    low = math.floor(ticks + 1e-9)
    frac = ticks - low
    if frac < 1e-6:
        return _ln_cor_of(params.with_(sensor_delay_s=low * h))
    a = _ln_cor_of(params.with_(sensor_delay_s=low * h))
    b = _ln_cor_of(params.with_(sensor_delay_s=(low + 1) * h))
    return (1.0 - frac) * a + frac * b


def ln_cor(params: HybridLoopParams, sample_rate_hz: float | None = None) -> float:
    """ln CoR of one loop (:data:`FAILED_LN_COR` if it diverges or never lets go),
    on a rig computer at ``sample_rate_hz`` (None: ``params``' own)."""
    rate = sample_rate_hz or params.sample_rate_hz
    if rate is not None:
        return _ln_cor_sampled(params.with_(sample_rate_hz=None), rate)
    return _ln_cor_of(params)


class CorModel:
    """ln CoR of cases under a fixed list of effects, as a function of their parameters.

    Parameters
    ----------
    effects : sequence of CorEffect
        The effects, applied in this order.

    Notes
    -----
    The parameters are handled in the fit's coordinates ``u`` (``u = 0``: every
    effect null; one unit: one ``scale`` of the parameter, see
    :class:`~hybridtable.explain.effects.CorParameter`).
    """

    def __init__(self, effects: Sequence[CorEffect]) -> None:
        self.effects = tuple(effects)
        self.parameters: tuple[CorParameter, ...] = tuple(
            p for e in self.effects for p in e.parameters
        )

    @property
    def names(self) -> list[str]:
        """The effects' names."""
        return [e.name for e in self.effects]

    def values(self, u: Sequence[float]) -> dict[str, float]:
        """Parameter name -> value at coordinates ``u``."""
        return {p.name: p.to_unit(float(x)) for p, x in zip(self.parameters, u, strict=True)}

    def coordinates(self, values: Mapping[str, float]) -> np.ndarray:
        """The coordinates ``u`` of parameter ``values`` (missing: null)."""
        return np.array([p.from_value(values.get(p.name, p.null)) for p in self.parameters])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of ``u``."""
        lo, hi = (
            zip(*(p.bounds() for p in self.parameters), strict=True)
            if self.parameters
            else ((), ())
        )
        return np.array(lo, float), np.array(hi, float)

    def predict(self, cases: Sequence[Case], u: Sequence[float]) -> np.ndarray:
        """ln CoR of each case at coordinates ``u``."""
        values = self.values(u)
        return np.array(
            [ln_cor(loop_of(c, self.effects, values), c[1].sample_rate_hz) for c in cases]
        )

    def jacobian(
        self,
        cases: Sequence[Case],
        u: Sequence[float],
        step: float = 0.05,
        columns: Sequence[int] | None = None,
    ) -> np.ndarray:
        """d ln CoR / d u of each case (central differences, one-sided at a bound),
        for the coordinates ``columns`` (default: all)."""
        u = np.asarray(u, float)
        lo, hi = self.bounds()
        cols = []
        for j in range(len(u)) if columns is None else columns:
            up, dn = u.copy(), u.copy()
            up[j] = min(u[j] + step, hi[j])
            dn[j] = max(u[j] - step, lo[j])
            cols.append((self.predict(cases, up) - self.predict(cases, dn)) / (up[j] - dn[j]))
        return np.column_stack(cols) if cols else np.zeros((len(cases), 0))
