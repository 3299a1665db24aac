"""Audit of the rig's computer: what it did, by arithmetic, against what its JSON says.

A record holds the rig computer's own arithmetic (steps 2-4 of
``docs/run-format.md``): the compensated force ``f_comp`` computed from the
readings ``f_mea``, ``p_act`` and the last command ``p_des``; the spacecraft
model's velocity ``v_des`` stepped by ``-f_comp / m h``; the command ``p_des``
stepped by ``v_des h``. None of this is physics, so none of it is fitted: the
values the computer used are solved for from the record, exact up to the
CSV's precision, and every one that differs from the run's JSON is a
:class:`Finding` with its size ("lead_time_s used 4.0 ms, JSON says 5.0 ms").

Per run (:func:`audit_run`):

- **time step and integration rule**: ``p_des[k] - p_des[k-1] = v_des[k] h``
  gives ``h`` by least squares (``sample_rate_hz = 1 / h``); a computer that
  steps the model by another rule (:data:`~hybridtable.laws.spacecraft.INTEGRATORS`:
  ``p_des`` steps by ``h (theta v_des[k] + (1 - theta) v_des[k-1])``) shows
  in the fit of ``h v_des[k] - c (v_des[k] - v_des[k-1])``, ``theta = 1 - c / h``,
  where the force changes the velocity: a ``theta`` other than 1 is a
  finding that names the rule (explicit Euler 0, trapezoid or RK4 with the
  force held 1/2), and ``h`` is then read from that fit, so the rule does
  not pass for a time step, mass or lead time of its own; ``p_des[0] = -gap
  + v_des[0] h`` (``theta``-weighted) gives the initial gap;
- **mass**: ``v_des[k] - v_des[k-1] = -f_comp[k] h / m`` on the ticks with a
  force gives ``m``; a ``v_des`` that changes with no force is reported;
- **compensation**: on the ticks with ``f_comp != 0``, a least-squares fit of
  ``f_comp = a f_mea + L (f_mea[k] - f_mea[k-1]) / h + K (p_des[k-1] - p_act[k]) + b``
  gives the lead time ``L``, the MDC stiffness ``K``, and a gain ``a`` (1) and
  offset ``b`` (0) that the format does not have; a fit residual far above the
  CSV's precision says the law is not the format's;
- **deadband and clamp**: the readings gated to zero although their
  compensation is positive bound the deadband from below, the smallest reading
  with a force from above; a negative ``f_comp`` says there is no clamp.

A value is reported when it differs from the JSON's by more than five
standard errors of its estimate *and* by more than
:data:`RELATIVE_TOLERANCE` of its scale: a computer that rounds a value in
its JSON is not a mismatch. :func:`audit_runs` merges what the runs agree on.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hybridtable.laws.compensation import backward_difference, linear_terms
from hybridtable.laws.spacecraft import DEFAULT_INTEGRATOR, INTEGRATORS
from hybridtable.measurement.audit_findings import (
    RELATIVE_TOLERANCE,
    SIGNIFICANCE,
    Audit,
    ComputerEstimate,
    Finding,
    differs,
)
from hybridtable.measurement.audit_fit import (
    NOISE_LEVELS,
    block_ticks,
    deadband_bounds,
    deadband_used,
    linear_fit,
    reading_noise,
    stated_law_levels,
)
from hybridtable.measurement.run_format import Run

__all__ = [
    "audit_run",
    "audit_runs",
]


def audit_run(run: Run) -> tuple[ComputerEstimate, list[Finding]]:
    """Solve one run's record for what its computer used (see the module doc)."""
    info = run.info
    h_json = info.sample_period_s
    p_des = np.asarray(run.p_des_m, dtype=float)
    fc = np.asarray(run.f_comp_n, dtype=float)
    v = np.asarray(run.v_des_m_per_s, dtype=float)
    n = len(v)
    rid = (run.run_id,)
    found: list[Finding] = []

    # Time step: p_des[k] - p_des[k-1] = v[k] h.
    dx = np.diff(p_des)
    vv = v[1:]
    if n > 2 and float(vv @ vv) > 0.0:
        (h,), (h_se,), _ = linear_fit(vv[:, None], dx)
    else:
        h, h_se = h_json, math.inf
    rule, weight, weight_se, h_rule, h_rule_se = _integration_rule(dx, v)
    if rule != DEFAULT_INTEGRATOR:
        h, h_se = h_rule, h_rule_se
        if rule == "other":
            named = "a rule the model does not have"
        else:
            named = rule.replace("_", " ")
            if rule == "trapezoid":
                named += " (or RK4 with the force held over the tick)"
        found.append(
            Finding(
                "integrator",
                1.0,
                weight,
                weight_se,
                rid,
                f"the computer steps the spacecraft model by {named}: p_des steps by "
                f"h ({weight:.3g} v_des[k] + {1.0 - weight:.3g} v_des[k-1]); the format's "
                "semi-implicit Euler steps by h v_des[k]",
            )
        )
    if differs(h, h_se, h_json, h_json):
        found.append(
            Finding(
                "sample_rate_hz",
                info.sample_rate_hz,
                1.0 / h,
                h_se / (h * h),
                rid,
                f"the command steps with a time step of {h * 1e3:.6g} ms "
                f"({1.0 / h:.6g} Hz); the JSON says {info.sample_rate_hz:g} Hz",
            )
        )
    v_start = v[0] + fc[0] * h / info.spacecraft_mass_kg  # before tick 0's step
    gap = -(p_des[0] - h * (weight * v[0] + (1.0 - weight) * v_start))
    if differs(gap, 10 * abs(h_se * v[0]), info.initial_gap_m, max(info.initial_gap_m, 1e-6)):
        found.append(
            Finding(
                "initial_gap_m",
                info.initial_gap_m,
                gap,
                abs(h_se * v[0]),
                rid,
                f"the spacecraft model started {gap * 1e3:.6g} mm from contact; "
                f"the JSON says {info.initial_gap_m * 1e3:.6g} mm",
            )
        )

    # Mass: v[k] - v[k-1] = -f_comp[k] h / m.
    dv = np.diff(v)
    fk = fc[1:]
    on = fk != 0.0
    m, m_se = math.nan, math.nan
    if on.sum() >= 2:
        (b,), (b_se,), _ = linear_fit((fk[on] * h)[:, None], -dv[on])
        if b > 0.0:
            m = 1.0 / b
            m_se = b_se / (b * b)
            if differs(m, m_se, info.spacecraft_mass_kg, info.spacecraft_mass_kg):
                found.append(
                    Finding(
                        "spacecraft_mass_kg",
                        info.spacecraft_mass_kg,
                        m,
                        m_se,
                        rid,
                        f"spacecraft_mass_kg used {m:.6g} kg, JSON says "
                        f"{info.spacecraft_mass_kg:.6g} kg ({m / info.spacecraft_mass_kg - 1:+.2%})",
                    )
                )
    free = dv[~on]
    resolution = 1e-8 * max(float(np.max(np.abs(v))), 1e-12)
    free_change = float(np.max(np.abs(free))) if free.size else 0.0
    if free_change > 100 * resolution:
        found.append(
            Finding(
                "spacecraft_model",
                0.0,
                free_change,
                resolution,
                rid,
                f"v_des changes by up to {free_change:.3g} m/s on ticks without a "
                "compensated force: the spacecraft model has a force the format does not",
            )
        )
    v0 = v[0] + fc[0] * h / m if math.isfinite(m) else v[0]
    v0_scale = max(abs(info.initial_velocity_m_per_s), 1e-9)
    if differs(v0, resolution, info.initial_velocity_m_per_s, v0_scale):
        found.append(
            Finding(
                "initial_velocity_m_per_s",
                info.initial_velocity_m_per_s,
                v0,
                resolution,
                rid,
                f"the spacecraft model started at {v0:.6g} m/s; the JSON says "
                f"{info.initial_velocity_m_per_s:.6g} m/s",
            )
        )

    coef, se, resid, deadband, noise_levels = _compensation(run, h, found)
    negative = int(np.sum(fc < 0.0))
    if negative:
        found.append(
            Finding(
                "clamp",
                0.0,
                float(np.min(fc)),
                0.0,
                rid,
                f"f_comp is negative on {negative} tick(s) (down to {np.min(fc):.4g} N): "
                "the computer does not clamp it at zero",
            )
        )
    est = ComputerEstimate(
        run_id=run.run_id,
        time_step_s=float(h),
        time_step_se=float(h_se),
        integrator=rule,
        position_weight=float(weight),
        position_weight_se=float(weight_se),
        initial_gap_m=float(gap),
        initial_velocity_m_per_s=float(v0),
        mass_kg=float(m),
        mass_se=float(m_se),
        lead_time_s=float(coef[1]),
        lead_time_se=float(se[1]),
        stiffness_n_per_m=float(coef[2]),
        stiffness_se=float(se[2]),
        gain=float(coef[0]),
        gain_se=float(se[0]),
        offset_n=float(coef[3]),
        offset_se=float(se[3]),
        compensation_residual_n=float(resid),
        compensation_noise_levels=noise_levels,
        deadband_n=deadband,
        force_ticks=int(on.sum()),
        free_velocity_change_m_per_s=free_change,
        negative_force_ticks=negative,
    )
    return est, found


