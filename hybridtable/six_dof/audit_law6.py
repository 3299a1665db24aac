"""The audit of a six-axis rig computer's compensation law: the lead, the
MDC's stiffness, a gain, offsets and the dead band it used, solved from the
record.

A 6-DoF record holds the compensator's inputs and its output at every tick
(``docs/run6-format.md``, step 2): the readings ``w_mea[k]`` and
``w_mea[k-1]``, the measured pose ``q_act[k]``, the command ``q_des[k-1]``
still held, and the compensated wrench ``w_comp[k]``. On every tick with a
compensated wrench the format's law is linear in its constants:

    w_comp = a w_mea + T_lead (w_mea[k] - w_mea[k-1]) / h + s (-K (q_des[k-1] - q_act[k])) + b

(``h`` the time step the computer stepped its model by:
:func:`computer_step`) with the terms taken from the law's one definition
(:func:`~hybridtable.laws.compensation.linear_terms`, as the 1-D audit's
regression, :mod:`hybridtable.measurement.audit`), ``K`` the scenario's
stiffness model at the measured pose
(:func:`~hybridtable.six_dof.compensator.stiffness_model_of`), the gain ``a``
(1), the MDC term's factor ``s`` (1 with an MDC, else 0) and an offset ``b``
per component (0). The six components of the ticks of the runs that state
one law (:func:`law_key`: compensator, lead, rate, believed contact and
the nominal pose of a ``nominal`` stiffness model) are
solved together by least squares, each component weighted by its size (not
below 1e-3 of the largest's). A value is a finding as the 1-D audit decides
(:func:`~hybridtable.measurement.audit_findings.differs`): ``lead_time_error``
(the lead used less the JSON's), ``compensator_stiffness_error`` (the MDC
term over its model's, where ``K`` is linear in the believed stiffness and
the factor within that effect's range), ``compensation_law_error`` (a gain,
an offset, a lead or MDC term the JSON's compensator does not have, or a
residual above ``COMPENSATION_RESIDUAL`` of the signal: the computer does not
compensate by the format's law) and ``deadband_error`` (the readings it
gated bound its dead band from below, those it compensated from above;
:func:`~hybridtable.measurement.audit_fit.deadband_bounds`). A computer that
gave no wrench although its readings passed the JSON's dead band has a
``deadband_error`` above them.

A log whose readings carry noise the computer did not see (a logger of its
own; the format logs what the computer read) leaves a residual above that.
The constants are then not solved: a least-squares fit on noisy readings is
biased (errors in variables: the lead and the MDC term trade, and a
component the computer saw as zero pulls the gain towards it). Only the
JSON's law is tested (:func:`~hybridtable.measurement.audit_fit.stated_law_levels`,
shared with the 1-D audit), over means of blocks of ticks (the law holds for
means too; the readings' noise shrinks in them, a misfit of a constant does
not), against the noise the readings carry, from every tick: within
``NOISE_LEVELS`` it is the JSON's law to that noise, and the sentence says
how large a lead or MDC error would not show; beyond, ``compensation_law_error``
without saying which constant. The dead band is still bounded, each bound
five force noise levels wider.

Not audited, with why: a compensator that is not one of the format's four
(``sdmdc-online`` scales ``K`` by an estimate that changes every tick; a
plug-in); an MDC whose contact model has a rate term (``C != 0``: the
table's twist it reads is not in the log).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hybridtable.effects.registry import get_effect
from hybridtable.laws.compensation import backward_difference, linear_terms
from hybridtable.measurement.audit_findings import differs
from hybridtable.measurement.audit_fit import (
    NOISE_LEVELS,
    block_ticks,
    deadband_bounds,
    deadband_used,
    linear_fit,
    reading_noise,
    stated_law_levels,
)
from hybridtable.six_dof.audit_findings6 import (
    COMPENSATION_RESIDUAL,
    WRENCH_COMPONENTS,
    AuditFinding6,
    CompensationAudit6,
)
from hybridtable.six_dof.compensator import stiffness_model_of
from hybridtable.six_dof.physics6 import rig_scale

__all__ = ["AUDITED_COMPENSATORS", "audit_compensation6", "computer_step", "law_key", "time_step"]

#: The compensators whose law the audit solves for (the format's four).
AUDITED_COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")


def _level(wrench: np.ndarray, axial: bool) -> np.ndarray:
    """What the dead band reads of each row: the compression ``-fz`` or the force's norm."""
    return -wrench[:, 5] if axial else np.linalg.norm(wrench[:, 3:], axis=1)


