"""Which physical effect a six-axis rig's model is missing: ``diagnose`` on
6-DoF runs (``hybridtable-run6/1``), on the one effect core.

The data are the runs' replays (:func:`~hybridtable.six_dof.compare6.replay_residuals`:
every component of every tick in its noise levels). Forward selection over
the candidates (every registered effect with ``apply6``, or those named):

1. the nominal model's error: each component's RMS replay error in noise
   levels; the model *explains* the runs when their pooled RMS is at most
   :data:`~hybridtable.diagnosis.settings.EXPLAINED_MAX_ERROR` (as the 1-D
   diagnose pools its channels) and no component is above
   :data:`COMPONENT_MAX_ERROR` (a misfit of one component is not diluted by
   the others; each noise level is estimated from some tens of ticks out of
   contact, to about 10 %);
2. each round fits every candidate that touches nothing already selected,
   jointly with the selected effects (started at their fitted values; the
   effect core's fit, :func:`~hybridtable.six_dof.fit6.fit_runs6`), in forked
   workers, and scores it by the information criterion over the blocks (one a
   run and component, in the component's noise levels, which are stated:
   :func:`~hybridtable.effects.selection.delta_bic`); a candidate that cannot
   act on the rig (the table's response on the Stewart platform) is left out,
   with why;
3. the most significant candidate that is relevant enters: significant
   (``delta_bic`` above :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`)
   and removing at least :data:`~hybridtable.diagnosis.settings.MIN_EXCESS_REMOVED`
   of the worst component's error above the noise (a significant effect that
   leaves the worst error where it was explains nothing, and does not block
   one that does); when no candidate does, of the error pooled over the
   components (two hidden effects, each fit alone compromised by the other's
   misfit: the one that explains most enters first); relevant candidates within
   :data:`~hybridtable.diagnosis.settings.INDISTINGUISHABLE_BIC` of it are its
   look-alikes, which the data cannot tell apart;
4. it stops when the model explains the runs, when no candidate enters, or
   after ``max_effects`` (:data:`MAX_EFFECTS`);
5. a swap step (the 1-D diagnose's, :func:`~hybridtable.effects.search.swaps`):
   the selection with one effect replaced by one of the
   :data:`~hybridtable.diagnosis.settings.PAIR_POOL` best significant others
   of the round it entered in, each fitted jointly; the best swap whose
   information criterion beats the selection's replaces it: by
   :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`, or by anything at
   all when it has fewer parameters (the simpler model, no worse: a power law
   whose exponent came back to 1 is a stiffness). A look-alike chosen first
   (one that fitted another effect's misfit in its round) cannot block the
   right effect so.
6. a separating run (the 1-D diagnose's, on the core's
   :func:`~hybridtable.effects.selection.most_separating`): for each selected
   effect and each of its first :data:`MAX_SEPARATED` look-alikes, the
   candidate run on which the two fitted models differ most
   (:func:`~hybridtable.six_dof.design6.separating_run6`: a faster or slower
   approach, another spacecraft mass, more pitch, the compensator off), and
   whether one such run would tell them apart, how many would, or that none
   of them does (the look-alike's hint at another measurement).

Effects of the rig computer (``stage="closed_loop"``: ``com_offset``) act
on no replay: the audit of the computer's spacecraft
(:func:`~hybridtable.six_dof.audit6.audit_runs6`) solves for them from the
record, and its findings join the verdict.

The verdict is one of: nothing is missing (the nominal model explains the
runs and the computer's spacecraft is the JSON's), the effects found (with their values, standard errors and the error
falling), or that the runs are not explained (the best the library does, and
where the misfit still sits: an effect outside the library).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hybridtable.diagnosis.settings import (
    BIC_THRESHOLD,
    INDISTINGUISHABLE_BIC,
    MIN_EXCESS_REMOVED,
    PAIR_POOL,
)
from hybridtable.effects.registry import effect_names, get_effect
from hybridtable.effects.search import compatible, forward, swaps
from hybridtable.effects.selection import delta_bic, lookalikes
from hybridtable.effects.workers import pool_map
from hybridtable.errors import ParameterError, SimulationError
from hybridtable.six_dof.audit6 import audit_runs6
from hybridtable.six_dof.compare6 import replay_residuals
from hybridtable.six_dof.design6 import candidate_runs, mean_levels, separation, try_distance
from hybridtable.six_dof.fit6 import Fit6, blocks, fit_runs6
from hybridtable.six_dof.physics6 import physics_with, rig_scale
from hybridtable.six_dof.run6 import Run6
from hybridtable.six_dof.verdict6 import (
    Diagnosis6,
    Step6,
    component_errors,
    pooled_error,
    public_entry,
)

__all__ = ["MAX_EFFECTS", "MAX_SEPARATED", "diagnose_runs6"]

#: The most effects forward selection adds.
MAX_EFFECTS = 3

#: The most look-alikes of one selected effect a separating run is sought for.
MAX_SEPARATED = 3


def _fit_job(runs: Sequence[Run6], job: tuple) -> Fit6 | str:
    """The joint fit of the effects ``names`` from ``start`` (``job``), or
    why it failed: a round's candidate with the selection, or a swap."""
    names, start = job
    try:
        return fit_runs6(runs, [(get_effect(n), {}) for n in names], start)
    except (SimulationError, ParameterError) as err:
        return f"{type(err).__name__}: {err}"