def _compensation(run: Run, h: float, found: list[Finding]) -> tuple:
    """The compensation's constants solved from one run (see the module doc),
    its findings appended to ``found``: (coefficients ``[a, L, K, b]``, their
    standard errors, the residual RMS (N), the dead band's bounds, and the
    JSON's law's misfit in noise levels where the readings carry noise the
    computer did not see: then the constants are not solved, NaN)."""
    info, rid = run.info, (run.run_id,)
    f = np.asarray(run.f_mea_n, dtype=float)
    fc = np.asarray(run.f_comp_n, dtype=float)
    p_des = np.asarray(run.p_des_m, dtype=float)
    p_act = np.asarray(run.p_act_m, dtype=float)
    # f_comp = a f + L df/h + K (p_des[k-1] - p_act[k]) + b, the law's terms from its
    # definition (a gain of the reading, the lead's, the MDC's per N/m)
    k = np.arange(1, len(f))
    rate = backward_difference(f[k], f[k - 1], h)
    terms = linear_terms(f[k], rate, response_error=p_des[k - 1] - p_act[k], stiffness=1.0)
    x_all = np.column_stack([*terms, np.ones(len(k))])
    rows = fc[k] != 0.0
    lead_json = info.lead_time_s if info.compensator in ("SDC", "SDMDC") else 0.0
    stiff_json = info.contact_stiffness_n_per_m if info.compensator in ("MDC", "SDMDC") else 0.0
    nan4 = np.full(4, math.nan)
    if rows.sum() < 8:
        return nan4, nan4, math.nan, (math.nan, math.nan), math.nan
    coef, se, resid = linear_fit(x_all[rows], fc[k][rows])
    f_scale = float(np.max(np.abs(fc)))
    exact = resid <= 1e-4 * f_scale + 10 * 1e-9 * f_scale
    before = int(np.argmax(p_act > 0.0))
    (sigma_f,), noisy_f = reading_noise(f, before)
    (sigma_p,), noisy_p = reading_noise(p_act, before)
    if exact or not (noisy_f or (noisy_p and stiff_json > 0.0)):
        _constants(info, h, (lead_json, stiff_json), coef, se, resid, f_scale, exact, found)
        pre = x_all @ coef  # every tick's compensation, ungated
        pending = pre > 5.0 * resid + 1e-9 * f_scale
        levels, slack = math.nan, 0.0
    else:
        # Noise the computer did not see, or another law: a fit on noisy readings is
        # biased (errors in variables), so the constants are not solved; the JSON's law
        # is tested over means of blocks of ticks, and bounds the dead band.
        stated = x_all[:, :3] @ [1.0, lead_json, stiff_json]
        var_m = np.full((len(k), 1), stiff_json**2 * sigma_p**2)
        m = block_ticks(int(rows.sum()))
        misfit = (fc[k] - stated)[:, None]
        levels = float(
            stated_law_levels(misfit, rows, np.array([sigma_f**2]), var_m, lead_json / h, m)[0]
        )
        coef, se = nan4, nan4
        if not levels <= NOISE_LEVELS:
            found.append(
                Finding(
                    "compensation_law",
                    0.0,
                    resid,
                    0.0,
                    rid,
                    f"f_comp is not the JSON's {info.compensator} law of the logged readings: "
                    + (
                        f"over means of {m} ticks it misses by {levels:.3g} noise levels (at "
                        f"most {NOISE_LEVELS:g}), and no gain, lead, stiffness and offset make it "
                        "one exactly"
                        if math.isfinite(levels)
                        else "no gain, lead, stiffness and offset make it one exactly, and its "
                        "stretches of force are too short to tell noise from another law"
                    )
                    + ": the computer compensates otherwise, or the log's readings carry "
                    "noise it did not see, and then which of its constants differs cannot be "
                    "solved from them",
                )
            )
        lead = lead_json / h
        noise = math.sqrt(sigma_f**2 * ((1.0 + lead) ** 2 + lead**2) + var_m[0, 0])
        pending = stated > 3.0 * noise  # a compensation the clamp does not explain
        slack = 5.0 * sigma_f
    lower, upper = deadband_bounds(f[k], fc[k] > 0.0, pending, slack)
    db = info.force_deadband_n
    verdict = deadband_used(lower, upper, db)
    if verdict is not None:
        used, half = verdict
        found.append(
            Finding(
                "force_deadband_n",
                db,
                used,
                half,
                rid,
                f"which readings give no force is not a deadband: a reading of "
                f"{lower:.4g} N gave none, one of {upper:.4g} N gave one"
                if lower >= upper
                else f"force_deadband_n used between {max(lower, 0.0):.4g} and {upper:.4g} N, "
                f"JSON says {db:.4g} N",
            )
        )
    return coef, se, resid, (lower, upper), levels


