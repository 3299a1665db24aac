"""Candidates of a diagnosis: one fitted effect with its evidence, the ranking,
look-alikes, and the :class:`Diagnosis` result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridtable.diagnosis.evaluate import Evaluation, Evaluator, RunData
from hybridtable.diagnosis.fit import (
    Fit,
    HeldOut,
    delta_bic,
    fit_effects,
    heldout,
    model_spec,
    pooled_error,
)
from hybridtable.diagnosis.goodness import FALSE_ALARM_RATE, GoodnessOfFit
from hybridtable.diagnosis.settings import (
    BIC_THRESHOLD,
    EXPLAINED_MAX_ERROR,
    INDISTINGUISHABLE_BIC,
    MIN_EXCESS_REMOVED,
    TIE_BIC,
    Z_THRESHOLD,
)
from hybridtable.effects.effect import Effect
from hybridtable.effects.registry import EFFECTS, get_effect
from hybridtable.effects.selection import lookalikes
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.measurement.audit_findings import Audit

__all__ = [
    "Candidate",
    "Diagnosis",
    "evaluate_candidate",
    "judge",
    "mark_lookalikes",
    "closed_loop_summary",
    "rank_candidates",
]


# -- candidates and the diagnosis ----------------------------------------------
@dataclass
class Candidate:
    """One effect fitted on top of a base model in one round."""

    effect: str
    stage: str
    parameters: dict[str, float]
    model: list[str]
    model_values: dict[str, dict[str, float]]
    error_before: float
    error_after: float
    heldout_error_after: float
    delta_bic: float
    heldout_z: float
    significant: bool
    channel_error_before: dict[str, float]
    channel_error_after: dict[str, float]
    indistinguishable_from: list[str] = field(default_factory=list)
    separation: dict | None = None
    nfev: int = 0
    notes: list[str] = field(default_factory=list)
    fit: Fit | None = None
    #: Held-out error of the model without the effect (noise units).
    heldout_error_before: float = math.nan
    #: Fraction of the held-out excess error (error - 1) the effect removes.
    excess_removed: float = math.nan
    #: Significant and practically relevant: may enter the model.
    accepted: bool = False
    #: Why it was accepted or rejected, in words.
    reason: str = ""

    def to_json(self) -> dict:
        return {
            "effect": self.effect,
            "stage": self.stage,
            "parameters": dict(self.parameters),
            "units": {p.name: p.unit for p in get_effect(self.effect).parameters},
            "error_before": self.error_before,
            "error_after": self.error_after,
            "heldout_error_after": self.heldout_error_after,
            "delta_bic": self.delta_bic,
            "heldout_z": self.heldout_z,
            "significant": self.significant,
            "heldout_error_before": self.heldout_error_before,
            "excess_removed": self.excess_removed,
            "accepted": self.accepted,
            "reason": self.reason,
            "indistinguishable_from": list(self.indistinguishable_from),
            "separating_run": self.separation,
            "channel_error_before": dict(self.channel_error_before),
            "channel_error_after": dict(self.channel_error_after),
            "notes": list(self.notes),
            **({"note": "; ".join(why)} if (why := self._unset_reasons()) else {}),
        }

    def _unset_reasons(self) -> list[str]:
        """Why figures of :meth:`to_json` are null, in words."""
        why = []
        if not math.isfinite(self.heldout_z) or not math.isfinite(self.heldout_error_after):
            why.append(
                "heldout_error_after and heldout_z null: the held-out test runs only for an "
                f"effect whose fit is significant (delta_bic > {BIC_THRESHOLD:g}) on two runs "
                "or more"
            )
        if not math.isfinite(self.excess_removed):
            why.append(
                "excess_removed null: no held-out error after the effect, or no excess error "
                "(the model without it is within the noise)"
            )
        if self.separation is None:
            why.append("separating_run null: no other effect fits as well as this one")
        for name in ("delta_bic", "error_after", "heldout_error_before"):
            if not math.isfinite(getattr(self, name)):
                why.append(f"{name} null: not computed (the fit failed or did not run)")
        return why


@dataclass
class Diagnosis:
    """Everything :func:`~hybridtable.diagnosis.diagnose.diagnose` found.

    ``selected`` holds the physical effects fitted (``selected_values`` their
    values); the audit's findings about the rig computer are in ``audit``;
    :attr:`named` is both. ``explained`` says the final model passed the end
    test (``goodness``) with a held-out error at most
    :data:`~hybridtable.diagnosis.settings.EXPLAINED_MAX_ERROR`.
    """

    data: list[RunData]
    scale: RigScale
    verdict: str
    selected: list[str]
    selected_values: dict[str, dict[str, float]]
    rounds: list[list[Candidate]]
    staircase: list[dict]
    nominal: dict[int, Evaluation]
    final: dict[int, Evaluation]
    closed_loop: dict[str, dict]
    simulations: int
    audit: Audit
    goodness: GoodnessOfFit
    explained: bool
    search: list[dict] = field(default_factory=list)
    lookalikes: dict[str, list[str]] = field(default_factory=dict)
    wall_time_s: float = math.nan
    notes: list[str] = field(default_factory=list)
    #: Standard errors of ``selected_values`` (:func:`~hybridtable.diagnosis.fit.parameter_std`).
    selected_std: dict[str, dict[str, float | None]] = field(default_factory=dict)

    @property
    def ranking(self) -> list[Candidate]:
        """The first round: every effect against the nominal model, by ``delta_bic``."""
        return list(self.rounds[0]) if self.rounds else []

    @property
    def named(self) -> list[str]:
        """The audit's findings (``mass_error``, ...) then the physical effects selected."""
        return [*self.audit.effects, *self.selected]

    @property
    def heldout_error(self) -> float:
        """Held-out error of the final model (noise units)."""
        return float(self.staircase[-1]["heldout_error"])

    def final_spec(self) -> ModelSpec:
        return model_spec(self.selected, self.selected_values, self.scale)

    def computer_values(self) -> dict[str, dict[str, float]]:
        """The audit's findings as verdict parameters (``mass_error``: ``mass_ratio``)."""
        out: dict[str, dict[str, float]] = {}
        for f in self.audit.findings:
            vals = out.setdefault(f.effect, {})
            if f.key == "spacecraft_mass_kg":
                vals["mass_ratio"] = f.used_value / f.json_value
            vals[f.key] = f.used_value
        return out

    def remaining(self) -> dict:
        """What the final model leaves: held-out error, the end test, where it misfits."""
        g = self.goodness
        return {
            "heldout_error": self.heldout_error,
            "error": float(self.staircase[-1]["error"]),
            "channel_error": dict(self.staircase[-1]["channel_error"]),
            "test_passed": g.passed,
            "p_value": g.p_value,
            "false_alarm_rate": g.false_alarm_rate,
            "tests": g.tests,
            "where": g.where.to_json() if g.where else None,
            "goodness_of_fit": g.to_json(),
        }

    def to_json(self) -> dict:
        named_values = {**self.computer_values(), **self.selected_values}
        return {
            "verdict": self.verdict,
            "explained": self.explained,
            "selected": self.named,
            "physical": list(self.selected),
            "computer": list(self.audit.effects),
            "parameters": {n: dict(v) for n, v in named_values.items()},
            "parameter_std": {n: dict(v) for n, v in self.selected_std.items()},
            "lookalikes": {k: list(v) for k, v in self.lookalikes.items()},
            "remaining": self.remaining(),
            "audit": self.audit.to_json(),
            "ranking": [c.to_json() for c in self.ranking],
            "staircase": list(self.staircase),
            "rounds": [[c.to_json() for c in r] for r in self.rounds],
            "search": list(self.search),
            "closed_loop": self.closed_loop,
            "runs": [
                {
                    "run_id": d.run_id,
                    "compensator": d.run.info.compensator,
                    "initial_velocity_m_per_s": d.run.info.initial_velocity_m_per_s,
                    "noise": {
                        c: {
                            "rms": m.sigma,
                            "ar1": m.phi,
                            "ar": list(m.coefficients),
                            "samples": m.samples,
                        }
                        for c, m in d.noise.items()
                    },
                    "notes": list(d.notes),
                }
                for d in self.data
            ],
            "criteria": {
                "bic_threshold": BIC_THRESHOLD,
                "z_threshold": Z_THRESHOLD,
                "min_excess_removed": MIN_EXCESS_REMOVED,
                "explained_max_error": EXPLAINED_MAX_ERROR,
                "false_alarm_rate": FALSE_ALARM_RATE,
                "indistinguishable_bic": INDISTINGUISHABLE_BIC,
                "error_unit": "RMS residual / noise RMS, pooled over runs, f_mea and p_act",
            },
            "simulations": self.simulations,
            "wall_time_s": self.wall_time_s,
            "notes": list(self.notes),
        }