def _parameters(names) -> int:
    return sum(len(get_effect(n).parameters) for n in names)


def _swap_step(runs: Sequence[Run6], out: Diagnosis6, workers: int, progress: bool) -> None:
    """The swap step (see the module): ``out``'s selection, fit, errors and
    look-alikes replaced by the best swap that beats them, if one does."""
    selected = tuple(out.selected)
    # each selected effect against the best others of the round it entered
    pools: dict[str, list[str]] = {}
    fitted: dict[tuple[str, str], dict] = {}
    for step in out.steps:
        if step.kind != "round" or step.chosen is None:
            continue
        ranked = sorted(
            (r for r in step.ranking if "delta_bic" in r and r["effect"] not in selected),
            key=lambda r: r["delta_bic"],
            reverse=True,
        )
        near = [r for r in ranked if r["delta_bic"] > BIC_THRESHOLD][:PAIR_POOL]
        pools[step.chosen] = [r["effect"] for r in near]
        for r in near:
            fitted[(step.chosen, r["effect"])] = r["values"][r["effect"]]
    pool = list(dict.fromkeys(n for names in pools.values() for n in names))

    jobs = []
    for names in swaps(selected, pool, compatible, {frozenset(selected)}):
        gone = next(n for n in selected if n not in names)
        if names[-1] not in pools.get(gone, ()):
            continue
        start = {n: out.fit.values[n] for n in names[:-1]}
        start[names[-1]] = fitted[(gone, names[-1])]
        jobs.append((names, start))
    if not jobs:
        return
    results = pool_map(_fit_job, jobs, workers, progress=progress, label="swaps", shared=list(runs))
    out.fits += len(jobs)
    current = blocks(runs, out.fit.residuals)
    k0 = _parameters(selected)
    ranking = []
    for (names, _), result in zip(jobs, results, strict=True):
        gone = next(n for n in selected if n not in names)
        entry = {"effect": names[-1], "replaces": gone, "effects": list(names)}
        if isinstance(result, str):
            ranking.append({**entry, "failed": result})
            continue
        gain = delta_bic(current, blocks(runs, result.residuals), _parameters(names) - k0, True)
        errors = component_errors(runs, result.residuals)
        ranking.append({**entry, "delta_bic": gain, "errors": errors, "fit": result})
    scored = sorted(
        (r for r in ranking if "delta_bic" in r), key=lambda r: r["delta_bic"], reverse=True
    )

    def beats(r: dict) -> bool:
        simpler = _parameters(r["effects"]) < k0
        return r["delta_bic"] > (0.0 if simpler else BIC_THRESHOLD)

    better = [r for r in scored if beats(r)]
    step = Step6(
        [public_entry(r) for r in ranking],
        None,
        "no swap beats the selection (by "
        f"{BIC_THRESHOLD:g} in delta BIC, or by any with fewer parameters)",
        kind="swap",
    )
    out.steps.append(step)

    before = out.fit  # the selection the swaps are scored against

    def note_lookalikes(swapped: str | None) -> None:
        # a swap of another effect that scored as well as the selection
        for r in scored:
            if r["replaces"] != swapped and abs(r["delta_bic"]) < INDISTINGUISHABLE_BIC:
                alike = out.lookalikes_of.setdefault(r["replaces"], [])
                alike += [r["effect"]] * (r["effect"] not in alike)
                if swapped is None:  # else ``before`` holds the effect swapped out
                    out.pairs[r["replaces"], r["effect"]] = (before, r["fit"])

    if not better:
        note_lookalikes(None)
        return
    best = better[0]
    step.chosen = best["effect"]
    step.why = (
        f"{best['effect']} for {best['replaces']}: delta BIC {best['delta_bic']:.4g} against "
        f"{' + '.join(selected)}"
        + (" with fewer parameters" if _parameters(best["effects"]) < k0 else "")
    )
    out.selected[:] = [best["effect"] if n == best["replaces"] else n for n in selected]
    out.fit = best["fit"]
    out.final_errors = best["errors"]
    # what the data cannot tell apart: for the swapped effect, the one it
    # replaced and the other replacements of that effect within the margin
    gone, new = best["replaces"], best["effect"]
    out.lookalikes_of.pop(gone, None)
    alike = [gone] if best["delta_bic"] < INDISTINGUISHABLE_BIC else []
    alike += [
        r["effect"]
        for r in scored
        if r is not best
        and r["replaces"] == gone
        and best["delta_bic"] - r["delta_bic"] < INDISTINGUISHABLE_BIC
    ]
    out.lookalikes_of[new] = alike
    out.pairs = {k: v for k, v in out.pairs.items() if k[0] != gone}
    out.pairs[new, gone] = (best["fit"], before)
    out.pairs.update(  # the other replacements of the same effect
        {
            (new, r["effect"]): (best["fit"], r["fit"])
            for r in scored
            if r["replaces"] == gone and r["effect"] in alike
        }
    )
    note_lookalikes(gone)


