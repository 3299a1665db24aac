"""The audit of a six-axis rig computer's compensation law: the lead, the
MDC's stiffness, a gain, offsets and the dead band it used, solved from the
record.

A 6-DoF record holds the compensator's inputs and its output at every tick
(``docs/run6-format.md``, step 2): the readings ``w_mea[k]`` and
``w_mea[k-1]``, the measured pose ``q_act[k]``, the command ``q_des[k-1]``
still held, and the compensated wrench ``w_comp[k]``. On every tick with a
compensated wrench the format's law is linear in its constants:

    w_comp = a w_mea + T_lead (w_mea[k] - w_mea[k-1]) / h + s (-K (q_des[k-1] - q_act[k])) + b

with the terms taken from the law's one definition
(:func:`~hybridtable.laws.compensation.linear_terms`, as the 1-D audit's
regression, :mod:`hybridtable.measurement.audit`), ``K`` the scenario's
stiffness model at the measured pose
(:func:`~hybridtable.six_dof.compensator.stiffness_model_of`), the gain ``a``
(1), the MDC term's factor ``s`` (1 with an MDC, else 0) and an offset ``b``
per component (0). The six components of the ticks of the runs of one
compensator are solved together by least squares, each component weighted
by its own size. A value is a finding as the 1-D audit decides
(:func:`~hybridtable.measurement.audit_findings.differs`): ``lead_time_error``
(the lead used less the JSON's), ``compensator_stiffness_error`` (the MDC's
stiffness over its model's), ``compensation_law_error`` (a gain, an offset,
an MDC term the JSON's compensator does not have, or a residual above
:data:`LAW_RESIDUAL` of the signal: the computer does not compensate by the
format's law) and ``deadband_error`` (the readings it gated bound its dead
band from below, those it compensated from above).

A log whose readings carry noise the computer did not see (a logger of its
own; the format logs what the computer read) leaves a residual above that.
The constants are then not solved: a least-squares fit on noisy readings is
biased (errors in variables: on the test rig a 2 um position noise moved the
MDC factor to 0.86 and the lead from 5 to 6.4 ms). Only the JSON's law is
tested, over means of blocks of ticks (the law holds for means too; the
readings' noise shrinks in them, a misfit of a constant does not): within
:data:`NOISE_LEVELS` of the noise the logged readings carry into the means,
the compensation is the JSON's to that noise; beyond it,
``compensation_law_error``, without saying which constant.

Not audited, with why: a compensator that is not one of the format's four
(``sdmdc-online`` scales ``K`` by an estimate that changes every tick; a
plug-in); an MDC whose contact model has a rate term (``C != 0``: the
table's twist it reads is not in the log).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hybridtable.laws.compensation import backward_difference, linear_terms
from hybridtable.measurement.audit_findings import RELATIVE_TOLERANCE, SIGNIFICANCE, differs
from hybridtable.measurement.audit_fit import (
    NOISE_LEVELS,
    block_ticks,
    linear_fit,
    stated_law_levels,
)
from hybridtable.six_dof.compensator import stiffness_model_of
from hybridtable.six_dof.run6 import noise_levels

__all__ = [
    "AUDITED_COMPENSATORS",
    "LAW_RESIDUAL",
    "AuditFinding6",
    "CompensationAudit6",
    "audit_compensation6",
]

#: The compensators whose law the audit solves for (the format's four).
AUDITED_COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")

#: The largest RMS residual of the law, over the RMS of the compensated wrench,
#: of a computer that compensates by the format's law (the 1-D audit's 1e-4 of
#: the force's scale; a CSV at six digits leaves about 1e-5).
LAW_RESIDUAL = 1e-4

_COMPONENTS = ("mx", "my", "mz", "fx", "fy", "fz")


@dataclass(frozen=True)
class AuditFinding6:
    """A quantity the six-axis rig computer used that is not the JSON's."""

    effect: str
    values: dict[str, float]
    std: dict[str, float | None]
    sentence: str

    def to_dict(self) -> dict:
        return {
            "effect": self.effect,
            "values": self.values,
            "std": self.std,
            "sentence": self.sentence,
        }


