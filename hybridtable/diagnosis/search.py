"""Pairs and swaps: models forward selection cannot reach, and drop-one tests.

Forward selection adds one effect at a time, so two effects whose influence on
the CoR cancels (one dissipates, one adds energy) can each look too weak to
enter alone, or the first effect chosen can be a look-alike that blocks the
right one. When the end test fails after forward selection,
:func:`pairs_and_swaps` fits

- every pair of the first round's :data:`~hybridtable.diagnosis.settings.PAIR_POOL`
  best candidates (by ``delta_bic`` against the nominal model), jointly, from
  their single fits;
- every *swap*: the selection with one effect replaced by one of those candidates.

The proposal with the largest ``delta_bic`` against the nominal model replaces
the selection if it beats it by :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`
and every one of its effects is accepted given the others (:func:`drop_one`:
significant and removing :data:`~hybridtable.diagnosis.settings.MIN_EXCESS_REMOVED`
of the held-out excess error of the model without it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import combinations

from hybridtable.diagnosis.candidates import Candidate, judge
from hybridtable.diagnosis.evaluate import Evaluator
from hybridtable.diagnosis.fit import Fit, delta_bic, fit_effects, heldout, pooled_error
from hybridtable.diagnosis.registry import get_effect
from hybridtable.diagnosis.settings import BIC_THRESHOLD, PAIR_POOL
from hybridtable.diagnosis.workers import pool_map

__all__ = ["drop_one", "pairs_and_swaps"]


_STATE: dict = {}


def _fit_job(job):
    ev = _STATE["ev"]
    names, start = job
    sims = ev.simulations
    fit = fit_effects(ev, names, start=start)
    return fit, ev.simulations - sims


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
    pool = [c for c in first_round if c.fit is not None and not c.fit.failed][:PAIR_POOL]
    current_set = frozenset(selected)
    proposals: dict[frozenset, tuple[list[str], dict]] = {}

    def conflict_free(names: Sequence[str]) -> bool:
        effects = [get_effect(n) for n in names]
        return not any(a.conflicts_with(b) for a, b in combinations(effects, 2))

    for a, b in combinations(pool, 2):
        names = [a.effect, b.effect]
        key = frozenset(names)
        if key != current_set and conflict_free(names) and len(names) <= max_effects:
            proposals[key] = (names, {a.effect: a.parameters, b.effect: b.parameters})
    for s in selected:
        for c in pool:
            if c.effect in selected:
                continue
            names = [n for n in selected if n != s] + [c.effect]
            key = frozenset(names)
            if key in proposals or not conflict_free(names):
                continue
            start = {n: current.values[n] for n in names if n in current.values}
            start[c.effect] = c.parameters
            proposals[key] = (names, start)
    if not proposals:
        return None
    jobs = list(proposals.values())
    _STATE.update(ev=ev)
    out = pool_map(_fit_job, jobs, workers, progress, f"fit {len(jobs)} pair(s)/swap(s)")
    _STATE.clear()
    ev.simulations += sum(s for _, s in out)
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
    if not scored or scored[0][0] <= current_bic + BIC_THRESHOLD:
        log.append({"decision": "kept the forward selection: no pair or swap beats it"})
        return None
    dbic, fit = scored[0]
    judged = drop_one(ev, nominal, fit)
    log.append(
        {
            "decision": "drop-one tests of " + " + ".join(fit.effects),
            "members": [c.to_json() for c in judged],
        }
    )
    if not all(c.accepted for c in judged):
        log.append(
            {"decision": "kept the forward selection: an effect of the pair is not accepted"}
        )
        return None
    held = judged[0].heldout_error_after
    if not math.isfinite(held):
        held = judged[0].error_after
    log.append({"decision": "replaced the selection with " + " + ".join(fit.effects)})
    return fit, held, dbic