def evaluate_candidate(
    ev: Evaluator,
    base_fit: Fit,
    base_error: tuple[float, dict[str, float]],
    effect: Effect,
    residuals,
    base_heldout: float = math.nan,
) -> Candidate:
    """Fit the replay effect ``effect`` on top of ``base_fit`` and judge it (:func:`judge`).

    ``base_heldout`` is the held-out error of the base model (noise units;
    NaN: its in-sample error), against which the effect's practical
    significance is measured.
    """
    names = [*base_fit.effects, effect.name]
    start = {**base_fit.values, effect.name: effect.start(ev.scale)}
    starts = effect.fit_starts(ev.scale, residuals)
    if base_fit.effects:
        # The new effect alone on the fixed base first; jointly only if it helps.
        fit = fit_effects(ev, names, start=start, fixed=base_fit.values, starts=starts)
        fit.n_parameters += base_fit.n_parameters
        if delta_bic(base_fit, fit) > 0.0:
            joint = fit_effects(ev, names, start=fit.values)
            if delta_bic(base_fit, joint) > delta_bic(base_fit, fit):
                joint.nfev += fit.nfev
                fit = joint
    else:
        fit = fit_effects(ev, names, start=start, starts=starts)
    err_after, chan_after = pooled_error(ev.data, fit.evaluations)
    c = Candidate(
        effect=effect.name,
        stage="replay",
        parameters=dict(fit.values[effect.name]),
        model=names,
        model_values={n: dict(v) for n, v in fit.values.items()},
        error_before=base_error[0],
        error_after=err_after,
        heldout_error_after=math.nan,
        delta_bic=math.nan,
        heldout_z=math.nan,
        significant=False,
        channel_error_before=base_error[1],
        channel_error_after=chan_after,
        nfev=fit.nfev,
        fit=fit,
        heldout_error_before=base_heldout if math.isfinite(base_heldout) else base_error[0],
    )
    judge(ev, base_fit, c)
    return c