def _constants(info, h, stated, coef, se, resid, f_scale, exact, found: list[Finding]) -> None:
    """The findings of the compensation's solved constants against the
    ``stated`` lead and MDC stiffness (and, when no constant makes the law
    exact, that)."""
    a, lead, stiff, off = (float(c) for c in coef)
    a_se, lead_se, stiff_se, off_se = (float(s) for s in se)
    lead_json, stiff_json = stated
    rid = (info.run_id,)
    if not exact:
        found.append(
            Finding(
                "compensation_law",
                0.0,
                resid,
                0.0,
                rid,
                f"f_comp is not the format's compensation of the readings: "
                f"{resid:.3g} N RMS remain after fitting a gain, a lead, a "
                "stiffness and an offset",
            )
        )
    if differs(lead, lead_se, lead_json, max(lead_json, h)):
        says = (
            f"JSON says {lead_json * 1e3:.6g} ms"
            if lead_json > 0.0
            else f"the JSON's compensator {info.compensator} has no lead"
        )
        found.append(
            Finding(
                "lead_time_s",
                lead_json,
                lead,
                lead_se,
                rid,
                f"lead_time_s used {lead * 1e3:.6g} ms, {says}",
            )
        )
    k_scale = max(stiff_json, info.contact_stiffness_n_per_m)
    if differs(stiff, stiff_se, stiff_json, k_scale):
        says = (
            f"JSON says {stiff_json:.6g} N/m"
            if stiff_json > 0.0
            else f"the JSON's compensator {info.compensator} has no MDC"
        )
        found.append(
            Finding(
                "contact_stiffness_n_per_m",
                stiff_json,
                stiff,
                stiff_se,
                rid,
                f"the MDC stiffness used {stiff:.6g} N/m, {says}",
            )
        )
    if differs(a, a_se, 1.0, 1.0):
        found.append(
            Finding(
                "compensation_gain",
                1.0,
                a,
                a_se,
                rid,
                f"the computer scales the force reading by {a:.6g} before compensating",
            )
        )
    if differs(off, off_se, 0.0, f_scale):
        found.append(
            Finding(
                "compensation_offset_n",
                0.0,
                off,
                off_se,
                rid,
                f"the computer adds {off:.4g} N to the compensated force",
            )
        )