@dataclass(frozen=True)
class CompensationAudit6:
    """What :func:`audit_compensation6` solved for the runs of one compensator
    (``None`` where it did not solve; ``not_audited`` says why)."""

    run_ids: list[str]
    compensator: str
    ticks: int = 0
    stated_lead_s: float = 0.0
    lead_s: float | None = None
    lead_std_s: float | None = None
    stated_factor: float = 0.0
    factor: float | None = None
    factor_std: float | None = None
    gain: float | None = None
    gain_std: float | None = None
    offsets: tuple[float, ...] = ()
    offsets_std: tuple[float, ...] = ()
    relative_residual: float = math.nan
    deadband_n: tuple[float, float] = (-math.inf, math.inf)
    #: With readings the computer did not see (``block`` > 1): the law's misfit
    #: over block means in noise levels (largest component), NaN otherwise.
    noise_levels: float = math.nan
    #: 1: solved tick by tick; more: over means of that many ticks.
    block: int = 1
    not_audited: str = ""
    findings: list[AuditFinding6] = field(default_factory=list)

    def sentence(self) -> str:
        if self.not_audited:
            return f"the rig computer's compensation law is not audited: {self.not_audited}"
        if self.block > 1 and not self.findings:
            return (
                f"the rig computer's compensation is the JSON's {self.compensator} to the noise "
                f"of the logged readings, which it did not see (over means of {self.block} "
                f"ticks, {self.noise_levels:.2g} noise levels; {self.ticks} ticks): its "
                "constants are not solved from them"
            )
        if not self.findings:
            return (
                f"the rig computer's compensation is the JSON's {self.compensator} (lead, MDC "
                f"term, gain, offsets, dead band; {self.ticks} ticks, residual "
                f"{self.relative_residual:.2g} of the signal)"
            )
        return "the rig computer's compensation: " + "; ".join(f.sentence for f in self.findings)

    def to_dict(self) -> dict:
        return {
            "runs": self.run_ids,
            "compensator": self.compensator,
            "ticks": self.ticks,
            "sentence": self.sentence(),
            "not_audited": self.not_audited or None,
            "stated": {"lead_time_s": self.stated_lead_s, "mdc_factor": self.stated_factor},
            "solved": {
                "lead_time_s": self.lead_s,
                "mdc_factor": self.factor,
                "gain": self.gain,
                "offsets": dict(zip(_COMPONENTS, self.offsets, strict=False)),
                "deadband_n": [_finite(x) for x in self.deadband_n],
            },
            "std": {
                "lead_time_s": self.lead_std_s,
                "mdc_factor": self.factor_std,
                "gain": self.gain_std,
                "offsets": dict(zip(_COMPONENTS, self.offsets_std, strict=False)),
            },
            "relative_residual": _finite(self.relative_residual),
            "block_ticks": self.block,
            "block_noise_levels": _finite(self.noise_levels),
            "findings": [f.to_dict() for f in self.findings],
            "thresholds": {
                "sigmas": SIGNIFICANCE,
                "relative": RELATIVE_TOLERANCE,
                "law_residual": LAW_RESIDUAL,
            },
        }


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _level(wrench: np.ndarray, axial: bool) -> np.ndarray:
    """What the dead band reads of each row: the compression ``-fz`` or the force's norm."""
    return -wrench[:, 5] if axial else np.linalg.norm(wrench[:, 3:], axis=1)


def _terms(run, model) -> dict | None:
    """Of ticks 1.. of ``run``: the law's ``terms`` (rows x 6 components x
    [reading, lead, MDC]; ``model`` None: no MDC term), the compensated wrench
    ``wc``, the readings ``w``, the readings' noise variance ``var_w`` (6) and
    the MDC term's from the measured pose's ``var_m`` (rows x 6), the noise
    from the ticks before the first touch; None where the stiffness ``model``
    has a rate term."""
    params = run.params
    h = params.sample_period_s
    w, wc = run.wrench("mea"), run.wrench("comp")
    q_act, q_des = run.pose("act"), run.pose("des")
    k = np.arange(1, run.n)
    rate = backward_difference(w[k], w[k - 1], h)
    motion, var_m = np.zeros((len(k), 6)), np.zeros((len(k), 6))
    before = np.arange(run.n) < int(np.argmax(run.contact_ticks))
    if before.sum() < 10:
        before = None  # every tick (robust second differences)
    sigma_q = noise_levels(q_act, before)
    if model is not None:
        for j, i in enumerate(k):
            K, C = model(q_act[i], np.zeros(6))
            if np.any(C):
                return None
            motion[j] = linear_terms(w[i], rate[j], q_des[i - 1] - q_act[i], -K)[2]
            var_m[j] = (K**2) @ sigma_q**2
    reading, lead_term, _ = linear_terms(w[k], rate)
    return {
        "h": h,
        "lead_s": params.effective_lead_time_s if params.compensator in ("SDC", "SDMDC") else 0.0,
        "terms": np.stack([reading, lead_term, motion], axis=2),
        "wc": wc[k],
        "w": w[k],
        "var_w": noise_levels(w, before) ** 2,
        "var_m": var_m,
    }


