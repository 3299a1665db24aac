"""Which physical effect is the rig model missing, if any, and is that all?

:func:`diagnose` answers one of three ways: ``none`` (the nominal model
explains the runs), the named effect(s), or ``unexplained`` (the model misses
something no effect of the library explains); with named effects,
``explained`` says whether they account for everything.

0. **Audit of the rig computer** (:mod:`hybridtable.measurement.audit`): the
   mass, lead time, MDC stiffness and deadband the computer used are solved
   from the record by arithmetic; every mismatch with the JSON is named
   (``mass_error``, ``lead_time_error``, ...), never fitted.
1. **Residuals.** The replay (:mod:`hybridtable.measurement.replay`: the recorded command
   through table, contact and force sensor) predicts ``f_mea`` and ``p_act``;
   the residuals of each run and channel are *prewhitened* with an AR(p)
   noise model estimated without any model from the no-contact ticks
   (:func:`~hybridtable.measurement.noise_model.estimate_noise`), so that
   under a right model they are white with unit variance.
2. **Fit.** ``scipy.optimize.least_squares`` (bounded, in units of each
   parameter's typical change) on the stacked whitened residuals of all runs,
   from the effect's start values and its data-driven starts.
3. **Significance.** ``delta_bic = sum_b N_b ln(RSS_b,before / RSS_b,after) -
   dp ln N`` over the blocks ``b`` (run x channel) must exceed
   :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD` (10), and the
   leave-one-run-out ``z`` (the effect fitted on the other runs predicting the
   held-out one) :data:`~hybridtable.diagnosis.settings.Z_THRESHOLD` (3: a
   false-alarm rate of 0.13 % per candidate).
4. **Practical significance.** The effect must also remove at least
   :data:`~hybridtable.diagnosis.settings.MIN_EXCESS_REMOVED` (25 %) of the
   held-out excess error (held-out error minus the noise floor, 1). Every
   rejected candidate says why.
5. **Forward selection.** The accepted effect with the largest ``delta_bic``
   joins the model and the others are fitted again on top of it, until none is
   accepted (the *staircase*).
6. **End test** (:mod:`hybridtable.diagnosis.goodness`): the final model's
   whitened residuals against the noise, per run, channel, contact phase and
   time scale, at a false-alarm rate of 1 % per set.
7. **Pairs and swaps.** If the end test fails, the first round's best
   candidates are fitted in pairs, and each selected effect is swapped for
   each other candidate; a model with a better BIC whose every effect is
   accepted given the others (drop-one tests) replaces the selection. Two
   effects whose influence on the CoR cancels are found this way.
8. **Verdict.** ``explained`` = the end test passes and the held-out error is
   at most :data:`~hybridtable.diagnosis.settings.EXPLAINED_MAX_ERROR`; with
   nothing named the verdict is ``none`` if explained, else ``unexplained``.
9. **Look-alikes.** Accepted effects whose ``delta_bic`` differ by less than
   :data:`~hybridtable.diagnosis.settings.INDISTINGUISHABLE_BIC` (6) cannot be
   told apart on the data; :func:`~hybridtable.diagnosis.design.separating_run`
   names the run that would.

"Error" in the results is the RMS residual in units of the noise (pooled over
runs and both channels, each divided by its model-free noise RMS): 1.0 is the
noise floor.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

from hybridtable.diagnosis.candidates import (
    Candidate,
    Diagnosis,
    closed_loop_summary,
    evaluate_candidate,
    mark_lookalikes,
    rank_candidates,
)
from hybridtable.diagnosis.design import separating_run
from hybridtable.diagnosis.evaluate import Evaluator, prepare_runs
from hybridtable.diagnosis.fit import (
    Fit,
    fit_effects,
    model_spec,
    parameter_std,
    pooled_error,
    residual_probe,
)
from hybridtable.diagnosis.goodness import goodness_of_fit
from hybridtable.diagnosis.search import pairs_and_swaps
from hybridtable.diagnosis.settings import EXPLAINED_MAX_ERROR, FIT_ACCURACY
from hybridtable.effects.model_file import FittedEffect, RigModel
from hybridtable.effects.registry import default_effects, get_effect
from hybridtable.effects.search import forward
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.effects.workers import pool_map, worker_count
from hybridtable.measurement.audit import audit_runs
from hybridtable.measurement.run_format import Run

__all__ = [
    "diagnose",
    "model_from_diagnosis",
]


# -- one round of candidates ----------------------------------------------------
def _candidate_job(shared, name):
    ev, base_fit, base_error, residuals, base_heldout = shared
    sims = ev.simulations
    c = evaluate_candidate(ev, base_fit, base_error, get_effect(name), residuals, base_heldout)
    return c, ev.simulations - sims


def _run_round(ev, base_fit, base_error, base_heldout, names, workers, progress):
    residuals = residual_probe(ev.data, base_fit.evaluations)
    shared = (ev, base_fit, base_error, residuals, base_heldout)
    # Expensive effects first, so two workers finish together.
    jobs = sorted(names, key=lambda n: -len(get_effect(n).parameters))
    label = f"fit {len(jobs)} effect(s)"
    before = ev.simulations
    out = pool_map(_candidate_job, jobs, workers, progress, label, shared=shared)
    # each job's count: in a forked worker it is lost, in this process it is in already
    ev.simulations = before + sum(s for _, s in out)
    cands = [c for c, _ in out]
    rank_candidates(cands)
    mark_lookalikes(cands)
    return cands


def _step(effects: list[str], fit: Fit, error, heldout_error: float, dbic: float, how: str) -> dict:
    return {
        "effects": list(effects),
        "parameters": {n: dict(fit.values[n]) for n in effects},
        "error": error[0],
        "heldout_error": heldout_error,
        "channel_error": error[1],
        "delta_bic": dbic,
        "how": how,
    }


def _forward(ev, names, selected, base_fit, staircase, rounds, max_effects, workers, progress):
    """Forward selection from ``selected`` (fitted as ``base_fit``; the effect
    core's loop, :func:`~hybridtable.effects.search.forward`): add the accepted
    candidate with the largest ``delta_bic`` until none is accepted."""

    def round_(pool: list[str]) -> str | None:
        nonlocal base_fit
        base_error = (staircase[-1]["error"], staircase[-1]["channel_error"])
        cands = _run_round(
            ev,
            base_fit,
            base_error,
            staircase[-1]["heldout_error"],
            pool,
            workers,
            progress,
        )
        rounds.append(cands)
        best = next((c for c in cands if c.accepted), None)
        if best is None:
            return None
        for c in cands:
            if c.accepted and c is not best:
                c.reason += f"; outranked by {best.effect} (delta_bic {best.delta_bic:.1f})"
        base_fit = best.fit
        held = (
            best.heldout_error_after
            if math.isfinite(best.heldout_error_after)
            else best.error_after
        )
        staircase.append(
            _step(
                [*selected, best.effect],
                best.fit,
                (best.error_after, best.channel_error_after),
                held,
                best.delta_bic,
                "forward selection",
            )
        )
        return best.effect

    forward(names, selected, max_effects, round_)
    return base_fit


def diagnose(
    runs: Sequence[Run],
    effects: Sequence[str] | None = None,
    max_effects: int = 3,
    workers: int | None = None,
    separate: bool = True,
    progress: bool = False,
    accuracy: float = FIT_ACCURACY,
) -> Diagnosis:
    """Name what the rig model misses, or say that nothing is, or that nothing
    in the library explains it (see the module doc).

    Parameters
    ----------
    runs : sequence of Run
        Runs of one rig (same sample rate), each with a contact.
    effects : sequence of str, optional
        Candidate effects (default: every registered one). Effects of the
        rig computer (``mass_error``) are decided by the audit, not fitted.
    max_effects : int
        Most physical effects the model may gain.
    workers : int, optional
        Processes fitting candidates in parallel (default: up to 2).
    separate : bool
        Look for a run separating look-alikes of the verdict.
    progress : bool
        Progress bars on standard error.
    accuracy : float
        Integrator accuracy of the model runs.

    Raises
    ------
    MeasurementError
        If a run cannot be diagnosed (:func:`~hybridtable.diagnosis.evaluate.prepare_runs`).
    """
    t0 = time.perf_counter()
    data = prepare_runs(runs)
    audit = audit_runs(runs)
    scale = RigScale.from_runs(runs)
    names = list(effects) if effects is not None else list(default_effects("diagnose"))
    for n in names:
        get_effect(n)
    workers = worker_count(workers)
    ev = Evaluator(data, scale, accuracy)
    ev.computer = {d.run_id: audit.computer_changes(d.run_id) for d in data}
    notes = []
    computer_effects = [n for n in names if get_effect(n).stage != "replay"]
    if computer_effects:
        notes.append(
            f"{', '.join(computer_effects)}: decided by the audit of the rig computer, not fitted"
        )
    replay_names = [n for n in names if get_effect(n).stage == "replay"]

    nominal = fit_effects(ev, [], stage="replay")
    base_error = pooled_error(data, nominal.evaluations)
    staircase = [_step([], nominal, base_error, base_error[0], 0.0, "nominal")]
    rounds: list[list[Candidate]] = []
    selected: list[str] = []
    final_fit = _forward(
        ev, replay_names, selected, nominal, staircase, rounds, max_effects, workers, progress
    )
    goodness = goodness_of_fit(data, final_fit.evaluations)

    # Pairs and swaps, when forward selection leaves a misfit.
    search: list[dict] = []
    if not goodness.passed and rounds and len(replay_names) > 1:
        found = pairs_and_swaps(
            ev, nominal, rounds[0], selected, final_fit, max_effects, workers, progress, search
        )
        if found is not None:
            fit, held, dbic = found
            selected[:] = list(fit.effects)
            staircase.append(
                _step(
                    selected,
                    fit,
                    pooled_error(data, fit.evaluations),
                    held,
                    dbic,
                    "pair and swap search",
                )
            )
            final_fit = _forward(
                ev, replay_names, selected, fit, staircase, rounds, max_effects, workers, progress
            )
            goodness = goodness_of_fit(data, final_fit.evaluations)

    selected_values = {n: dict(final_fit.values[n]) for n in selected}
    selected_std = parameter_std(ev, final_fit) if selected else {}
    heldout_error = staircase[-1]["heldout_error"]
    explained = bool(goodness.passed and heldout_error <= EXPLAINED_MAX_ERROR)
    named = [*audit.effects, *selected]
    verdict = " + ".join(named) if named else ("none" if explained else "unexplained")

    # Look-alikes of each selected effect, from the round it entered in.
    lookalikes: dict[str, list[str]] = {}
    for r in rounds:
        for c in r:
            if c.effect in selected and c.accepted and c.effect not in lookalikes:
                lookalikes[c.effect] = list(c.indistinguishable_from)
    first = rounds[0] if rounds else []
    if separate and selected:
        lead = selected[0]
        c = next((x for x in first if x.effect == lead), None)
        if c is not None and c.indistinguishable_from:
            spec_a = model_spec([c.effect], {c.effect: c.parameters}, scale)
            for other in c.indistinguishable_from:
                o = next(x for x in first if x.effect == other)
                spec_b = model_spec([o.effect], {o.effect: o.parameters}, scale)
                sep = separating_run(ev, spec_a, spec_b)
                if sep is not None:
                    sep["effects"] = [c.effect, o.effect]
                    sep["hint"] = get_effect(o.effect).separation_hint
                    o.separation = sep
                    c.separation = c.separation or sep

    final_spec = model_spec(selected, selected_values, scale)
    final = {i: final_fit.evaluations[i] for i in range(len(data))}
    computer, ev.computer = ev.computer, {}
    closed = {"before": closed_loop_summary(ev, ModelSpec())}
    ev.computer = computer
    closed["after"] = closed_loop_summary(ev, final_spec)
    if len(data) < 2:
        notes.append("one run: significance from the BIC alone (no held-out run)")
    return Diagnosis(
        data=data,
        scale=scale,
        verdict=verdict,
        selected=selected,
        selected_values=selected_values,
        selected_std={n: dict(selected_std.get(n, {})) for n in selected},
        rounds=rounds,
        staircase=staircase,
        nominal=nominal.evaluations,
        final=final,
        closed_loop=closed,
        simulations=ev.simulations,
        audit=audit,
        goodness=goodness,
        explained=explained,
        search=search,
        lookalikes=lookalikes,
        wall_time_s=time.perf_counter() - t0,
        notes=notes,
    )


def model_from_diagnosis(d: Diagnosis) -> RigModel:
    """The model a :class:`~hybridtable.diagnosis.candidates.Diagnosis` found:
    its physical effects with their fitted values and standard errors, the
    audit's rig computer per run, and the evidence of the verdict."""
    effects = [
        FittedEffect(
            n,
            dict(d.selected_values[n]),
            dict(d.selected_std.get(n, {})),
            tuple(d.selected_values[n]),
        )
        for n in d.selected
    ]
    remaining = d.remaining()
    evidence = {
        "verdict": d.verdict,
        "explained": d.explained,
        "named": list(d.named),
        "heldout_error": remaining["heldout_error"],
        "error": remaining["error"],
        "end_test_passed": remaining["test_passed"],
        "end_test_p_value": remaining["p_value"],
        "error_unit": "RMS residual / noise RMS, pooled over runs, f_mea and p_act",
    }
    computer = {x.run_id: d.audit.computer_changes(x.run_id) for x in d.data}
    return RigModel.from_runs(
        [x.run for x in d.data], effects, computer, source="diagnose", evidence=evidence
    )
