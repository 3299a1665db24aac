"""Fit models of 1-3 effects to a CoR table by least squares in ln CoR, and rank them.

The residual of a row is ``(ln CoR_model - ln CoR_measured) / sigma``, with
``sigma`` the row's noise in ln CoR (its CoR's std over its CoR) and the
model's own error added in quadrature. A model is fitted only when it has
fewer parameters than the table has rows (so that its fit can be tested);
``chi2`` is tested against ``n - p`` degrees of freedom, and models are ranked
by BIC (``chi2 + p ln n``).

Which models are fitted: every single effect (from a grid of starts over its
range); pairs and triples are proposed by the one search
(:func:`~hybridtable.effects.search.propose`), screened by the loop linearized
at the nominal point (bounded linear least squares): the best of each size,
together with the combinations of the best single effects, are fitted on the
loop itself, started from their single effects' fits.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear
from scipy.stats import chi2 as chi2_dist

from hybridtable.effects.fitting import (
    LeastSquares,
    fit_values,
    standard_errors,
)
from hybridtable.effects.search import propose
from hybridtable.effects.selection import bic
from hybridtable.effects.workers import pool_map
from hybridtable.explain.model import JACOBIAN_STEP, Case, CorModel, EffectAt

__all__ = ["ModelFit", "fit_model", "fit_models", "rank_fits"]


@dataclass(frozen=True)
class ModelFit:
    """One model fitted to a table.

    Parameters
    ----------
    effects : tuple of str
        The effects (empty: the stated loop, nothing missing).
    values, std : dict
        Parameter -> fitted value and its standard error (unit of the parameter;
        None when the table cannot determine the parameters).
    predicted_cor : ndarray
        The model's CoR of each row.
    z : ndarray
        Each row's residual in noise units (model - measured).
    chi2 : float
        Sum of ``z**2``.
    dof : int
        Rows minus parameters.
    at_bound : tuple of str
        Parameters that ended on their plausible range's edge.
    """

    effects: tuple[str, ...]
    values: dict[str, float]
    std: dict[str, float | None]
    predicted_cor: np.ndarray
    measured_cor: np.ndarray
    z: np.ndarray
    chi2: float
    dof: int
    at_bound: tuple[str, ...] = ()

    @property
    def n_parameters(self) -> int:
        """Number of fitted parameters."""
        return len(self.values)

    @property
    def bic(self) -> float:
        """chi2 + p ln n (:func:`~hybridtable.effects.selection.bic`)."""
        return bic(self.chi2, self.n_parameters, len(self.z))

    @property
    def aic(self) -> float:
        """chi2 + 2 p."""
        return self.chi2 + 2.0 * self.n_parameters

    @property
    def p_value(self) -> float:
        """P(chi2 >= this | the model is right), with ``dof`` degrees of freedom."""
        return float(chi2_dist.sf(self.chi2, self.dof)) if self.dof > 0 else float("nan")

    @property
    def rms_cor(self) -> float:
        """RMS of the CoR residuals (CoR units)."""
        return float(np.sqrt(np.mean(np.square(self.predicted_cor - self.measured_cor))))

    @property
    def name(self) -> str:
        """The effects joined by ``+``, or ``nothing missing``."""
        return " + ".join(self.effects) if self.effects else "nothing missing"

    def to_dict(self) -> dict:
        """JSON-ready summary: ``std`` holds the standard errors the table determines;
        ``undetermined`` (with a ``note``) names the parameters it does not."""
        undetermined = [k for k, v in self.std.items() if v is None]
        note = {}
        if undetermined:
            note["note"] = (
                f"the table does not determine {', '.join(undetermined)}: the rows' CoR does "
                "not move with it independently of the others, so it has no standard error"
            )
        return {
            "effects": list(self.effects),
            "values": self.values,
            "std": {k: v for k, v in self.std.items() if v is not None},
            "undetermined": undetermined,
            **note,
            "at_bound": list(self.at_bound),
            "predicted_cor": [float(x) for x in self.predicted_cor],
            "residuals_cor": [float(x) for x in self.predicted_cor - self.measured_cor],
            "residuals_sigma": [float(x) for x in self.z],
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": None if self.dof == 0 else self.p_value,
            "rms_cor": self.rms_cor,
            "aic": self.aic,
            "bic": self.bic,
        }


#: The optimizer's settings for ln CoR rows: a row costs milliseconds on the fast
#: engine (more, finer steps, each start off the bounds); coordinates about the
#: null point, so that the difference step grows away from it (a delay's ln CoR is
#: rough at fine scales, the continuous delay line's period moving with the delay:
#: centred on a start far
#: from the null, the Table 3 fits with an extra delay end 40 times worse in chi2);
#: each given start polished (a pair's start from its single effects' fits can lead
#: to a better valley than the stated loop, whose chi2 is lower).
COR_LEAST_SQUARES = LeastSquares(
    method="trf",
    diff_step=1e-3,
    ftol=1e-8,
    xtol=1e-5,
    max_nfev=25,
    per_parameter=True,
    margin=0.1,
    centred=False,
    each_start=True,
)


def _finish(model: CorModel, cases, y, sigma, values: dict[str, float]) -> ModelFit:
    pred = model.predict_values(cases, values)
    z = (pred - y) / sigma
    u = model.coordinates(values)
    lo, hi = model.bounds()
    at_bound = tuple(
        p.name
        for p, x, a, b in zip(model.parameters, u, lo, hi, strict=True)
        if min(x - a, b - x) < 1e-3
    )
    std = model.flat(
        standard_errors(
            lambda v: (model.predict_values(cases, model.flat(v)) - y) / sigma,
            model.space.centred(model.nested(values)),
            z,
            step=JACOBIAN_STEP,
        )
    )
    return ModelFit(
        effects=tuple(model.names),
        values=dict(values),
        std=std,
        predicted_cor=np.exp(pred),
        measured_cor=np.exp(y),
        z=z,
        chi2=float(np.sum(z**2)),
        dof=len(y) - len(u),
        at_bound=at_bound,
    )


def fit_model(
    effects: Sequence[EffectAt],
    cases: Sequence[Case],
    y: np.ndarray,
    sigma: np.ndarray,
    starts: Sequence[dict[str, float]] = (),
) -> ModelFit:
    """Fit ``effects`` to ln CoR ``y`` (noise ``sigma``) of ``cases``
    (:func:`~hybridtable.effects.fitting.fit_values`): each of the ``starts``
    (parameter -> value; without any, the null point) and the best point of a
    grid over the range are polished; the lowest chi2 wins.
    """
    model = CorModel(effects)
    n_par = len(model.parameters)
    if n_par == 0:
        return _finish(model, cases, y, sigma, {})
    lo, hi = model.bounds()
    points = {1: 13, 2: 7}.get(n_par, 4)
    axes = [_axis(p, a, b, points) for p, a, b in zip(model.parameters, lo, hi, strict=True)]
    grid = [model.values(np.array(g)) for g in itertools.product(*axes)]
    sol = fit_values(
        lambda v: (model.predict_values(cases, model.flat(v)) - y) / sigma,
        model.space,
        [model.nested(s) for s in starts],
        COR_LEAST_SQUARES,
        grid=[model.nested(g) for g in grid],
    )
    return _finish(model, cases, y, sigma, model.flat(sol.values))


def _axis(p, a: float, b: float, points: int) -> np.ndarray:
    """Grid points of one coordinate over ``[a, b]`` (``u = 0``: the null value):
    geometric from a linear parameter's null at its lower bound (e.g. damping
    >= 0: its plausible sizes span decades), else even."""
    if not p.log and a == 0.0 and b > 0.0:
        return a + (b - a) * np.concatenate([[0.0], np.geomspace(1e-3, 1.0, points - 1)])
    return np.linspace(a, b, points)


def fit_models(
    effects: Sequence[EffectAt],
    cases: Sequence[Case],
    y: np.ndarray,
    sigma: np.ndarray,
    max_effects: int = 3,
    keep: int = 4,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
) -> tuple[list[ModelFit], list[tuple[str, ...]]]:
    """Fit the stated loop, every single effect, and the promising pairs and triples.

    ``workers`` > 1 fits the models in that many forked processes
    (:func:`~hybridtable.effects.workers.pool_map`: the effects stay in this
    process's memory, which the workers inherit).

    Returns
    -------
    fits : list of ModelFit
        Ranked by BIC (best first).
    too_many : list of tuple of str
        Effect combinations not fitted because they have at least as many
        parameters as the table has rows.
    """
    n = len(y)
    note = progress or (lambda _msg: None)
    too_many: list[tuple[str, ...]] = []
    singles = [e for e in effects if len(e.parameters) < n]
    too_many += [(e.name,) for e in effects if len(e.parameters) >= n]
    shared = ({e.name: e for e in effects}, cases, y, sigma)
    fits = _run([((), ())] + [((e.name,), ()) for e in singles], workers, note, shared)
    single = {f.effects[0]: f for f in fits[1:]}
    everything = CorModel(effects)
    index, j = {}, 0
    for e in effects:
        index[e.name] = list(range(j, j + len(e.parameters)))
        j += len(e.parameters)
    zero = np.zeros(len(everything.parameters))
    jac = everything.jacobian(cases, zero)
    y0 = everything.predict(cases, zero)
    lo, hi = everything.bounds()

    def screen(combos):
        """Each combination's chi2 on the loop linearized at the stated point."""
        out = []
        for combo in combos:
            cols = [j for name in combo for j in index[name]]
            a, b = jac[:, cols] / sigma[:, None], (y - y0) / sigma
            sol = lsq_linear(a, b, bounds=(lo[cols], hi[cols]))
            out.append((float(np.sum((a @ sol.x - b) ** 2)), None))
        return out

    def start(combo):
        return {n: dict(single[n].values) for n in combo if n in single}

    best_single = [f.effects[0] for f in rank_fits(list(single.values()))[:3]]
    by_name = {e.name: e for e in effects}
    work, seen = [], set()
    for size in range(2, max_effects + 1):
        for p in propose(
            list(by_name), size, screen, keep, start=start, best=best_single, seen=seen
        ):
            if sum(len(by_name[k].parameters) for k in p.names) >= n:
                too_many.append(p.names)
            else:
                work.append((p.names, (CorModel.flat(p.start),)))
    fits += _run(work, workers, note, shared)
    return rank_fits(fits), sorted(set(too_many))


def _fit_job(shared, job) -> ModelFit:
    by_name, cases, y, sigma = shared
    names, starts = job
    return fit_model([by_name[n] for n in names], cases, y, sigma, starts)


def _run(work, workers: int, note: Callable[[str], None], shared) -> list[ModelFit]:
    """Fit the (effect names, starts) of ``work``, in ``workers`` forked processes."""
    return pool_map(
        _fit_job,
        work,
        workers,
        on_done=lambda job, _fit: note(" + ".join(job[0]) or "the stated loop"),
        shared=shared,
    )


def rank_fits(fits: list[ModelFit]) -> list[ModelFit]:
    """``fits`` by BIC, then by fewer effects."""
    return sorted(fits, key=lambda f: (round(f.bic, 9), len(f.effects)))