def _able(runs: Sequence[Run6], effects: Sequence[str]) -> tuple[list[str], dict[str, str]]:
    """The candidates that can act on the runs' rig: each applied one typical
    change from its null to the first run's scenario (a ParameterError: it
    cannot, and why)."""
    params = runs[0].params
    scale = rig_scale(params)
    able, refused = [], {}
    for name in effects:
        effect = get_effect(name)
        values = {}
        for p in effect.parameters:  # one typical change from the null (of ln for a ratio)
            values[p.name] = min(p.value_at(1.0, scale), p.bounds(scale)[1])
        try:
            physics_with([(effect, values)], scale).apply(params)
        except ParameterError as err:
            refused[name] = str(err)
            continue
        able.append(name)
    return able, refused


def diagnose_runs6(
    runs: Sequence[Run6],
    effects: Sequence[str] | None = None,
    workers: int = 1,
    progress: bool = False,
    max_effects: int = MAX_EFFECTS,
    swap: bool = True,
    separate: bool = True,
) -> Diagnosis6:
    """Forward selection of the effects the runs' model misses (see the module).

    Parameters
    ----------
    runs : sequence of Run6
    effects : sequence of str, optional
        The candidates (default: every registered effect with ``apply6``).
    workers : int
        Processes for the candidates' fits.
    max_effects : int
        The most effects the model gains.
    swap : bool
        Try the swap step after the forward selection (step 5 of the module).
    separate : bool
        Look for the runs that would separate the selected effects from
        their look-alikes (step 6 of the module).

    Raises
    ------
    ParameterError
        For a named effect without ``apply6``.
    """
    if effects is None:
        effects = [n for n in effect_names() if get_effect(n).apply6 is not None]
    for name in effects:
        if get_effect(name).apply6 is None:
            raise ParameterError(
                f"effect {name} acts on the 1-D loop only (hybridtable effects, column loops, "
                "lists those of a six-axis rig)"
            )
    audited = [n for n in effects if get_effect(n).stage == "closed_loop"]
    effects, refused = _able(runs, [n for n in effects if n not in audited])
    r0 = np.concatenate([replay_residuals(r) for r in runs])
    out = Diagnosis6([r.run_id for r in runs], list(effects), component_errors(runs, r0))
    out.refused = refused
    out.audit = audit_runs6(runs)
    out.scale = rig_scale(runs[0].params)
    out.final_errors = dict(out.nominal_errors)
    current = blocks(runs, r0)
    fit: Fit6 | None = None

    def round_(jobs: list[str]) -> str | None:
        nonlocal fit, current
        if out.explained:
            return None
        start = None if fit is None else fit.values
        results = pool_map(
            _fit_job,
            [((*out.selected, name), start) for name in jobs],
            workers,
            progress=progress,
            label=f"round {len(out.steps) + 1}",
            shared=list(runs),
        )
        out.fits += len(jobs)
        ranking = []
        for name, result in zip(jobs, results, strict=True):
            if isinstance(result, str):
                ranking.append({"effect": name, "failed": result})
                continue
            k = len(get_effect(name).parameters)
            gain = delta_bic(current, blocks(runs, result.residuals), k, stated=True)
            errors = component_errors(runs, result.residuals)
            ranking.append({"effect": name, "delta_bic": gain, "errors": errors, "fit": result})
        scored = sorted(
            (r for r in ranking if "delta_bic" in r), key=lambda r: r["delta_bic"], reverse=True
        )
        step = Step6([public_entry(r) for r in ranking], None, "no candidate could be fitted")
        out.steps.append(step)
        if not scored:
            return None
        worst = max(out.final_errors, key=out.final_errors.__getitem__)
        excess = out.final_errors[worst] - 1.0

        pooled = pooled_error(out.final_errors)

        def from_worst(entry: dict) -> float:
            gone = out.final_errors[worst] - entry["errors"][worst]
            return gone / excess if excess > 0 else 0.0

        def from_pooled(entry: dict) -> float:
            gone = pooled - pooled_error(entry["errors"])
            return gone / (pooled - 1.0) if pooled > 1.0 else 0.0

        def relevant_by(removed) -> list[dict]:
            return [
                r
                for r in scored
                if r["delta_bic"] > BIC_THRESHOLD and removed(r) >= MIN_EXCESS_REMOVED
            ]

        # the most significant candidate that is also relevant (one that fits
        # other components better but leaves the worst where it was does not
        # block the one that explains it); when none touches the worst, the
        # one that removes most of the error pooled over the components (two
        # effects, each leaving the other's components off: the first enters)
        removed_by, measure = from_worst, f"{worst}'s error"
        relevant = relevant_by(from_worst)
        if not relevant and relevant_by(from_pooled):
            removed_by, measure = from_pooled, "the pooled error"
            relevant = relevant_by(from_pooled)
        best = relevant[0] if relevant else scored[0]
        removed = removed_by(best)
        if best["delta_bic"] <= BIC_THRESHOLD:
            step.why = (
                f"{best['effect']} is the best but not significant (delta BIC "
                f"{best['delta_bic']:.3g} <= {BIC_THRESHOLD:g})"
            )
            return None
        if removed < MIN_EXCESS_REMOVED:
            step.why = (
                f"{best['effect']} is significant (delta BIC {best['delta_bic']:.3g}) but removes "
                f"{100 * removed:.0f} % of {worst}'s error above the noise, and less of the "
                f"pooled error (at least {100 * MIN_EXCESS_REMOVED:.0f} % needed)"
            )
            return None
        step.chosen = best["effect"]
        step.why = (
            f"{best['effect']}: delta BIC {best['delta_bic']:.4g}, removes {100 * removed:.0f} % "
            f"of {measure} above the noise"
        )
        fit = out.fit = best["fit"]
        out.final_errors = best["errors"]
        current = blocks(runs, fit.residuals)
        alike = lookalikes(
            best,
            relevant,
            INDISTINGUISHABLE_BIC,
            lambda r: r["delta_bic"],
            lambda r: (r["effect"],),
            inclusive=False,
        )
        out.lookalikes_of[best["effect"]] = [r["effect"] for r in alike]
        for r in alike:  # the selection so far with the one, or the other
            out.pairs[best["effect"], r["effect"]] = (best["fit"], r["fit"])
        return best["effect"]

    forward(effects, out.selected, max_effects, round_)
    if out.selected and out.fit is not None and swap:
        _swap_step(runs, out, workers, progress)
    if separate:
        _separate(runs, out, workers, progress)
    return out