def time_step(run) -> tuple[float, float]:
    """The time step (s) the rig computer steps its model by, and its
    standard error: the format's position step of the centre of mass, ``p[k]
    = p[k-1] + h v[k]``, on the port's logged pose and twist (``p = p_P - R
    c``, ``v = v_P - omega x R c``, ``c`` the JSON's port position: an error
    of ``c`` enters to second order), by least squares over every tick."""
    c = np.asarray(run.params.spacecraft.port_position_m, dtype=float)
    Rc = run.rotations("des") @ c
    p, v, omega = run.blocks["p_des"], run.blocks["v_des"], run.blocks["w_des"]
    y = np.diff(p - Rc, axis=0).ravel()
    x = (v - np.cross(omega, Rc))[1:].ravel()
    if not float(x @ x) > 0.0:
        return run.params.sample_period_s, math.inf
    (h,), (se,), _ = linear_fit(x[:, None], y)
    return float(h), float(se)


def computer_step(run) -> float:
    """The time step the rig computer stepped its model by: :func:`time_step`
    where it differs from the JSON's rate (a finding of the spacecraft's
    audit), else the JSON's."""
    h_json = run.params.sample_period_s
    h, se = time_step(run)
    return h if differs(h, se, h_json, h_json) else h_json


def law_key(params) -> tuple:
    """What states a run's compensation law: its compensator, lead, rate and
    the contact its MDC believes (and, for the ``nominal`` stiffness model,
    the pose it is taken at); the runs of one key are audited together."""
    nominal = tuple(params.nominal_pose()) if params.stiffness_model == "nominal" else None
    return (
        params.rig.compensator,
        params.effective_lead_time_s,
        params.sample_rate_hz,
        params.believed_contact,
        nominal,
    )


