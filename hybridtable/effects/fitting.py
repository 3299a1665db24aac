"""One fit of effects to data, for every front end: bounded least squares in each
parameter's coordinate, from the best of several starts, and its standard errors.

A front end (``diagnose``: prewhitened replay residuals of recorded runs;
``explain``: ln CoR rows of a table) gives a function from effect values to a
vector of residuals in noise units; everything else is here:

- :class:`Coordinates`: the space a fit moves in. Parameter ``j`` at ``u_j`` is
  :meth:`~hybridtable.effects.effect.EffectParameter.value_at` from an origin:
  one typical change per unit, of the logarithm for a log parameter, so every
  parameter moves by comparable steps whatever its unit;
- :func:`fit_values`: evaluate the informed starts (the origin, an earlier
  fit, an effect's data-driven starts) and the points of a grid over the
  range, then polish the best informed start (or each, :class:`LeastSquares`)
  and the best grid point with :func:`scipy.optimize.least_squares` (bounded;
  in coordinates centred on the start, or about the origin); the result is
  never worse than the best start; ``success`` says every polish converged;
- :func:`jacobian` and :func:`standard_errors`: the linearized covariance
  ``s^2 (J^T J)^-1`` with ``s^2 = max(1, chi2 / (N - p))``: the residuals are in
  noise units, and a misfit larger than the noise widens the errors rather
  than narrowing them. ``None`` when ``J^T J`` is singular (not identifiable).

The front ends keep only their data, their noise model and their words.
:class:`LeastSquares` holds the optimizer's settings, which depend on what one
residual costs (a replay of a recorded run: 0.1 s; a CoR row on the fast
engine: a millisecond) and on how smooth it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from hybridtable.effects.effect import EffectParameter
from hybridtable.effects.spec import RigScale

__all__ = [
    "Values",
    "LeastSquares",
    "REPLAY_LEAST_SQUARES",
    "Coordinates",
    "Solution",
    "fit_values",
    "jacobian",
    "standard_errors",
]

#: Effect -> parameter -> value (SI units).
Values = dict[str, dict[str, float]]


def copy_values(values: Mapping[str, Mapping[str, float]]) -> Values:
    return {n: dict(v) for n, v in values.items()}


@dataclass(frozen=True)
class LeastSquares:
    """Settings of :func:`scipy.optimize.least_squares` for one kind of data.

    ``max_nfev`` is per free parameter when ``per_parameter``; ``margin`` (in
    coordinate units, at least a thousandth of the range) keeps a start off
    the bounds, where ``xtol``, relative to ``|u|``, would stop it at once.
    ``centred``: the coordinates of a polish are centred on its start (``u = 0``);
    otherwise they stay about the origin, and scipy's finite-difference step,
    ``diff_step`` times ``max(1, |u|)``, grows with the distance from it (a
    coarser step over a residual that is rough at fine scales, as ln CoR of a
    delay on the continuous engine is: its delay line's period moves with the
    delay). ``each_start``: every informed start
    given is polished (the origin only when none is), not only the best of them
    and the origin: where a residual is cheap, a start from earlier fits can
    lead to a better valley than a null point of lower chi2.
    """

    method: str = "trf"
    diff_step: float = 1e-3
    ftol: float = 1e-8
    xtol: float = 1e-5
    gtol: float = 1e-8
    max_nfev: int = 25
    per_parameter: bool = False
    margin: float = 0.0
    centred: bool = True
    each_start: bool = False

    def nfev(self, n_free: int) -> int:
        return self.max_nfev * n_free if self.per_parameter else self.max_nfev


#: The optimizer's settings for replays of recorded runs, 1-D and 6-DoF (each
#: evaluation replays every run: few, coarse steps).
REPLAY_LEAST_SQUARES = LeastSquares(
    method="dogbox", diff_step=1e-2, ftol=1e-5, xtol=1e-4, gtol=1e-8, max_nfev=20
)


@dataclass(frozen=True)
class Coordinates:
    """The coordinates ``u`` of a fit's free parameters about ``origin``
    (every effect's values, the held ones too): ``u = 0`` is the origin."""

    free: tuple[tuple[str, EffectParameter], ...]
    scale: RigScale
    origin: Mapping[str, Mapping[str, float]]

    def centred(self, origin: Mapping[str, Mapping[str, float]]) -> Coordinates:
        """The same parameters about another origin."""
        return Coordinates(self.free, self.scale, origin)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The plausible range of each coordinate."""
        lo, hi = [], []
        for n, p in self.free:
            a, b = p.bounds(self.scale)
            lo.append(p.coordinate(a, self.scale, self.origin[n][p.name]))
            hi.append(p.coordinate(b, self.scale, self.origin[n][p.name]))
        return np.array(lo, float), np.array(hi, float)

    def values(self, u: Sequence[float]) -> Values:
        """The values at ``u`` (each within its bounds)."""
        vals = copy_values(self.origin)
        for (n, p), x in zip(self.free, u, strict=True):
            lo, hi = p.bounds(self.scale)
            value = p.value_at(float(x), self.scale, self.origin[n][p.name])
            vals[n][p.name] = float(np.clip(value, lo, hi))
        return vals

    def coordinates(self, values: Mapping[str, Mapping[str, float]]) -> np.ndarray:
        """The coordinates of ``values`` (a parameter missing: at the origin)."""
        return np.array(
            [
                p.coordinate(
                    values.get(n, {}).get(p.name, self.origin[n][p.name]),
                    self.scale,
                    self.origin[n][p.name],
                )
                for n, p in self.free
            ]
        )


@dataclass
class Solution:
    """The result of :func:`fit_values`."""

    values: Values
    cost: float
    nfev: int
    success: bool
    #: The coordinates about :attr:`values` (``u = 0``) for standard errors.
    coordinates: Coordinates


def _merge(origin: Values, start: Mapping[str, Mapping[str, float]], held) -> Values:
    vals = copy_values(origin)
    for n, v in start.items():
        if n in vals:
            vals[n].update({k: x for k, x in v.items() if k not in held.get(n, {})})
    return vals


def fit_values(
    residual: Callable[[Values], np.ndarray],
    space: Coordinates,
    starts: Sequence[Mapping[str, Mapping[str, float]]] = (),
    settings: LeastSquares = LeastSquares(),
    grid: Sequence[Mapping[str, Mapping[str, float]]] = (),
    held: Mapping[str, Mapping[str, float]] | None = None,
) -> Solution:
    """Fit the free parameters of ``space`` to make ``residual`` small.

    Parameters
    ----------
    residual : callable
        Values -> residuals in noise units (its squares sum to chi2).
    space : Coordinates
        The free parameters and the origin, which is the first start.
    starts : sequence of mappings
        Further informed starts (an earlier fit, an effect's data-driven
        starts; partial: the rest from the origin, ``held`` values kept). The
        one with the lowest chi2, the origin included, is polished by least
        squares (each of them, with ``settings.each_start``).
    grid : sequence of mappings
        Points scanning the range: the best of them is polished too, so that a
        second valley, away from the informed starts, is found.
    settings : LeastSquares
        The optimizer's settings.
    """
    held = held or {}

    def best_of(points) -> list:
        scored = []
        for k, start in enumerate(points):
            vals = _merge(space.origin, start, held)
            r = residual(vals)
            scored.append((float(r @ r), k, vals, r))
        return [min(scored, key=lambda t: (t[0], t[1]))] if scored else []

    if settings.each_start:
        informed = [best_of([s])[0] for s in (starts or [{}])]
    else:
        informed = best_of([{}, *starts])
    chosen = informed + best_of(grid)
    best_cost, _, best_vals, _ = min(chosen, key=lambda t: t[0])
    nfev = (max(len(starts), 1) if settings.each_start else 1 + len(starts)) + len(grid)
    success, polished = True, False
    for _, _, origin, r0 in chosen if space.free else ():
        centred = space.centred(origin) if settings.centred else space
        lo, hi = centred.bounds()
        u0 = np.zeros(len(lo)) if settings.centred else space.coordinates(origin)
        cache: dict[bytes, np.ndarray] = {u0.tobytes(): r0}

        def fun(u: np.ndarray, centred=centred, cache=cache) -> np.ndarray:
            key = u.tobytes()
            if key not in cache:
                cache[key] = residual(centred.values(u))
            return cache[key]

        margin = np.maximum(settings.margin, 1e-3 * (hi - lo)) if settings.margin else 0.0
        x0 = np.clip(u0, lo + margin, hi - margin)
        try:
            sol = least_squares(
                fun,
                x0,
                bounds=(lo, hi),
                method=settings.method,
                diff_step=settings.diff_step,
                x_scale=1.0,
                ftol=settings.ftol,
                xtol=settings.xtol,
                gtol=settings.gtol,
                max_nfev=settings.nfev(len(lo)),
            )
            u, ok, nfev = sol.x, bool(sol.status > 0), nfev + sol.nfev
        except ValueError:  # e.g. non-finite residuals: the start stays as it was
            success = False
            continue
        success = success and ok
        r = fun(u)
        cost = float(r @ r)
        # a polished start replaces an unpolished one it equals; never a worse one
        if cost < best_cost or (cost == best_cost and not polished):
            best_cost, best_vals, polished = cost, centred.values(u), True
    return Solution(best_vals, best_cost, nfev, success, space.centred(best_vals))


def jacobian(
    residual: Callable[[Values], np.ndarray], space: Coordinates, step: float
) -> np.ndarray | None:
    """d residual / d u about ``space``'s origin by central differences of
    ``step`` (one-sided at a bound); None if a parameter has no room to move."""
    lo, hi = space.bounds()
    cols = []
    for j in range(len(space.free)):
        up, dn = np.zeros(len(lo)), np.zeros(len(lo))
        up[j], dn[j] = min(step, hi[j]), max(-step, lo[j])
        if up[j] <= dn[j]:
            return None
        cols.append((residual(space.values(up)) - residual(space.values(dn))) / (up[j] - dn[j]))
    return np.column_stack(cols) if cols else None


def standard_errors(
    residual: Callable[[Values], np.ndarray],
    space: Coordinates,
    r0: np.ndarray,
    step: float,
) -> dict[str, dict[str, float | None]]:
    """Standard errors (SI units) of the free parameters of ``space`` fitted at
    its origin, whose residuals are ``r0`` (see the module doc); every
    parameter not free, and all when they are not identifiable, ``None``."""
    out: dict[str, dict[str, float | None]] = {n: dict.fromkeys(v) for n, v in space.origin.items()}
    jac = jacobian(residual, space, step) if space.free else None
    if jac is None:
        return out
    dof = max(r0.size - len(space.free), 1)
    s2 = max(1.0, float(r0 @ r0) / dof)
    jtj = jac.T @ jac
    if not np.all(np.isfinite(jtj)) or np.linalg.cond(jtj) > 1e14:
        return out
    cov = s2 * np.linalg.inv(jtj)
    for j, (n, p) in enumerate(space.free):
        x = space.origin[n][p.name]
        per_unit = p.typical(space.scale) * (abs(x) if p.log else 1.0)  # d value / d u
        out[n][p.name] = math.sqrt(max(float(cov[j, j]), 0.0)) * per_unit
    return out