def _design_job(shared: tuple, job: tuple[int, int]) -> float | None:
    """One candidate run's distance between one pair of models."""
    runs, pairs, designs, levels = shared
    i, j = job
    return try_distance(runs, *pairs[i], designs[j][1], levels)


def _separate(runs: Sequence[Run6], out: Diagnosis6, workers: int, progress: bool) -> None:
    """Each selected effect's separating runs from its first
    :data:`MAX_SEPARATED` look-alikes (step 6 of the module), the candidate
    runs of every pair in ``workers`` processes; a look-alike it cannot seek
    one for says why."""
    wanted = [(s, o) for s in out.selected for o in out.lookalikes_of.get(s, [])[:MAX_SEPARATED]]
    pairs = [p for p in wanted if p in out.pairs]
    designs = candidate_runs(runs)
    jobs = [(i, j) for i in range(len(pairs)) for j in range(len(designs))]
    shared = (list(runs), [out.pairs[p] for p in pairs], designs, mean_levels(runs))
    results = pool_map(
        _design_job, jobs, workers, progress=progress, label="separating runs", shared=shared
    )
    distances: dict[tuple[str, str], dict[str, float | None]] = {p: {} for p in pairs}
    for (i, j), d in zip(jobs, results, strict=True):
        distances[pairs[i]][designs[j][0]] = d
    for name, other in wanted:
        entry: dict = {"effects": [name, other], "run": None}
        if (name, other) not in out.pairs:
            entry["why"] = (
                "the swap step changed the selection after the look-alike was found, so "
                "no two fitted models differ in these effects alone"
            )
        else:
            sep = separation(*out.pairs[name, other], designs, distances[name, other])
            if sep is None:
                entry["why"] = "none of the candidate runs could be simulated on this rig"
            else:
                entry.update(sep, hint=get_effect(other).separation_hint)
        out.separations.setdefault(name, []).append(entry)