def _solve(parts: list[dict], columns: int, size: np.ndarray):
    """The law's constants of ``parts`` by least squares over their open
    ticks, each component over its ``size``: (coefficients, standard errors,
    RMS residual, the design of every tick)."""
    xs, ys, design = [], [], []
    for p in parts:
        open_ = np.any(p["wc"] != 0.0, axis=1)
        x = np.concatenate(
            [p["terms"][:, :, :columns], np.broadcast_to(np.eye(6), (len(open_), 6, 6))], axis=2
        )
        design.append(x / size[None, :, None])
        xs.append(design[-1][open_])
        ys.append(p["wc"][open_] / size)
    x, y = np.concatenate(xs), np.concatenate(ys)
    coef, se, resid = linear_fit(x.reshape(-1, x.shape[2]), y.ravel())
    return coef, se, resid, design


def audit_compensation6(runs: Sequence) -> CompensationAudit6:
    """Solve the compensation law of ``runs``
    (:class:`~hybridtable.six_dof.run6.Run6`) whose JSONs state one
    compensator and rate (see the module)."""
    params = runs[0].params
    name = params.compensator
    ids = [r.run_id for r in runs]
    if name not in AUDITED_COMPENSATORS:
        why = (
            "sdmdc-online scales its K by an estimate that changes every tick"
            if name == "sdmdc-online"
            else f"the compensator {name!r} is not one of the format's laws"
        )
        return CompensationAudit6(ids, name, not_audited=why)
    mdc = name in ("MDC", "SDMDC")
    model = stiffness_model_of(params)
    parts = [_terms(r, model) for r in runs]
    if any(p is None for p in parts):
        if mdc:
            return CompensationAudit6(
                ids,
                name,
                not_audited="its MDC's contact model has a rate term (C), and the table's "
                "twist it reads is not in the log",
            )
        parts = [_terms(r, None) for r in runs]  # the JSON has no MDC: none is solved
    wc = np.concatenate([p["wc"] for p in parts])
    open_ = np.any(wc != 0.0, axis=1)
    ticks = int(open_.sum())
    if ticks < 8:
        return CompensationAudit6(ids, name, not_audited="fewer than 8 ticks with a wrench")
    columns = 3 if any(np.any(p["terms"][:, :, 2]) for p in parts) else 2
    size = np.sqrt(np.mean(wc[open_] ** 2, axis=0))
    size = np.maximum(size, 1e-6 * max(float(size.max()), 1e-300))
    coef, se, resid, design = _solve(parts, columns, size)
    signal = float(np.sqrt(np.mean((wc[open_] / size) ** 2)))
    relative = resid / signal if signal > 0.0 else 0.0
    block, levels = 1, math.nan
    noisy = any(np.any(p["var_w"] > 0.0) or np.any(p["var_m"] > 0.0) for p in parts)
    if relative > LAW_RESIDUAL and noisy:
        # The readings' noise the computer did not see, or another law. A fit on
        # noisy readings is biased (errors in variables: the lead and the MDC term
        # trade), so only the JSON's law is tested, over means of ticks, whose
        # noise the means shrink and a misfit of the law's constants survives.
        block = block_ticks(min(int(np.any(p["wc"] != 0.0, axis=1).sum()) for p in parts))
        stated = np.array([1.0, parts[0]["lead_s"], 1.0 if mdc else 0.0][:columns])
        levels = float(
            np.max(
                [
                    stated_law_levels(
                        p["wc"] - p["terms"][:, :, :columns] @ stated,
                        np.any(p["wc"] != 0.0, axis=1),
                        p["var_w"],
                        p["var_m"],
                        p["lead_s"] / p["h"],
                        block,
                    )
                    for p in parts
                ]
            )
        )
    predicted = np.concatenate(design) @ coef * size  # every tick's compensation, ungated
    level = _level(
        np.concatenate([p["w"] for p in parts]), params.deadband_reading == "axial_force"
    )
    clamped = params.clamp_nonnegative & (-predicted[:, 5] < 0.0)
    quiet = 5.0 * relative * signal + 1e-9
    gated = ~open_ & ~clamped & np.any(np.abs(predicted) / size > quiet, axis=1)
    audit = CompensationAudit6(
        ids, name, ticks, parts[0]["lead_s"], float(coef[1]), float(se[1]),
        1.0 if mdc else 0.0,
        float(coef[2]) if columns == 3 else None, float(se[2]) if columns == 3 else None,
        float(coef[0]), float(se[0]),
        tuple(float(b) for b in coef[-6:] * size), tuple(float(s) for s in se[-6:] * size),
        relative,
        (float(np.max(level[gated])) if gated.any() else -math.inf, float(np.min(level[open_]))),
        levels, block,
    )  # fmt: skip
    audit.findings.extend(_findings(audit, params, size))
    return audit


