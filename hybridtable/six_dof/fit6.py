"""Fit 6-DoF effects to recorded 6-DoF runs: ``compare --add`` on
``hybridtable-run6/1`` runs.

The residual is the replay's (:func:`~hybridtable.six_dof.replay6.replay_run6`
through the effects' :class:`~hybridtable.six_dof.physics6.DockingPhysics`):
every compared component (:data:`~hybridtable.six_dof.compare6.COMPONENTS`)
of every tick of every run, in that component's noise levels. The fit is the
effect core's (:func:`~hybridtable.effects.fitting.fit_values`, with the 1-D
replay's settings, :data:`~hybridtable.effects.fitting.REPLAY_LEAST_SQUARES`),
in each parameter's coordinate; standard errors from the same core. The
effects' bounds are taken at the first run's scenario
(:func:`~hybridtable.six_dof.physics6.rig_scale`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from hybridtable.effects.effect import Effect
from hybridtable.effects.fitting import (
    REPLAY_LEAST_SQUARES,
    Coordinates,
    Values,
    fit_values,
    standard_errors,
)
from hybridtable.effects.selection import Block
from hybridtable.errors import ParameterError
from hybridtable.six_dof.compare6 import COMPONENTS, noise_levels_of, replay_residuals
from hybridtable.six_dof.physics6 import NOMINAL_PHYSICS, DockingPhysics, physics_with, rig_scale
from hybridtable.six_dof.run6 import Run6

__all__ = ["Fit6", "fit_runs6", "blocks", "residual_probe"]


@dataclass
class Fit6:
    """Effects fitted to 6-DoF runs.

    Attributes
    ----------
    values : dict
        Effect -> parameter -> value (SI units; the given ones too).
    std : dict
        Effect -> parameter -> standard error (None: given, or not identifiable).
    fitted : dict
        Effect -> the parameters fitted (the others were given).
    chi2_before, chi2_after : float
        Sum of squared replay residuals (noise levels) without and with the effects.
    n_residuals : int
    evaluations : int
        Replays of every run the fit took.
    success : bool
        Every least-squares polish converged.
    physics : DockingPhysics
        The rig's physical part with the fitted effects.
    residuals : ndarray
        The replay residuals with them (noise levels; run after run, each
        component's ticks in turn: :func:`blocks`).
    """

    values: Values
    std: dict[str, dict[str, float | None]]
    fitted: dict[str, tuple[str, ...]]
    chi2_before: float
    chi2_after: float
    n_residuals: int
    evaluations: int
    success: bool
    physics: DockingPhysics
    residuals: np.ndarray

    def to_dict(self) -> dict:
        return {
            "values": self.values,
            "std": self.std,
            "fitted": {k: list(v) for k, v in self.fitted.items()},
            "chi2_before": self.chi2_before,
            "chi2_after": self.chi2_after,
            "n_residuals": self.n_residuals,
            "evaluations": self.evaluations,
            "success": self.success,
            "physics": self.physics.to_dict(),
        }


class _CannotAct(RuntimeError):
    """An effect's values the rig cannot take (a ParameterError, which the
    core's fit would take for a failed polish: it catches ValueError)."""


def blocks(runs: Sequence[Run6], residuals: np.ndarray) -> list[Block]:
    """The residuals (:func:`~hybridtable.six_dof.compare6.replay_residuals`
    of each run in turn) as one block per run and component, for the
    information criterion (:mod:`hybridtable.effects.selection`; in noise
    levels: the noise is stated)."""
    out, start = [], 0
    for run in runs:
        for _ in COMPONENTS:
            part = residuals[start : start + run.n]
            out.append(Block(float(part @ part), run.n))
            start += run.n
    return out


def residual_probe(runs: Sequence[Run6], residuals: np.ndarray) -> list[dict[str, np.ndarray]]:
    """The nominal residuals as an effect's ``starts`` reads them
    (:attr:`~hybridtable.effects.effect.Effect.starts`): one mapping per run
    and axis, ``"f_mea_n"`` the wrench component's and ``"p_act_m"`` the pose
    component's residual on it (in noise levels: the spectrum's peak, not its
    unit, is read), ``"time_s"`` the ticks' times."""
    out, start, m = [], 0, len(COMPONENTS)
    for run in runs:
        part = residuals[start : start + m * run.n].reshape(m, run.n)
        start += m * run.n
        time_s = run.params.sample_period_s * np.arange(run.n)
        half = m // 2  # the wrench's components, then the pose's
        out += [
            {"time_s": time_s, "f_mea_n": part[j], "p_act_m": part[half + j]} for j in range(half)
        ]
    return out


def fit_runs6(
    runs: Sequence[Run6],
    effects: Sequence[tuple[Effect, Mapping[str, float]]],
    start: Mapping[str, Mapping[str, float]] | None = None,
    base: DockingPhysics | None = None,
) -> Fit6:
    """Fit the parameters of ``effects`` not given (each ``(effect, given
    values)``) to ``runs`` (see the module); ``start``: an informed start
    (effect -> parameter -> value, e.g. an earlier fit's), besides the null;
    ``base``: the rig's physical part the effects change (default the
    scenario's; e.g. a model file's), which ``chi2_before`` is of too.

    Raises
    ------
    ParameterError
        For an effect without ``apply6`` (the 1-D loop's only), or two effects
        of one name.
    SimulationError
        If a replay fails.
    """
    if not runs:
        raise ParameterError("no runs to fit to")
    names = [e.name for e, _ in effects]
    if len(set(names)) != len(names):
        raise ParameterError(f"an effect is named twice: {', '.join(names)}")
    for effect, _ in effects:
        if effect.apply6 is None:
            raise ParameterError(
                f"effect {effect.name} acts on the 1-D loop only (it has no apply6 for a "
                "six-axis rig)"
            )
    scale = rig_scale(runs[0].params)
    by_name = {e.name: e for e, _ in effects}
    given: Values = {}
    for effect, values in effects:
        checked = effect.check_values(values, scale)  # bounds, names
        given[effect.name] = {k: checked[k] for k in values}
    origin: Values = {}
    for effect, _ in effects:
        origin[effect.name] = {
            p.name: given[effect.name].get(p.name, p.at(scale).null) for p in effect.parameters
        }
    free = tuple(
        (e.name, p) for e, _ in effects for p in e.parameters if p.name not in given[e.name]
    )
    evaluations = 0
    levels = [noise_levels_of(r) for r in runs]  # the runs' own: once, not each replay

    def residual(values: Values) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        try:
            physics = physics_with([(by_name[n], values[n]) for n in names], scale, base)
            return np.concatenate(
                [replay_residuals(r, physics, n) for r, n in zip(runs, levels, strict=True)]
            )
        except ParameterError as err:  # not a failed polish: the effect cannot act here
            raise _CannotAct(str(err)) from None

    base = NOMINAL_PHYSICS if base is None else base
    r0 = np.concatenate([replay_residuals(r, base, n) for r, n in zip(runs, levels, strict=True)])
    space = Coordinates(free, scale, origin)
    starts = [start] if start else []
    probe = residual_probe(runs, r0)
    for effect, values in effects:  # its data-driven starts (a mode's spectral peak)
        if len(values) < len(effect.parameters):
            starts += effect.fit_starts(scale, probe)
    try:
        solution = fit_values(residual, space, starts, REPLAY_LEAST_SQUARES, held=given)
        r1 = residual(solution.values)
        std = standard_errors(residual, solution.coordinates, r1, REPLAY_LEAST_SQUARES.diff_step)
    except _CannotAct as err:
        raise ParameterError(f"{' + '.join(names)} cannot act on this rig: {err}") from None
    return Fit6(
        values=solution.values,
        std=std,
        fitted={n: tuple(p.name for m, p in free if m == n) for n in names},
        chi2_before=float(r0 @ r0),
        chi2_after=float(r1 @ r1),
        n_residuals=int(r1.size),
        evaluations=evaluations,
        success=solution.success,
        physics=physics_with([(by_name[n], solution.values[n]) for n in names], scale, base),
        residuals=r1,
    )