def judge(ev: Evaluator, base_fit: Fit, c: Candidate) -> None:
    """Decide whether the fitted candidate ``c`` (its :attr:`Candidate.fit`) may
    enter the model ``base_fit``, and say why.

    It must be *significant*: ``delta_bic >`` :data:`BIC_THRESHOLD` and, with
    two runs or more, a leave-one-run-out ``z >`` :data:`Z_THRESHOLD` (a
    one-sided false-alarm rate of 0.13 % per candidate); and *practically
    relevant*: remove at least :data:`MIN_EXCESS_REMOVED` of the held-out
    excess error ``e_before - 1`` (noise units; in-sample with one run).
    """
    fit = c.fit
    names = list(fit.effects)
    dbic = delta_bic(base_fit, fit)
    c.delta_bic = dbic
    if fit.failed:
        c.notes.append("a model run failed during the fit")
    if dbic > BIC_THRESHOLD:
        held = heldout(ev, base_fit.evaluations, names, fit.values, c.stage)
    else:
        held = HeldOut(math.nan, math.nan, [])
    c.heldout_z = held.z
    c.heldout_error_after = held.error
    one_run = len(ev.data) < 2
    if one_run and "one run: no leave-one-run-out check" not in c.notes:
        c.notes.append("one run: no leave-one-run-out check")
    c.significant = bool(
        dbic > BIC_THRESHOLD
        and not fit.failed
        and (one_run or (math.isfinite(held.z) and held.z > Z_THRESHOLD))
    )
    after = c.error_after if one_run else held.error
    excess = c.heldout_error_before - 1.0
    if math.isfinite(after) and excess > 0.0:
        c.excess_removed = (c.heldout_error_before - after) / excess
    if fit.failed:
        c.reason = "a model run failed during the fit"
    elif not dbic > BIC_THRESHOLD:
        c.reason = f"not significant: delta_bic {dbic:.1f} <= {BIC_THRESHOLD:g}"
    elif not c.significant:
        c.reason = (
            f"not significant on held-out runs: z {held.z:.1f} <= {Z_THRESHOLD:g} "
            "(fitted on the other runs, it does not predict the held-out run better)"
        )
    elif not excess > 0.0:
        c.reason = (
            f"the model is at the noise floor already (held-out error "
            f"{c.heldout_error_before:.3f}x the noise)"
        )
    elif not c.excess_removed >= MIN_EXCESS_REMOVED:
        c.reason = (
            f"significant but removes only {c.excess_removed:.0%} of the held-out excess "
            f"error ({c.heldout_error_before:.3f} -> {after:.3f}x the noise; needs "
            f"{MIN_EXCESS_REMOVED:.0%})"
        )
    else:
        c.accepted = True
        c.reason = (
            f"significant (delta_bic {dbic:.1f}"
            + ("" if one_run else f", held-out z {held.z:.1f}")
            + f") and removes {c.excess_removed:.0%} of the held-out excess error "
            f"({c.heldout_error_before:.3f} -> {after:.3f}x the noise)"
        )