def _terms(run) -> dict:
    """Of ticks 1.. of ``run``: the law's ``terms`` (rows x 6 components x
    [reading, lead, MDC], its scenario's stiffness model at the measured pose;
    ``rate_free`` false, and the MDC term zero, where the model has a rate
    term), the compensated wrench ``wc``, the readings ``w``, the readings'
    noise variance ``var_w`` (6) and what the measured pose's noise puts in
    the MDC term, ``var_m`` (rows x 6; :func:`reading_noise`: from every
    tick), and whether the readings carry noise at all (``noisy``)."""
    params = run.params
    h = computer_step(run)
    w, wc = run.wrench("mea"), run.wrench("comp")
    q_act, q_des = run.pose("act"), run.pose("des")
    k = np.arange(1, run.n)
    rate = backward_difference(w[k], w[k - 1], h)
    before = int(np.argmax(run.contact_ticks))
    sigma_w, noisy_w = reading_noise(w, before)
    sigma_q, noisy_q = reading_noise(q_act, before)
    model = stiffness_model_of(params)
    motion, var_m = np.zeros((len(k), 6)), np.zeros((len(k), 6))
    rate_free = True
    for j, i in enumerate(k):
        K, C = model(q_act[i], np.zeros(6))
        if np.any(C):
            rate_free = False
            motion[:] = 0.0
            var_m[:] = 0.0
            break
        motion[j] = linear_terms(
            w[i], rate[j], response_error=q_des[i - 1] - q_act[i], stiffness=-K
        )[2]
        var_m[j] = (K**2) @ sigma_q**2
    reading, lead_term, _ = linear_terms(w[k], rate)
    has_lead = params.compensator in ("SDC", "SDMDC")
    return {
        "h": h,
        "lead_s": params.effective_lead_time_s if has_lead else 0.0,
        "terms": np.stack([reading, lead_term, motion], axis=2),
        "wc": wc[k],
        "w": w[k],
        "var_w": sigma_w**2,
        "var_m": var_m,
        "noisy": noisy_w or (noisy_q and bool(np.any(var_m))),
        "rate_free": rate_free,
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


def _stated(parts: list[dict], stated: np.ndarray, block: int, size: np.ndarray):
    """The JSON's law against the logged readings: its misfit over means of
    ``block`` ticks in noise levels (largest component of any run), per tick
    its compensation and that compensation's noise (rows x 6), and the
    smallest change of each constant (gain, lead in s, the MDC term's factor)
    that would pass :data:`NOISE_LEVELS` (its term's block means against
    their noise in the most telling component: ``levels^2 = 1 + (c term)^2 /
    noise``). A component whose readings carry no noise counts the exact
    law's resolution (``COMPENSATION_RESIDUAL`` of its ``size``) as its noise."""
    levels, predicted, noise, telling = [], [], [], []
    floor = (COMPENSATION_RESIDUAL * size) ** 2
    for p in parts:
        p = dict(p, var_w=np.maximum(p["var_w"], floor))
        x = p["terms"][:, :, : len(stated)]
        predicted.append(x @ stated)
        lead = p["lead_s"] / p["h"]
        noise.append(np.sqrt(p["var_w"] * ((1.0 + lead) ** 2 + lead**2) + p["var_m"]))
        open_ = np.any(p["wc"] != 0.0, axis=1)
        misfit = p["wc"] - predicted[-1]
        levels.append(stated_law_levels(misfit, open_, p["var_w"], p["var_m"], lead, block))
        # per unit of each constant, its term's block means in noise levels, squared
        unit = [
            stated_law_levels(x[:, :, c], open_, p["var_w"], p["var_m"], lead, block) ** 2
            for c in range(len(stated))
        ]
        telling.append([float(np.max(np.nan_to_num(u))) for u in unit])
    most = np.max(telling, axis=0)
    smallest = np.full(len(most), np.inf)
    smallest[most > 0.0] = np.sqrt((NOISE_LEVELS**2 - 1.0) / most[most > 0.0])
    # a run too short for a block tells nothing; all of them: NaN
    level = float(np.nanmax(levels)) if np.any(np.isfinite(levels)) else math.nan
    return level, np.concatenate(predicted), np.concatenate(noise), smallest


def audit_compensation6(runs: Sequence) -> CompensationAudit6:
    """Solve the compensation law of ``runs``
    (:class:`~hybridtable.six_dof.run6.Run6`) of one :func:`law_key` (see the
    module)."""
    if not runs:
        raise ValueError("audit_compensation6 needs at least one run")
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
    parts = [_terms(r) for r in runs]
    if mdc and not all(p["rate_free"] for p in parts):
        why = "its MDC's contact model has a rate term (C), and the table's twist it reads is not in the log"
        return CompensationAudit6(ids, name, not_audited=why)
    columns = 3 if any(np.any(p["terms"][:, :, 2]) for p in parts) else 2
    stated = np.array([1.0, parts[0]["lead_s"], 1.0 if mdc else 0.0][:columns])
    wc = np.concatenate([p["wc"] for p in parts])
    open_ = np.any(wc != 0.0, axis=1)
    ticks = int(open_.sum())
    level = _level(
        np.concatenate([p["w"] for p in parts]), params.deadband_reading == "axial_force"
    )
    noisy = any(p["noisy"] for p in parts)
    # the readings' noise moves a dead band's bounds: by 5 levels (the force's norm of
    # three noisy components passes 5 levels once in 70,000 ticks)
    slack = 5.0 * float(np.sqrt(max(np.max(p["var_w"][3:]) for p in parts))) if noisy else 0.0
    block = block_ticks(min(int(np.any(p["wc"] != 0.0, axis=1).sum()) for p in parts))
    base = dict(stated_lead_s=parts[0]["lead_s"], stated_factor=1.0 if mdc else 0.0)
    clamp = params.clamp_nonnegative
    if ticks < 8:  # a computer that gave (almost) no wrench: a dead band above its readings?
        _, predicted, noise, _ = _stated(parts, stated, block, np.ones(6))
        pending = ~(clamp & (-predicted[:, 5] < 3.0 * noise[:, 5]))  # not (maybe) clamped
        bounds = deadband_bounds(level, open_, pending, slack)
        audit = CompensationAudit6(ids, name, ticks, deadband_n=bounds, **base)
        audit.findings.extend(_deadband(audit, params))
        if audit.findings:
            return audit
        return CompensationAudit6(ids, name, ticks, not_audited="fewer than 8 ticks with a wrench")
    size = np.sqrt(np.mean(wc[open_] ** 2, axis=0))
    size = np.maximum(size, 1e-3 * max(float(size.max()), 1e-300))
    coef, se, resid, design = _solve(parts, columns, size)
    signal = float(np.sqrt(np.mean((wc[open_] / size) ** 2)))
    relative = resid / signal if signal > 0.0 else 0.0
    if relative <= COMPENSATION_RESIDUAL or not noisy:
        predicted = np.concatenate(design) @ coef * size  # every tick's, ungated
        pending = np.any(np.abs(predicted) / size > 5.0 * relative * signal + 1e-9, axis=1)
        levels, how = math.nan, "exact" if relative <= COMPENSATION_RESIDUAL else "other"
    else:
        # Noise the computer did not see, or another law: a fit on noisy readings is
        # biased (errors in variables), so the constants are not solved; the JSON's
        # law is tested over means of blocks of ticks, and bounds the dead band.
        # Every tick without a wrench that its clamp may not explain was gated.
        levels, predicted, noise, smallest = _stated(parts, stated, block, size)
        pending = ~(clamp & (-predicted[:, 5] < 3.0 * noise[:, 5]))
        how = "noisy"
    pending &= ~(clamp & (-predicted[:, 5] < 0.0))
    bounds = deadband_bounds(level, open_, pending, slack if how == "noisy" else 0.0)
    solved = how != "noisy"
    audit = CompensationAudit6(
        ids, name, ticks, base["stated_lead_s"],
        float(coef[1]) if solved else None, float(se[1]) if solved else None,
        base["stated_factor"],
        float(coef[2]) if solved and columns == 3 else None,
        float(se[2]) if solved and columns == 3 else None,
        float(coef[0]) if solved else None, float(se[0]) if solved else None,
        tuple(float(b) for b in coef[-6:] * size) if solved else (),
        tuple(float(s) for s in se[-6:] * size) if solved else (),
        relative, bounds, levels, block if how == "noisy" else 1,
        tuple(float(x) for x in smallest) if how == "noisy" else (),
    )  # fmt: skip
    audit.findings.extend(_findings(audit, params, size, how))
    return audit


def _deadband(audit: CompensationAudit6, params) -> list[AuditFinding6]:
    """The dead band's finding: the bounds it lies in against the JSON's."""
    lower, upper = audit.deadband_n
    db = params.force_deadband_n
    verdict = deadband_used(lower, upper, db)
    if verdict is None:
        return []
    used, half = verdict
    if lower >= upper:
        said = (
            f"which readings get no compensation is not a dead band: a reading of "
            f"{lower:.4g} N got none, one of {upper:.4g} N got some"
        )
    elif math.isfinite(upper):
        said = f"its dead band is between {max(lower, 0.0):.4g} and {upper:.4g} N"
    else:
        said = f"its dead band is above {lower:.4g} N (no reading got a compensation)"
    return [
        AuditFinding6(
            "deadband_error",
            {"force_deadband_n": used},
            {"force_deadband_n": half if math.isfinite(half) else None},
            f"deadband_error: {said}" + ("" if lower >= upper else f", the JSON's {db:.4g} N"),
        )
    ]


def _findings(audit: CompensationAudit6, params, size: np.ndarray, how: str) -> list[AuditFinding6]:
    name, h = audit.compensator, params.sample_period_s
    if how == "other":
        return [
            AuditFinding6(
                "compensation_law_error",
                {"relative_residual": audit.relative_residual},
                {"relative_residual": None},
                f"compensation_law_error: w_comp is not the format's compensation of the "
                f"readings: {audit.relative_residual:.2g} of the signal remains after solving a "
                f"gain, a lead, the MDC term's factor and an offset per component (at most "
                f"{COMPENSATION_RESIDUAL:g})",
            )
        ]  # the values below assume the format's law
    if how == "noisy":
        if not math.isfinite(audit.noise_levels):
            return [
                AuditFinding6(
                    "compensation_law_error",
                    {"stated_law_noise_levels": audit.noise_levels},
                    {"stated_law_noise_levels": None},
                    "compensation_law_error: w_comp is not the JSON's law of the logged readings "
                    "exactly, and its stretches of compensation are too short to tell the "
                    "readings' noise from another law",
                )
            ]
        if audit.noise_levels <= NOISE_LEVELS:
            return _deadband(
                audit, params
            )  # the JSON's law, to the noise of readings it did not see
        return [
            AuditFinding6(
                "compensation_law_error",
                {"stated_law_noise_levels": audit.noise_levels},
                {"stated_law_noise_levels": None},
                f"compensation_law_error: w_comp is not the JSON's {name} law of the logged "
                f"readings: over means of {audit.block} ticks it misses by "
                f"{audit.noise_levels:.3g} noise levels (at most {NOISE_LEVELS:g}), and no gain, "
                f"lead, MDC factor and offsets make it one exactly ({audit.relative_residual:.2g} "
                "of the signal remains): the computer compensates "
                "otherwise, or the log's readings carry noise it did not see, and then which of "
                "its constants differs cannot be solved from them",
            )
        ]
    out = []
    if not all(
        math.isfinite(x) for x in (audit.lead_std_s, audit.gain_std, audit.factor_std or 0.0)
    ):
        return []  # the record does not determine them: the sentence says so
    stated = audit.stated_lead_s
    if differs(audit.lead_s, audit.lead_std_s, stated, max(stated, h)):
        if stated > 0.0:
            out.append(
                AuditFinding6(
                    "lead_time_error",
                    {"lead_error_s": audit.lead_s - stated},
                    {"lead_error_s": audit.lead_std_s},
                    f"lead_time_error: its lead is {audit.lead_s * 1e3:.6g} +- "
                    f"{audit.lead_std_s * 1e3:.2g} ms, the JSON's {stated * 1e3:.6g} ms",
                )
            )
        else:
            out.append(
                AuditFinding6(
                    "compensation_law_error",
                    {"lead_time_s": audit.lead_s},
                    {"lead_time_s": audit.lead_std_s},
                    f"compensation_law_error: it leads by {audit.lead_s * 1e3:.6g} +- "
                    f"{audit.lead_std_s * 1e3:.2g} ms; the JSON's compensator {name} has no lead",
                )
            )
    factor, std = audit.factor, audit.factor_std
    if factor is not None and differs(factor, std, audit.stated_factor, 1.0):
        # the MDC's stiffness is a factor on K only where K is linear in it (the pads'
        # springs without a law of their own), and a plausible one (a factor near 0 or
        # below it is no MDC, or one of the other sign: another law)
        linear = params.stiffness_model == "given" or params.believed_contact.drake_law
        ratio = get_effect("compensator_stiffness_error").parameter("compensator_stiffness_ratio")
        lo, hi = ratio.bounds(rig_scale(params))
        if audit.stated_factor > 0.0 and lo <= factor <= hi and linear:
            out.append(
                AuditFinding6(
                    "compensator_stiffness_error",
                    {"compensator_stiffness_ratio": factor},
                    {"compensator_stiffness_ratio": std},
                    f"compensator_stiffness_error: its MDC term is {factor:.6g} +- {std:.2g} "
                    f"times its {params.stiffness_model} stiffness model's",
                )
            )
        else:
            has = (
                "" if audit.stated_factor > 0.0 else f" the JSON's compensator {name} does not have"
            )
            said = (
                f"it has no MDC term (its factor {factor:.2g} +- {std:.2g} of its "
                f"{params.stiffness_model} stiffness model's); the JSON's {name} has one"
                if audit.stated_factor > 0.0 and not differs(factor, std, 0.0, 1.0)
                else f"its MDC term is {factor:.4g} +- {std:.2g} times its "
                f"{params.stiffness_model} stiffness model's{has}"
            )
            out.append(
                AuditFinding6(
                    "compensation_law_error",
                    {"mdc_factor": factor},
                    {"mdc_factor": std},
                    f"compensation_law_error: {said}",
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
        for c, b, s, z in zip(
            WRENCH_COMPONENTS, audit.offsets, audit.offsets_std, size, strict=True
        )
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
    return out + _deadband(audit, params)
