"""Explain a measured CoR table: which loop is consistent with it, and what it cannot say.

:func:`explain_table` fits the stated loop and models of one to three effects
(:mod:`~hybridtable.explain.fit`), analyses what the table determines
(:mod:`~hybridtable.explain.identify`), reads its patterns
(:mod:`~hybridtable.explain.patterns`) and names the run that would separate
the look-alikes (:mod:`~hybridtable.explain.separate`).

The table is explained when the best model's chi2 passes at
:data:`ALPHA` and no pattern is flagged. Nothing is missing when the stated
loop itself passes and no model with an effect is better by BIC by more than
:data:`~hybridtable.explain.separate.LOOKALIKE_BIC`. A table with no more rows
than a model has parameters does not fit that model: it says which quantities
it cannot determine.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import f as f_dist

from hybridtable.effects.effect import Effect
from hybridtable.effects.registry import default_effects, get_effect
from hybridtable.effects.workers import worker_count
from hybridtable.errors import ParameterError
from hybridtable.explain.fit import ModelFit, fit_models
from hybridtable.explain.identify import Identifiability, identifiability
from hybridtable.explain.model import EffectAt, loop_of, table_scale
from hybridtable.explain.patterns import WINDOW_LN, interactions, readings, trends
from hybridtable.explain.separate import LOOKALIKE_BIC, lookalikes, separating_runs
from hybridtable.explain.table import CorTable
from hybridtable.loop.fast import prepare_fast

__all__ = ["ALPHA", "MAX_DISTINCT_ROWS", "MODEL_ERROR_LN", "Explanation", "explain_table"]

#: The chi2 test's false-alarm rate.
ALPHA = 0.01
#: The loop model's own error in ln CoR, added to each row's noise: the paper's
#: simulated Table 1 differs from this loop by up to 5e-4 (its integrator and
#: delay line are not ours).
MODEL_ERROR_LN = 1.0e-3
#: The most rows of distinct conditions a table may have (repeated rows of the
#: same conditions cost one): each is simulated for every model and every step
#: of its fit; the whole explanation takes 2 s to 3 s a row on a 2-core
#: machine (Tables 1, 3 and 4: 13.8, 12.0 and 21.4 s on 2026-11-27, benchmarks/bench_explain.py).
MAX_DISTINCT_ROWS = 200


@dataclass
class Explanation:
    """What a CoR table says about the rig (see :func:`explain_table`)."""

    table: CorTable
    noise_source: str
    sigma_ln: np.ndarray
    model_error_ln: float
    fits: list[ModelFit]
    not_fitted: list[tuple[str, ...]]
    identifiability: Identifiability
    interactions: list[dict]
    readings: list[dict]
    trends: list[dict]
    flat: dict | None
    separations: list[dict]
    explained: bool
    nothing_missing: bool
    verdict: str
    unexplained: list[str] = field(default_factory=list)
    cannot_run: dict[str, str] = field(default_factory=dict)

    @property
    def best(self) -> ModelFit:
        """The best fit (the stated loop is always among the fits)."""
        return self.fits[0]

    def to_dict(self) -> dict:
        """The JSON document of ``hybridtable explain``."""
        ident = self.identifiability.to_dict()
        return {
            "verdict": self.verdict,
            "explained": self.explained,
            "nothing_missing": self.nothing_missing,
            "source": self.table.source,
            "rows": [
                {
                    "line": r.line,
                    "compensator": r.compensator,
                    "cor": r.cor,
                    "cor_std": r.cor_std,
                    "conditions": r.conditions.to_dict(),
                }
                for r in self.table.rows
            ],
            "stated": dict(self.table.stated or {}),
            "noise": {
                "source": self.noise_source,
                "sigma_ln_cor": [float(x) for x in self.sigma_ln],
                "model_error_ln_cor": self.model_error_ln,
            },
            "models": [f.to_dict() | {"name": f.name} for f in self.fits],
            "lookalikes": [f.name for f in lookalikes(self.fits)],
            "not_fitted": [
                {"effects": list(n), "why": "as many parameters as the table has rows, or more"}
                for n in self.not_fitted
            ]
            + [{"effects": [n], "why": why} for n, why in self.cannot_run.items()],
            "identifiable": ident["identifiable"],
            "unresolved": ident["unresolved"],
            "undetermined": ident["undetermined"],
            "sensitivity_singular_values": ident["singular_values"],
            "quantities": ident["quantities"],
            "interactions": self.interactions,
            "readings": self.readings,
            "trends": self.trends,
            "flat": self.flat,
            "separating_runs": self.separations,
            "unexplained": self.unexplained,
        }


def _flat(table: CorTable, y: np.ndarray, sigma: np.ndarray, best: ModelFit) -> dict | None:
    """A CoR constant per compensator, the empirical baseline a model must beat."""
    comps = sorted({r.compensator for r in table.rows})
    n, p = len(y), len(comps)
    if n <= p:
        return None
    pred = np.empty(n)
    for c in comps:
        idx = [i for i, r in enumerate(table.rows) if r.compensator == c]
        w = 1.0 / sigma[idx] ** 2
        pred[idx] = float(np.sum(w * y[idx]) / np.sum(w))
    chi2 = float(np.sum(((pred - y) / sigma) ** 2))
    rms = float(np.sqrt(np.mean((np.exp(pred) - np.exp(y)) ** 2)))
    out = {
        "cor": {c: float(np.exp(pred[[r.compensator == c for r in table.rows]][0])) for c in comps},
        "chi2": chi2,
        "dof": n - p,
        "rms_cor": rms,
    }
    extra = best.n_parameters - p
    if extra <= 0:
        out["best_model_beats_it"] = best.chi2 < chi2
    else:
        # an F test: the gain in chi2 per extra parameter against the best model's misfit
        stat = ((chi2 - best.chi2) / extra) / max(best.chi2 / best.dof, 1.0)
        out["f_p_value"] = float(f_dist.sf(stat, extra, best.dof))
        out["best_model_beats_it"] = bool(out["f_p_value"] < 0.05)
    return out


def _value_words(fit: ModelFit) -> str:
    parts = []
    for k, v in fit.values.items():
        s = fit.std.get(k)
        if s is None:
            parts.append(f"{k} = {1e3 * v:.3g} ms" if k.endswith("_s") else f"{k} = {v:.4g}")
            parts[-1] += " (not determined by the table)"
        elif k.endswith("_s"):
            parts.append(f"{k} = {1e3 * v:.3g} +/- {1e3 * s:.2g} ms")
        else:
            parts.append(f"{k} = {v:.4g} +/- {s:.2g}")
    return ", ".join(parts)


def explain_table(
    table: CorTable,
    effects: Sequence[Effect] | None = None,
    max_effects: int = 3,
    model_error_ln: float = MODEL_ERROR_LN,
    progress: Callable[[str], None] | None = None,
    workers: int | None = None,
    jobs: int | None = None,
    max_rows: int = MAX_DISTINCT_ROWS,
) -> Explanation:
    """Explain a measured CoR table.

    Parameters
    ----------
    table : CorTable
        The measured CoRs and their stated conditions.
    effects : sequence of Effect, optional
        The candidates (default: the registered effects ``explain`` tries,
        :func:`~hybridtable.effects.registry.default_effects`). One that cannot
        run on the table's loop (e.g. a sensor chain on a continuous rig
        computer) is left out, and :attr:`Explanation.cannot_run` says why.
    max_effects : int
        The most effects in one model (1-3).
    model_error_ln : float
        The loop model's own error in ln CoR, added in quadrature to each row's noise.
    progress : callable, optional
        Called with the name of each model as it is fitted.
    workers : int, optional
        Processes that fit models in parallel (1: in this process; default: as
        ``diagnose``, :func:`~hybridtable.effects.workers.worker_count`).
    jobs : int, optional
        The older name of ``workers`` (deprecated).
    max_rows : int
        The most rows of distinct conditions (compensator and conditions) the
        table may have; more are refused before any work
        (:class:`~hybridtable.errors.ParameterError`), not left to run for hours.
    """
    if jobs is not None:
        warnings.warn("explain_table(jobs=) is now workers=", DeprecationWarning, stacklevel=2)
        workers = jobs if workers is None else workers
    workers = worker_count(workers)
    if effects is None:
        effects = [get_effect(n) for n in default_effects("explain")]
    std, source = table.noise()
    y = table.ln_cor
    sigma = np.sqrt((std / np.exp(y)) ** 2 + model_error_ln**2)
    cases = [(r.compensator, r.conditions) for r in table.rows]
    distinct = len(set(cases))
    if distinct > max_rows:
        raise ParameterError(
            f"{table.source}: {distinct} rows of distinct conditions, more than the "
            f"{max_rows} explain fits (each is simulated for every model and every step of "
            "its fit: seconds a row on two cores): average repeated runs of the same conditions into one row with "
            "their cor_std, or give a larger --max-rows"
        )
    rig = table_scale(cases)
    effects, cannot_run = _runnable([EffectAt(e, rig) for e in effects], cases)
    if workers > 1:  # compiled once here, inherited by every forked worker
        prepare_fast(cond.loop_params(comp) for comp, cond in dict.fromkeys(cases))
    fits, not_fitted = fit_models(
        effects, cases, y, sigma, max_effects, progress=progress, workers=workers
    )
    # the stated loop is always fitted (it has no parameter and n >= 1 rows), and every
    # model fitted has fewer parameters than rows: the best exists and has dof >= 1
    best = fits[0]
    nominal = next(f for f in fits if not f.effects)
    ident = identifiability(effects, cases, sigma, best.values)
    predicted = np.log(best.predicted_cor)
    single = {f.effects[0]: np.log(f.predicted_cor) for f in fits if len(f.effects) == 1}
    inter = interactions(cases, y, sigma, predicted, effects, single)
    read = readings(cases, y, sigma)
    trend = trends(cases, y, sigma, predicted, effects)
    flat = _flat(table, y, sigma, best)
    first = table.rows[0].conditions
    separations = []
    unexplained = []
    for item in inter:
        if item["flagged"]:
            unexplained.append(
                f"the interaction I = ln none - ln SDC - ln MDC + ln SDMDC is "
                f"{item['interaction']:+.4f} +/- {item['std']:.2g}; each single effect of the library "
                f"fitted to the table gives at most {item['fitted_single_largest']:.2g} in size "
                f"(at most {item['library_largest']:.2g} over the sizes that keep the CoRs within "
                f"{WINDOW_LN:g} of the table's), the stated loop {item['stated_loop']:+.4f}, the "
                f"best model {item['best_model']:+.4f}: "
                f"{item['distance_sigma']:.0f} std from the nearest model"
            )
    for item in trend:
        if item["flagged"]:
            unexplained.append(item["words"])
    fits_noise = best.p_value >= ALPHA
    explained = bool(fits_noise and not unexplained)
    nothing = bool(
        explained and nominal.p_value >= ALPHA and nominal.bic - best.bic <= LOOKALIKE_BIC
    )
    if not nothing:
        separations = separating_runs(fits, first, float(np.median(sigma)), effects)
    if nothing:
        verdict = (
            f"Nothing is missing: the stated loop gives every CoR within the noise "
            f"(chi2 {nominal.chi2:.3g} for {nominal.dof} degrees of freedom, p {nominal.p_value:.2g}; "
            f"RMS {nominal.rms_cor:.2g} in CoR)."
        )
    elif explained:
        alike = [f.name for f in lookalikes(fits)[1:]]
        fit_words = (
            f"{_value_words(best)} (chi2 {best.chi2:.3g} for {best.dof} degrees of freedom, "
            f"p {best.p_value:.2g})"
        )
        if alike:
            verdict = (
                f"Explained, but not uniquely: {best.name} or {' or '.join(alike)} fit equally "
                f"well (within {LOOKALIKE_BIC:g} of BIC); the table cannot tell them apart. "
                f"Best: {best.name}, {fit_words}."
            )
        else:
            verdict = f"{best.name} explains the table: {fit_words}."
    else:
        worst = float(np.max(np.abs(best.z)))
        why = (
            unexplained[0]
            if unexplained
            else (
                f"the best of {len(fits)} models ({best.name}) leaves RMS {best.rms_cor:.2g} in CoR, "
                f"up to {worst:.1f} noise std (chi2 {best.chi2:.3g} for {best.dof} degrees of freedom, "
                f"p {best.p_value:.1e})"
            )
        )
        if unexplained:
            why += f"; the best model ({best.name}) leaves RMS {best.rms_cor:.2g} in CoR"
        verdict = f"Not explained by the loop model: {why}."
        if not fits_noise:
            unexplained.insert(
                0,
                f"best fit {best.name}: RMS {best.rms_cor:.2g} in CoR, chi2 {best.chi2:.3g} for "
                f"{best.dof} degrees of freedom (p {best.p_value:.1e})",
            )
    return Explanation(
        table=table,
        noise_source=source,
        sigma_ln=sigma,
        model_error_ln=model_error_ln,
        fits=fits,
        not_fitted=not_fitted,
        identifiability=ident,
        interactions=inter,
        readings=read,
        trends=trend,
        flat=flat,
        separations=separations,
        explained=explained,
        nothing_missing=nothing,
        verdict=verdict,
        unexplained=unexplained,
        cannot_run=cannot_run,
    )


def _runnable(
    effects: Sequence[EffectAt], cases: Sequence[tuple]
) -> tuple[list[EffectAt], dict[str, str]]:
    """The effects whose loop can be built for every row where they act
    (:meth:`~hybridtable.explain.model.EffectAt.probe_values`; at their null
    values they vanish, and any loop is built), and why the others cannot."""
    keep, why = [], {}
    for e in effects:
        probe = e.probe_values()
        try:
            for case in cases:
                loop_of(case, (e,), probe)
        except ParameterError as err:
            why[e.name] = str(err)
        else:
            keep.append(e)
    return keep, why