def _integration_rule(dx: np.ndarray, v: np.ndarray) -> tuple[str, float, float, float, float]:
    """The rule by which the computer stepped ``p_des`` (steps ``dx``) from its
    velocities ``v``: the fit ``dx = h v[k] - c (v[k] - v[k-1])``, as
    ``(rule, theta, theta_se, h, h_se)`` with ``theta = 1 - c / h``. The
    rule is the format's (``theta`` 1, its standard error 0, ``h`` NaN) while
    ``theta`` is within five standard errors or :data:`RELATIVE_TOLERANCE` of
    1, or the velocity never changes (nothing tells); else the nearest of
    :data:`~hybridtable.laws.spacecraft.INTEGRATORS` within the same of it,
    else ``"other"``."""
    fmt = (DEFAULT_INTEGRATOR, 1.0, 0.0, math.nan, math.nan)
    dv = np.diff(v)
    if len(dx) < 3 or not np.any(dv != 0.0):
        return fmt
    (h, c), (h_se, c_se), _ = linear_fit(np.column_stack([v[1:], -dv]), dx)
    if not (math.isfinite(h) and h > 0.0 and math.isfinite(c_se)):
        return fmt
    theta = 1.0 - c / h
    theta_se = math.hypot(c_se / h, c * h_se / (h * h))
    if abs(theta - 1.0) <= max(SIGNIFICANCE * theta_se, RELATIVE_TOLERANCE):
        return fmt
    rule = min(INTEGRATORS, key=lambda r: abs(theta - INTEGRATORS[r]))
    if abs(theta - INTEGRATORS[rule]) > max(SIGNIFICANCE * theta_se, 1e-2):
        rule = "other"
    return rule, theta, theta_se, h, h_se


