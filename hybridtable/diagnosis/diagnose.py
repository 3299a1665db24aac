"""Which physical effect is the rig model missing? Fit, rank, select.

:func:`diagnose` fits every registered candidate effect (the library of
:mod:`hybridtable.diagnosis.library`, plug-ins of :mod:`hybridtable.diagnosis.registry`)
to a set of recorded runs and ranks them:

1. **Residuals.** The replay (:mod:`hybridtable.measurement.replay`: the recorded command
   through table, contact and force sensor) predicts ``f_mea`` and ``p_act``;
   the residuals of each run and channel are *prewhitened* with an AR(1) noise
   model estimated without any model from the no-contact ticks
   (:func:`~hybridtable.measurement.noise_model.estimate_noise`) and divided by the innovations' standard
   deviation, so that under a right model they are white with unit variance.
2. **Fit.** ``scipy.optimize.least_squares`` (bounded, in units of each
   parameter's typical change) on the stacked whitened residuals of all runs,
   from the effect's start values and its data-driven starts.
3. **Criterion.** ``delta_bic = sum_b N_b ln(RSS_b,before / RSS_b,after) -
   dp ln N`` over the blocks ``b`` (run x channel), each with its own noise
   level (profiled out), ``N`` the whitened samples: > 0 favours the effect,
   and :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD` (10) is very strong evidence.
4. **Held-out check.** Leave-one-run-out: the effect fitted on the other runs
   predicts the held-out run; ``z = sum dSSE / (2 sqrt(sum |dy|^2))`` with
   ``dSSE`` the fall of the held-out run's whitened squared error and ``dy``
   the change of its prediction. Without the effect in the data ``z`` is
   normal with mean ``-|dy|/2 <= 0`` and unit variance; significant needs
   ``z >`` :data:`~hybridtable.diagnosis.settings.Z_THRESHOLD` (3) as well as the BIC test (one run: BIC only).
5. **Verdict and forward selection.** The significant effect with the largest
   ``delta_bic`` is the verdict (``none`` without one); it joins the model and
   the remaining effects (those not touching the same part) are fitted again
   jointly with it, until nothing significant is left: the *staircase*.
   Effects seen only in the closed loop (``mass_error``) are tested last, on
   the closed loop's spacecraft velocity with the physics selected so far.
6. **Look-alikes.** Two significant effects whose ``delta_bic`` differ by less
   than :data:`~hybridtable.diagnosis.settings.INDISTINGUISHABLE_BIC` (6) are indistinguishable on the data;
   :func:`~hybridtable.diagnosis.design.separating_run` simulates candidate runs (other approach velocity,
   other spacecraft mass) with both fitted models and names the one whose
   predictions differ most.

"Error" in the results is the RMS residual in units of the noise (pooled over
runs and both channels, each divided by its model-free noise RMS): 1.0 is the
noise floor.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence

from hybridtable.diagnosis.candidates import (
    Candidate,
    Diagnosis,
    closed_loop_summary,
    evaluate_candidate,
    mark_lookalikes,
    rank_candidates,
    velocity_error,
)
from hybridtable.diagnosis.design import separating_run
from hybridtable.diagnosis.effects import ModelSpec, RigScale
from hybridtable.diagnosis.evaluate import Evaluator, prepare_runs
from hybridtable.diagnosis.fit import (
    Fit,
    HeldOut,
    delta_bic,
    fit_effects,
    heldout,
    model_spec,
    pooled_error,
    residual_probe,
)
from hybridtable.diagnosis.registry import effect_names, get_effect
from hybridtable.diagnosis.settings import BIC_THRESHOLD, FIT_ACCURACY, Z_THRESHOLD
from hybridtable.measurement.run_format import Run

__all__ = [
    "diagnose",
]


# -- the procedure -------------------------------------------------------------
def _pool_map(func, jobs, workers: int):
    if workers <= 1 or len(jobs) <= 1:
        return [func(j) for j in jobs]
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("fork")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        return list(pool.map(func, jobs))


_STATE: dict = {}


def _candidate_job(job):
    ev, base_fit, base_error, residuals = (
        _STATE["ev"],
        _STATE["base_fit"],
        _STATE["base_error"],
        _STATE["residuals"],
    )
    name, always, stage = job
    sims = ev.simulations
    c = evaluate_candidate(ev, base_fit, base_error, get_effect(name), residuals, always, stage)
    return c, ev.simulations - sims


def _run_round(ev, base_fit, base_error, names, always_heldout, stage, workers, progress):
    residuals = residual_probe(ev.data, base_fit.evaluations) if stage == "replay" else []
    _STATE.update(ev=ev, base_fit=base_fit, base_error=base_error, residuals=residuals)
    jobs = [(n, always_heldout, stage) for n in names]
    # Expensive effects first, so two workers finish together.
    jobs.sort(key=lambda j: -len(get_effect(j[0]).parameters))
    if workers > 1 and len(jobs) > 1:
        if progress:
            print(
                f"fitting {len(jobs)} effect(s) ({stage}) in {workers} processes...",
                file=sys.stderr,
            )
        out = _pool_map(_candidate_job, jobs, workers)
        ev.simulations += sum(s for _, s in out)
        cands = [c for c, _ in out]
    else:
        cands = []
        iterator = jobs
        if progress:
            from tqdm import tqdm

            iterator = tqdm(jobs, desc=f"fit {stage}", unit="effect", file=sys.stderr, leave=False)
        for job in iterator:
            cands.append(_candidate_job(job)[0])
    _STATE.clear()
    rank_candidates(cands)
    mark_lookalikes(cands)
    return cands


def diagnose(
    runs: Sequence[Run],
    effects: Sequence[str] | None = None,
    max_effects: int = 3,
    workers: int | None = None,
    separate: bool = True,
    progress: bool = False,
    accuracy: float = FIT_ACCURACY,
) -> Diagnosis:
    """Name the physical effect the rig model is missing (see the module doc).

    Parameters
    ----------
    runs : sequence of Run
        Runs of one rig (same sample rate), each with a contact.
    effects : sequence of str, optional
        Candidate effects (default: every registered one).
    max_effects : int
        Most effects the forward selection adds.
    workers : int, optional
        Processes fitting candidates in parallel (default: up to 2).
    separate : bool
        Look for a run separating look-alikes of the verdict.

    Raises
    ------
    MeasurementError
        If a run cannot be diagnosed (:func:`prepare_runs`).
    """
    import time

    t0 = time.perf_counter()
    data = prepare_runs(runs)
    scale = RigScale.from_runs(runs)
    names = list(effects) if effects is not None else list(effect_names())
    for n in names:
        get_effect(n)
    if workers is None:
        workers = min(2, os.cpu_count() or 1)
    ev = Evaluator(data, scale, accuracy)
    replay_names = [n for n in names if get_effect(n).stage == "replay"]
    loop_names = [n for n in names if get_effect(n).stage == "closed_loop"]

    nominal = fit_effects(ev, [], stage="replay")
    base_fit = nominal
    base_error = pooled_error(data, nominal.evaluations)
    staircase = [
        {
            "effects": [],
            "parameters": {},
            "error": base_error[0],
            "heldout_error": base_error[0],
            "channel_error": base_error[1],
            "delta_bic": 0.0,
        }
    ]
    rounds: list[list[Candidate]] = []
    selected: list[str] = []
    while len(selected) < max_effects:
        pool = [
            n
            for n in replay_names
            if n not in selected
            and not any(get_effect(n).conflicts_with(get_effect(s)) for s in selected)
        ]
        if not pool:
            break
        cands = _run_round(ev, base_fit, base_error, pool, not rounds, "replay", workers, progress)
        rounds.append(cands)
        best = next((c for c in cands if c.significant), None)
        if best is None:
            break
        selected.append(best.effect)
        base_fit = best.fit
        base_error = (best.error_after, best.channel_error_after)
        staircase.append(
            {
                "effects": list(selected),
                "parameters": {n: dict(v) for n, v in best.model_values.items()},
                "error": best.error_after,
                "heldout_error": best.heldout_error_after,
                "channel_error": best.channel_error_after,
                "delta_bic": best.delta_bic,
            }
        )

    # Closed-loop effects, on top of the physics selected.
    physics_values = dict(base_fit.values)
    loop_cands: list[Candidate] = []
    if loop_names:
        ev.inject_noise(base_fit.evaluations)

        def closed_loop_base() -> Fit:
            # The selected physics, every value held: the closed loop's residuals.
            return fit_effects(
                ev,
                list(base_fit.effects),
                start=physics_values,
                fixed=physics_values,
                stage="closed_loop",
            )

        # Twice: the first residuals calibrate the closed loop's whitening, the
        # second evaluation is whitened with it.
        ev.calibrate_closed_loop(closed_loop_base().evaluations)
        loop_base = closed_loop_base()
        loop_error = velocity_error(loop_base.evaluations)
        for n in loop_names:
            effect = get_effect(n)
            names_n = [*base_fit.effects, n]
            fit = fit_effects(
                ev,
                names_n,
                start={**physics_values, n: effect.start(scale)},
                fixed=physics_values,
                stage="closed_loop",
            )
            dbic = delta_bic(loop_base, fit)
            held = (
                heldout(
                    ev,
                    loop_base.evaluations,
                    names_n,
                    fit.values,
                    "closed_loop",
                    fixed=physics_values,
                )
                if dbic > BIC_THRESHOLD
                else HeldOut(math.nan, math.nan, [])
            )
            err_after = velocity_error(fit.evaluations)
            significant = bool(
                dbic > BIC_THRESHOLD
                and not fit.failed
                and (len(data) < 2 or (math.isfinite(held.z) and held.z > Z_THRESHOLD))
            )
            loop_cands.append(
                Candidate(
                    effect=n,
                    stage="closed_loop",
                    parameters=dict(fit.values[n]),
                    model=names_n,
                    model_values={k: dict(v) for k, v in fit.values.items()},
                    error_before=loop_error[0],
                    error_after=err_after[0],
                    heldout_error_after=math.nan,
                    delta_bic=dbic,
                    heldout_z=held.z,
                    significant=significant,
                    channel_error_before=loop_error[1],
                    channel_error_after=err_after[1],
                    nfev=fit.nfev,
                    notes=["closed loop: errors are v_des RMS in m/s"],
                    fit=fit,
                )
            )
        rank_candidates(loop_cands)
        mark_lookalikes(loop_cands)
        for c in loop_cands:
            if c.significant and len(selected) < max_effects:
                selected.append(c.effect)
                physics_values[c.effect] = dict(c.parameters)
                staircase.append(
                    {
                        "effects": list(selected),
                        "parameters": {n: dict(v) for n, v in physics_values.items()},
                        "error": staircase[-1]["error"],
                        "heldout_error": staircase[-1]["heldout_error"],
                        "channel_error": {
                            **staircase[-1]["channel_error"],
                            **c.channel_error_after,
                        },
                        "delta_bic": c.delta_bic,
                        "stage": "closed_loop",
                    }
                )
                break
    selected_values = {n: dict(physics_values[n]) for n in selected}
    verdict = selected[0] if selected else "none"

    # Look-alikes of the verdict: what run would separate them.
    first = rounds[0] if rounds else []
    if separate:
        for c in first + loop_cands:
            if c.effect == verdict and c.indistinguishable_from:
                spec_a = model_spec([c.effect], {c.effect: c.parameters}, scale)
                for other in c.indistinguishable_from:
                    o = next(x for x in first + loop_cands if x.effect == other)
                    spec_b = model_spec([o.effect], {o.effect: o.parameters}, scale)
                    sep = separating_run(ev, spec_a, spec_b)
                    if sep is not None:
                        sep["effects"] = [c.effect, o.effect]
                        hint = get_effect(o.effect).separation_hint
                        sep["hint"] = hint
                        o.separation = sep
                        c.separation = c.separation or sep

    final_spec = model_spec(selected, selected_values, scale)
    final = {i: ev.evaluate(final_spec, i) for i in range(len(data))}
    closed = {
        "before": closed_loop_summary(ev, ModelSpec()),
        "after": closed_loop_summary(ev, final_spec),
    }
    notes = []
    if len(data) < 2:
        notes.append("one run: significance from the BIC alone (no held-out run)")
    return Diagnosis(
        data=data,
        scale=scale,
        verdict=verdict,
        selected=selected,
        selected_values=selected_values,
        rounds=rounds,
        staircase=staircase,
        closed_loop_candidates=loop_cands,
        nominal=nominal.evaluations,
        final=final,
        closed_loop=closed,
        simulations=ev.simulations,
        wall_time_s=time.perf_counter() - t0,
        notes=notes,
    )