def _findings(audit: CompensationAudit6, params, size: np.ndarray) -> list[AuditFinding6]:
    name, h = audit.compensator, params.sample_period_s
    if audit.relative_residual > LAW_RESIDUAL and audit.block == 1:
        return [
            AuditFinding6(
                "compensation_law_error",
                {"relative_residual": audit.relative_residual},
                {"relative_residual": None},
                f"compensation_law_error: w_comp is not the format's compensation of the "
                f"readings: {audit.relative_residual:.2g} of the signal remains after solving a "
                f"gain, a lead, the MDC term's factor and an offset per component (at most "
                f"{LAW_RESIDUAL:g})",
            )
        ]  # the values below assume the format's law
    if audit.block > 1:
        if audit.noise_levels <= NOISE_LEVELS:
            return []  # the JSON's law, to the noise of readings it did not see
        return [
            AuditFinding6(
                "compensation_law_error",
                {"stated_law_noise_levels": audit.noise_levels},
                {"stated_law_noise_levels": None},
                f"compensation_law_error: w_comp is not the JSON's {name} law of the logged "
                f"readings: over means of {audit.block} ticks it misses by "
                f"{audit.noise_levels:.3g} noise levels (at most {NOISE_LEVELS:g}), and no gain, "
                f"lead, MDC factor and offsets make it one ({audit.relative_residual:.2g} of the "
                "signal remains): the computer compensates otherwise, or the log's readings "
                "carry noise it did not see, and then which of its constants differs cannot be "
                "solved from them",
            )
        ]
    out = []
    stated = audit.stated_lead_s
    if differs(audit.lead_s, audit.lead_std_s, stated, max(stated, h)):
        says = (
            f"the JSON's {stated * 1e3:.6g} ms"
            if stated > 0.0
            else f"the JSON's compensator {name} has no lead"
        )
        out.append(
            AuditFinding6(
                "lead_time_error",
                {"lead_error_s": audit.lead_s - stated},
                {"lead_error_s": audit.lead_std_s},
                f"lead_time_error: its lead is {audit.lead_s * 1e3:.6g} +- "
                f"{audit.lead_std_s * 1e3:.2g} ms, {says}",
            )
        )
    if audit.factor is not None and differs(
        audit.factor, audit.factor_std, audit.stated_factor, 1.0
    ):
        if audit.stated_factor > 0.0:
            out.append(
                AuditFinding6(
                    "compensator_stiffness_error",
                    {"compensator_stiffness_ratio": audit.factor},
                    {"compensator_stiffness_ratio": audit.factor_std},
                    f"compensator_stiffness_error: its MDC term is {audit.factor:.6g} +- "
                    f"{audit.factor_std:.2g} times its {params.stiffness_model} stiffness model's",
                )
            )
        else:
            out.append(
                AuditFinding6(
                    "compensation_law_error",
                    {"mdc_factor": audit.factor},
                    {"mdc_factor": audit.factor_std},
                    f"compensation_law_error: it adds {audit.factor:.4g} times an MDC term "
                    f"the JSON's compensator {name} does not have",
                )
            )
    if differs(audit.gain, audit.gain_std, 1.0, 1.0):
        out.append(
            AuditFinding6(
                "compensation_law_error",
                {"gain": audit.gain},
                {"gain": audit.gain_std},
                f"compensation_law_error: it scales the readings by {audit.gain:.6g} before "
                "compensating",
            )
        )
    off = [
        (c, b, s)
        for c, b, s, z in zip(_COMPONENTS, audit.offsets, audit.offsets_std, size, strict=True)
        if differs(b, s, 0.0, z)
    ]
    if off:
        out.append(
            AuditFinding6(
                "compensation_law_error",
                {f"offset_{c}": b for c, b, _ in off},
                {f"offset_{c}": s for c, _, s in off},
                "compensation_law_error: it adds "
                + ", ".join(f"{b:.4g} to {c}" for c, b, _ in off)
                + " (N, N m) to the compensated wrench",
            )
        )
    lower, upper = audit.deadband_n
    db = params.force_deadband_n
    if lower >= upper:
        out.append(
            AuditFinding6(
                "deadband_error",
                {"force_deadband_n": lower},
                {"force_deadband_n": None},
                f"deadband_error: which readings get no compensation is not a dead band: a "
                f"reading of {lower:.4g} N got none, one of {upper:.4g} N got some",
            )
        )
    elif not (lower <= db < upper):
        used = 0.5 * (lower + upper) if math.isfinite(lower) else upper
        out.append(
            AuditFinding6(
                "deadband_error",
                {"force_deadband_n": used},
                {"force_deadband_n": 0.5 * (upper - lower) if math.isfinite(lower) else None},
                f"deadband_error: its dead band is between {max(lower, 0.0):.4g} and "
                f"{upper:.4g} N, the JSON's {db:.4g} N",
            )
        )
    return out