def audit_runs(runs: Sequence[Run]) -> Audit:
    """Audit every run; findings of the same key whose values agree (within
    five standard errors or :data:`RELATIVE_TOLERANCE`) are merged into one
    naming all their runs, with the inverse-variance mean."""
    estimates: list[ComputerEstimate] = []
    per_key: dict[str, list[Finding]] = {}
    for run in runs:
        est, found = audit_run(run)
        estimates.append(est)
        for f in found:
            per_key.setdefault(f.key, []).append(f)
    findings: list[Finding] = []
    for group in per_key.values():
        merged: list[list[Finding]] = []
        for f in group:
            for m in merged:
                g = m[0]
                d = abs(f.used_value - g.used_value)
                tol = max(
                    SIGNIFICANCE * math.hypot(_finite(f.uncertainty), _finite(g.uncertainty)),
                    RELATIVE_TOLERANCE * max(abs(g.used_value), abs(g.json_value)),
                )
                if f.json_value == g.json_value and d <= tol:
                    m.append(f)
                    break
            else:
                merged.append([f])
        for m in merged:
            findings.append(_merge(m))
    notes = []
    if any(not math.isfinite(e.mass_kg) for e in estimates):
        notes.append("a run without compensated force: its mass cannot be audited")
    for e in estimates:
        if e.compensation_noise_levels <= NOISE_LEVELS:
            notes.append(
                f"{e.run_id}: its compensation is the JSON's to the noise of its logged readings, "
                f"which the computer did not see ({e.compensation_noise_levels:.2g} noise levels "
                "over means of ticks): its lead, stiffness, gain and offset are not solved"
            )
    return Audit(estimates, findings, notes)


def _finite(x: float) -> float:
    return x if math.isfinite(x) else 0.0


def _merge(group: list[Finding]) -> Finding:
    if len(group) == 1:
        return group[0]
    w = np.array([1.0 / f.uncertainty**2 if f.uncertainty > 0 else 0.0 for f in group])
    values = np.array([f.used_value for f in group])
    if w.sum() > 0.0 and np.all(np.isfinite(w)):
        used = float(w @ values / w.sum())
        se = float(1.0 / math.sqrt(w.sum()))
    else:
        used, se = float(np.mean(values)), group[0].uncertainty
    runs = tuple(r for f in group for r in f.runs)
    text = group[0].text if len(group) == 1 else f"{group[0].text} (runs {', '.join(runs)})"
    return Finding(group[0].key, group[0].json_value, used, se, runs, text)
