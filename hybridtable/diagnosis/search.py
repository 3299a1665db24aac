"""Pairs and swaps: models forward selection cannot reach, and drop-one tests.

Forward selection adds one effect at a time, so two effects whose influence on
the CoR cancels (one dissipates, one adds energy) can each look too weak to
enter alone, or the first effect chosen can be a look-alike that blocks the
right one. When the end test fails after forward selection,
:func:`pairs_and_swaps` fits the models the one search proposes
(:mod:`~hybridtable.effects.search`, as ``explain``'s pairs and triples are):

- every pair of the first round's candidates that do not change the same part,
  jointly, from the best point of a grid crossing each member's single fit, its
  data-driven starts and a few magnitudes (:func:`grid_values`): an effect that
  is invisible alone (a friction whose steps a long extra delay misplaces) is
  found with its partner;
- every *swap*: the selection with one effect replaced by one of the
  :data:`~hybridtable.diagnosis.settings.PAIR_POOL` best first-round candidates.

Only pairs with a member that moves the other's signature in time (an effect
with data-driven starts: a lag, a delay, a mode) or of two of the
:data:`~hybridtable.diagnosis.settings.PAIR_POOL` best candidates are tried. The
grids are screened on :data:`SCREENING_RUNS` runs (those the nominal model
misses most):
only the :data:`SCREENED_PAIRS` pairs whose best grid point fits it best are
fitted to every run, shortly (:data:`PAIR_NFEV` evaluations); the best
:data:`JUDGED_PROPOSALS` that beat the selection are fitted again in full and
judged in turn, the first whose every effect is accepted replacing it.

A proposal replaces the selection if its ``delta_bic`` against the nominal
model beats the selection's by :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`
and every one of its effects is accepted given the others (:func:`drop_one`:
significant and removing :data:`~hybridtable.diagnosis.settings.MIN_EXCESS_REMOVED`
of the held-out excess error of the model without it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from hybridtable.diagnosis.candidates import Candidate, judge
from hybridtable.diagnosis.evaluate import Evaluator
from hybridtable.diagnosis.fit import (
    Fit,
    delta_bic,
    fit_effects,
    heldout,
    model_spec,
    pooled_error,
    residual_probe,
)
from hybridtable.diagnosis.settings import BIC_THRESHOLD, PAIR_POOL
from hybridtable.effects.registry import get_effect
from hybridtable.effects.search import compatible, propose, swaps
from hybridtable.effects.workers import pool_map

__all__ = ["PAIR_NFEV", "grid_values", "drop_one", "pairs_and_swaps"]


#: Least-squares evaluations of a pair's short fit to every run.
PAIR_NFEV = 8

#: Pairs fitted to every run after the screening.
SCREENED_PAIRS = 6

#: Proposals beating the selection that are judged (drop-one tests), best first.
JUDGED_PROPOSALS = 3

#: Runs the pairs' grids are screened on (those the nominal model misses most).
SCREENING_RUNS = 2

#: Magnitudes of a start grid, as fractions of the way from an effect's null
#: value to its bounds.
GRID_FRACTIONS = (0.05, 0.25, 0.6)


def _fit_job(ev, job):
    names, start, starts, nfev = job
    sims = ev.simulations
    fit = fit_effects(ev, names, start=start, starts=starts, max_nfev=nfev)
    return fit, ev.simulations - sims


def _screen_job(ev, job):
    """The best grid point of a pair on runs ``ks``: (whitened RSS, values)."""
    names, starts, ks = job
    sims = ev.simulations
    best = (math.inf, None)
    for values in starts:
        spec = model_spec(names, values, ev.scale)
        evs = [ev.evaluate(spec, k) for k in ks]
        if any(e.failed for e in evs):
            continue
        cost = sum(sum(e.rss().values()) for e in evs)
        if cost < best[0]:
            best = (cost, values)
    return best, ev.simulations - sims


def grid_values(c: Candidate, scale, residuals) -> list[dict[str, float]]:
    """Start values of candidate ``c``'s effect for a pair: its single fit and
    its data-driven starts or, without those, per parameter with a null value,
    magnitudes between the null and the bounds (:data:`GRID_FRACTIONS`)."""
    effect = get_effect(c.effect)
    out = [dict(c.parameters)]
    if effect.starts is not None:
        out += [dict(effect.start(scale), **v) for v in effect.starts(scale, residuals)]
        return out
    for p in effect.parameters:
        null = p.null_value(scale)
        if null is None:
            continue
        lo, hi = p.bounds(scale)
        for f in GRID_FRACTIONS:
            for bound in (hi, lo):
                if bound != null:
                    out.append(dict(effect.start(scale), **{p.name: null + f * (bound - null)}))
    return out


def _heldout_error(ev: Evaluator, nominal: Fit, fit: Fit) -> float:
    """Held-out error (noise units) of the model ``fit`` (in-sample with one run)."""
    if not fit.effects or len(ev.data) < 2:
        return pooled_error(ev.data, fit.evaluations)[0]
    return heldout(ev, nominal.evaluations, fit.effects, fit.values, "replay").error


def drop_one(ev: Evaluator, nominal: Fit, fit: Fit) -> list[Candidate]:
    """Judge every effect of the model ``fit`` given the others: the model
    without it (refitted) is the base of :func:`~hybridtable.diagnosis.candidates.judge`."""
    out = []
    error_after = pooled_error(ev.data, fit.evaluations)
    for x in fit.effects:
        rest = [n for n in fit.effects if n != x]
        base = (
            fit_effects(ev, rest, start={n: fit.values[n] for n in rest}, max_nfev=10)
            if rest
            else nominal
        )
        error_before = pooled_error(ev.data, base.evaluations)
        c = Candidate(
            effect=x,
            stage="replay",
            parameters=dict(fit.values[x]),
            model=list(fit.effects),
            model_values={n: dict(v) for n, v in fit.values.items()},
            error_before=error_before[0],
            error_after=error_after[0],
            heldout_error_after=math.nan,
            delta_bic=math.nan,
            heldout_z=math.nan,
            significant=False,
            channel_error_before=error_before[1],
            channel_error_after=error_after[1],
            nfev=fit.nfev,
            fit=fit,
            heldout_error_before=_heldout_error(ev, nominal, base),
        )
        judge(ev, base, c)
        out.append(c)
    return out


def pairs_and_swaps(
    ev: Evaluator,
    nominal: Fit,
    first_round: Sequence[Candidate],
    selected: Sequence[str],
    current: Fit,
    max_effects: int,
    workers: int,
    progress: bool,
    log: list[dict],
) -> tuple[Fit, float, float] | None:
    """The better model of the pair and swap search (see the module doc), as
    ``(fit, held-out error, delta_bic against the nominal model)``, or None.
    Every proposal and the decision are appended to ``log``."""
    usable = [c for c in first_round if c.fit is not None and not c.fit.failed]
    pool = [c.effect for c in usable[:PAIR_POOL]]
    residuals = residual_probe(ev.data, nominal.evaluations)
    # A pair can hide both its effects only if one of them moves the other's
    # signature in time (a lag, a delay, a mode: effects with data-driven
    # starts); other pairs come from the best candidates.
    timing = {c.effect for c in usable if get_effect(c.effect).starts is not None}
    seen = {frozenset(selected)}

    def worth_a_pair(names: Sequence[str]) -> bool:
        hides = set(names) & timing or set(names) <= set(pool)
        return bool(hides) and frozenset(names) not in seen and compatible(names)

    worst = sorted(range(len(ev.data)), key=lambda i: -sum(nominal.evaluations[i].rss().values()))
    worst = worst[:SCREENING_RUNS]
    screened: list[int] = []

    def screen(pairs):
        grids = {c.effect: grid_values(c, ev.scale, residuals) for c in usable}
        jobs = [
            ([a, b], [{a: x, b: y} for x in grids[a] for y in grids[b]], worst) for a, b in pairs
        ]
        screened.append(len(jobs))
        before = ev.simulations
        out = pool_map(
            _screen_job, jobs, workers, progress, f"screen {len(jobs)} pair(s)", shared=ev
        )
        ev.simulations = before + sum(s for _, s in out)  # once, in or out of process
        return [best for best, _ in out]

    proposals = []
    if max_effects >= 2:
        names = [c.effect for c in usable]
        pairs = propose(names, 2, screen, SCREENED_PAIRS, allowed=worth_a_pair, seen=seen)
        log.append(
            {
                "screening_runs": [ev.data[k].run_id for k in worst],
                "pairs_screened": sum(screened),
                "best": [{"effects": list(p.names), "rss": p.screened} for p in pairs],
            }
        )
        proposals += [(list(p.names), p.start, (), PAIR_NFEV) for p in pairs]
    fitted = {c.effect: c.parameters for c in usable}
    for names in swaps(selected, pool, compatible, seen):
        start = {n: current.values[n] for n in names if n in current.values}
        start[names[-1]] = fitted[names[-1]]
        proposals.append((list(names), start, (), PAIR_NFEV))
    if not proposals:
        return None
    label = f"fit {len(proposals)} pair(s)/swap(s)"
    before = ev.simulations
    out = pool_map(_fit_job, proposals, workers, progress, label, shared=ev)
    ev.simulations = before + sum(s for _, s in out)  # once, in or out of process
    current_bic = delta_bic(nominal, current)
    scored = sorted(
        ((delta_bic(nominal, fit), fit) for fit, _ in out if not fit.failed),
        key=lambda x: -x[0],
    )
    for dbic, fit in scored:
        log.append(
            {
                "effects": list(fit.effects),
                "delta_bic": dbic,
                "beats_selection_by": dbic - current_bic,
            }
        )
    better = [(d, f) for d, f in scored if d > current_bic + BIC_THRESHOLD][:JUDGED_PROPOSALS]
    if not better:
        log.append({"decision": "kept the forward selection: no pair or swap beats it"})
        return None
    for dbic, fit in better:
        # The screening fit was short: fit the proposal in full.
        full = fit_effects(ev, fit.effects, start=fit.values)
        if delta_bic(nominal, full) > dbic:
            dbic, fit = delta_bic(nominal, full), full
        judged = drop_one(ev, nominal, fit)
        log.append(
            {
                "decision": "drop-one tests of " + " + ".join(fit.effects),
                "members": [c.to_json() for c in judged],
            }
        )
        if all(c.accepted for c in judged):
            held = judged[0].heldout_error_after
            if not math.isfinite(held):
                held = judged[0].error_after
            log.append({"decision": "replaced the selection with " + " + ".join(fit.effects)})
            return fit, held, dbic
    log.append(
        {"decision": "kept the forward selection: no better proposal has every effect accepted"}
    )
    return None