def mark_lookalikes(candidates: list[Candidate]) -> None:
    """Name, on each accepted candidate, the other accepted ones whose ``delta_bic`` is within
    :data:`~hybridtable.diagnosis.settings.INDISTINGUISHABLE_BIC`
    (:func:`~hybridtable.effects.selection.lookalikes`: the data cannot tell them apart)."""
    sig = [c for c in candidates if c.accepted]
    for c in sig:
        alike = lookalikes(
            c, sig, INDISTINGUISHABLE_BIC, lambda x: x.delta_bic, lambda x: [x.effect], False
        )
        c.indistinguishable_from = [o.effect for o in alike]


def _cor_of(v_des: np.ndarray, f_comp: np.ndarray, v0: float) -> float:
    on = np.flatnonzero(np.asarray(f_comp) != 0.0)
    if on.size == 0:
        return math.nan
    v_in = float(v_des[on[0] - 1]) if on[0] > 0 else v0
    return abs(float(v_des[-1])) / abs(v_in)


def closed_loop_summary(ev: Evaluator, spec: ModelSpec) -> dict:
    """Closed-loop v_des RMS error and CoR error of a model (noise-free, as
    ``hybridtable compare``), per run."""
    rows = []
    injected, ev.injected_noise = ev.injected_noise, [None] * len(ev.data)
    for i, d in enumerate(ev.data):
        e = ev.evaluate(spec, i, "closed_loop")
        run = d.run
        cor_meas = _cor_of(run.v_des_m_per_s, run.f_comp_n, run.info.initial_velocity_m_per_s)
        if e.failed:
            rows.append({"run_id": d.run_id, "v_des_rms_error_m_per_s": math.nan})
            continue
        cor_model = _cor_of(
            e.prediction["v_des_m_per_s"],
            e.prediction["f_comp_n"],
            run.info.initial_velocity_m_per_s,
        )
        rows.append(
            {
                "run_id": d.run_id,
                "v_des_rms_error_m_per_s": float(
                    np.sqrt(np.mean(e.residual["v_des_m_per_s"] ** 2))
                ),
                "cor_measured": cor_meas,
                "cor_model": cor_model,
                "cor_error": cor_model - cor_meas,
            }
        )
    ev.injected_noise = injected
    return {"runs": rows}


def rank_candidates(cands: list[Candidate]) -> None:
    """Sort by ``delta_bic``, ties (:data:`TIE_BIC`) broken by fewer
    parameters, then registration order (a tie between, e.g., a stiffness
    error and a series compliance, which predict the same, is numerical)."""
    order = {n: i for i, n in enumerate(EFFECTS)}
    cands.sort(key=lambda c: -c.delta_bic)
    for _ in range(len(cands)):
        swapped = False
        for i in range(len(cands) - 1):
            a, b = cands[i], cands[i + 1]
            if a.delta_bic - b.delta_bic < TIE_BIC and (
                len(b.parameters),
                order.get(b.effect, len(order)),
            ) < (len(a.parameters), order.get(a.effect, len(order))):
                cands[i], cands[i + 1] = b, a
                swapped = True
        if not swapped:
            break
