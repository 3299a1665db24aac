"""The report of ``hybridtable diagnose``: a text ranking and Markdown with PNG figures.

Figures: the staircase (error against effects added), and per run the
measured signals with the nominal and the diagnosed model (replay), the
residuals by phase before and after, and the force-deflection loops before
and after.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridtable.diagnosis.candidates import Candidate, Diagnosis
from hybridtable.diagnosis.evaluate import RunData  # noqa: E402
from hybridtable.diagnosis.goodness import WINDOW_ERROR_FLOOR  # noqa: E402
from hybridtable.effects.registry import get_effect  # noqa: E402
from hybridtable.effects.selection import separation_words  # noqa: E402
from hybridtable.measurement.phases import PHASES, contact_mask, loop_energy  # noqa: E402
from hybridtable.reports.compare import figure_stem  # noqa: E402
from hybridtable.reports.figure_text import literal  # noqa: E402

__all__ = [
    "summary_sentence",
    "format_audit",
    "format_remaining",
    "format_ranking",
    "format_parameters",
    "separation_text",
    "write_report",
]

#: File that marks a folder as written by ``hybridtable diagnose --report``.


def _fmt(x, spec: str) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        width = "".join(ch for ch in spec.split(".")[0] if ch.isdigit())
        return "-".rjust(int(width) if width else 1)
    return format(x, spec)


def format_parameters(effect: str, values: dict[str, float]) -> str:
    """``name=value unit`` of an effect's parameters."""
    units = {p.name: p.unit for p in get_effect(effect).parameters}
    return ", ".join(
        f"{k}={v:.4g}" + ("" if units.get(k, "1") == "1" else f" {units[k]}")
        for k, v in values.items()
    )


def _rows(cands: list[Candidate]) -> list[str]:
    out = []
    for c in cands:
        alike = ",".join(c.indistinguishable_from) or "-"
        out.append(
            f"{c.effect:<20} {_fmt(c.delta_bic, '10.1f')} {_fmt(c.heldout_z, '7.1f')} "
            f"{_fmt(c.error_before, '9.4g')} {_fmt(c.error_after, '9.4g')} "
            f"{_fmt(c.heldout_error_after, '9.4g')} {_fmt(c.excess_removed * 100, '7.0f')}% "
            f"{'yes' if c.accepted else 'no':<4} "
            f"{alike:<22} {format_parameters(c.effect, c.parameters)}"
        )
    return out


_CHANNEL_WORDS = {"f_mea_n": "force", "p_act_m": "table position"}
_PHASE_WORDS = {
    "approach": "before the touch",
    "compression": "in compression",
    "restitution": "in restitution",
    "free_flight": "after separation",
}


def _where_words(w) -> str:
    phase = _PHASE_WORDS.get(w.phase, w.phase)
    if w.phase == "compression" and w.misfit_start_s <= w.start_s + 0.1 * (w.end_s - w.start_s):
        phase = "at the touch"
    if w.misfit_end_s > w.misfit_start_s:
        when = f"{w.misfit_start_s:.3f}-{w.misfit_end_s:.3f} s"
    else:  # a window of one tick, at the phase's end
        when = f"at {w.misfit_start_s:.3f} s"
    return (
        f"the {_CHANNEL_WORDS.get(w.channel, w.channel)} error {phase} of {w.run_id} "
        f"({when}, {w.band_hz[0]:.3g}-{w.band_hz[1]:.3g} Hz) "
        f"is {w.error:.3g}x the noise"
    )


def summary_sentence(d: Diagnosis) -> str:
    """The verdict in one plain sentence, with its evidence."""
    g = d.goodness
    held = d.heldout_error
    computer = "; ".join(f.text for f in d.audit.findings)
    if d.explained and not d.named:
        return (
            f"Nothing is missing: the nominal model explains the runs to the noise "
            f"(held-out error {held:.3g}x the noise; the residuals pass the end test, "
            f"p = {g.p_value:.2g} at a false-alarm rate of {g.false_alarm_rate:.0%})."
        )
    if not d.named:
        w = g.where
        near = d.ranking[0] if d.ranking else None
        tail = (
            f"; the nearest effect, {near.effect}, is not accepted: {near.reason}"
            if near is not None
            else ""
        )
        return (
            "The model misses something no effect of the library explains: "
            + (_where_words(w) if w else f"the held-out error is {held:.3g}x the noise")
            + f" (end test p = {g.p_value:.2g}){tail}."
        )
    parts = []
    if d.audit.findings:
        parts.append(f"The rig computer did not do what its JSON says: {computer}")
    if d.selected:
        nominal = d.staircase[0]["heldout_error"]
        named = [f"{n} ({format_parameters(n, d.selected_values[n])})" for n in d.selected]
        params = " and ".join([", ".join(named[:-1]), named[-1]] if len(named) > 1 else named)
        parts.append(
            f"The model misses {params}: with {'them' if len(named) > 1 else 'it'} the "
            f"held-out error falls from {nominal:.3g} to {held:.3g}x the noise"
        )
    if d.explained:
        parts.append(
            f"With {' + '.join(d.named)} the residuals pass the end test (p = {g.p_value:.2g})"
        )
    else:
        w = g.where
        parts.insert(
            0,
            f"The model still misses something: with {' + '.join(d.named)} added, "
            + (_where_words(w) if w else f"the held-out error is {held:.3g}x the noise"),
        )
    return ". ".join(parts) + "."


def format_audit(d: Diagnosis) -> str:
    """The audit of the rig computer, as text."""
    a = d.audit
    if a.ok:
        return (
            "audit of the rig computer: it did what the JSON says (mass, lead time, MDC "
            "stiffness, deadband, clamp, time step, initial state)"
        )
    return "\n".join(
        ["audit of the rig computer (solved from the record, not fitted):"]
        + [f"  {f.effect:<28} {f.text}" for f in a.findings]
    )


def format_remaining(d: Diagnosis) -> str:
    """What the final model leaves, as text."""
    g = d.goodness
    lines = [
        f"remaining: held-out error {d.heldout_error:.4g}x the noise; end test "
        f"{'passed' if g.passed else 'FAILED'} (p = {g.p_value:.3g} over {g.tests} tests, "
        f"false-alarm rate {g.false_alarm_rate:.0%})"
    ]
    for w in g.worst:
        lines.append(
            f"  {w.run_id} {w.channel} {w.phase:<12} {w.start_s:.3f}-{w.end_s:.3f} s: error "
            f"{w.error:.3g}x noise, p = {w.p_value:.3g} (scale {w.scale_ticks} ticks, band "
            f"{w.band_hz[0]:.3g}-{w.band_hz[1]:.3g} Hz)"
            + ("" if w.relevant else "; detectable but too small to count")
        )
    if any(not w.relevant for w in g.worst):
        lines.append(
            f"  (too small to count: the window's error is under {WINDOW_ERROR_FLOOR:g}x the "
            "noise once the noise's own spread is allowed for; a real but negligible misfit)"
        )
    return "\n".join(lines)


def format_ranking(d: Diagnosis) -> str:
    """The verdict, the audit, the first round's ranking, the staircase and what remains, as text."""
    head = (
        f"{'effect':<20} {'delta_bic':>10} {'z_held':>7} {'err_bef':>9} {'err_aft':>9} "
        f"{'held_aft':>9} {'excess-':>8} {'acc':<4} {'look-alikes':<22} parameters"
    )
    lines = [
        f"verdict: {d.verdict}  (explained: {'yes' if d.explained else 'no'})",
        "",
        format_audit(d),
        "",
        "ranking (each effect fitted to all runs on top of the nominal model; "
        "errors in noise RMS units; excess-: share of the held-out excess error removed):",
        head,
        "-" * len(head),
        *_rows(d.rounds[0] if d.rounds else []),
        "",
        "why:",
        *[f"  {c.effect:<20} {c.reason}" for c in (d.rounds[0] if d.rounds else [])],
    ]
    lines += ["", "staircase:"]
    for s in d.staircase:
        label = " + ".join(s["effects"]) or "nominal"
        lines.append(
            f"  {label:<48} error {_fmt(s['error'], '.4g')}  held-out {_fmt(s['heldout_error'], '.4g')}"
        )
    lines += ["", format_remaining(d)]
    for c in d.ranking:
        if c.separation and c.accepted and c.effect in d.selected[:1]:
            lines += ["", separation_text(c)]
    return "\n".join(lines)


def separation_text(c: Candidate) -> str:
    """What run would tell ``c`` from its look-alikes, in words
    (:func:`~hybridtable.effects.selection.separation_words`)."""
    s = c.separation
    return separation_words(s, s.get("effects") or [c.effect, *c.indistinguishable_from])


# -- figures -------------------------------------------------------------------
def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_staircase(d: Diagnosis, path: Path) -> Path:
    """Error (fitted runs and held-out, noise units) against the effects added."""
    steps = d.staircase
    labels = ["nominal"] + [f"+ {s['effects'][-1]}" for s in steps[1:]]
    x = np.arange(len(steps))
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.bar(x - 0.18, [s["error"] for s in steps], 0.36, label="error (fitted runs)")
    held = [s["heldout_error"] for s in steps]
    ax.bar(x + 0.18, held, 0.36, label="held-out error (leave one run out)")
    for xi, e in zip(x, [s["error"] for s in steps], strict=True):
        ax.annotate(f"{e:.3g}", (xi - 0.18, e), ha="center", va="bottom", fontsize=8)
    ax.axhline(1.0, color="k", ls=":", lw=1, label="noise floor")
    ax.set_xticks(x, [literal(s) for s in labels], fontsize=8)
    ax.set_ylabel("RMS error / noise RMS [1]")
    ax.set_ylim(0, max(1.2, 1.12 * max(s["error"] for s in steps)))
    ax.grid(True, alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    ax.set_title(f"staircase: error against effects added (verdict: {d.verdict})", fontsize=9)
    return _save(fig, path)


def _window(d: RunData, margin: int = 60) -> slice:
    idx = np.flatnonzero((d.labels == 1) | (d.labels == 2))
    a = max(idx[0] - margin, 0)
    b = min(idx[-1] + d.delay_ticks + margin, d.run.n - 1)
    return slice(a, b + 1)


def plot_overlay(d: Diagnosis, i: int, path: Path) -> Path:
    """Measured f_mea and p_act with the nominal and the diagnosed replay."""
    rd = d.data[i]
    r = rd.run
    nom, fin = d.nominal[i].prediction, d.final[i].prediction
    w = _window(rd)
    t = r.time_s[w]
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax[0].plot(t, r.f_mea_n[w], ".", ms=2, color="0.4", label="f_mea measured")
    ax[0].plot(t, nom["f_mea_n"][w], lw=1.2, label="nominal model")
    ax[0].plot(t, fin["f_mea_n"][w], lw=1.2, label="diagnosed model")
    ax[0].set_ylabel("force [N]")
    ax[1].plot(t, (r.f_mea_n - nom["f_mea_n"])[w], ".", ms=2, label="residual, nominal")
    ax[1].plot(t, (r.f_mea_n - fin["f_mea_n"])[w], ".", ms=2, label="residual, diagnosed")
    sig = rd.noise["f_mea_n"].sigma
    for s in (-2, 2):
        ax[1].axhline(s * sig, color="k", ls=":", lw=0.8)
    ax[1].set_ylabel("f_mea residual [N]")
    ax[2].plot(t, (r.p_act_m - nom["p_act_m"])[w] * 1e6, ".", ms=2, label="residual, nominal")
    ax[2].plot(t, (r.p_act_m - fin["p_act_m"])[w] * 1e6, ".", ms=2, label="residual, diagnosed")
    sig = rd.noise["p_act_m"].sigma * 1e6
    for s in (-2, 2):
        ax[2].axhline(s * sig, color="k", ls=":", lw=0.8)
    ax[2].set_ylabel("p_act residual [um]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=7, loc="best", markerscale=3)
    model = " + ".join(d.selected) or "nominal"
    ax[0].set_title(
        f"{rd.run_id}: replay before and after ({model}); dotted: +-2 noise RMS", fontsize=9
    )
    return _save(fig, path)


def _phase_rms(e: np.ndarray, labels: np.ndarray) -> list[float]:
    return [
        float(np.sqrt(np.mean(e[labels == k] ** 2))) if np.any(labels == k) else math.nan
        for k in range(len(PHASES))
    ]


def plot_phases(d: Diagnosis, i: int, path: Path) -> Path:
    """RMS residual per phase, before and after, in noise units."""
    rd = d.data[i]
    r = rd.run
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
    x = np.arange(len(PHASES))
    for k, (ch, labels) in enumerate((("f_mea_n", rd.f_labels), ("p_act_m", rd.labels))):
        sig = rd.noise[ch].sigma
        before = _phase_rms((getattr(r, ch) - d.nominal[i].prediction[ch]) / sig, labels)
        after = _phase_rms((getattr(r, ch) - d.final[i].prediction[ch]) / sig, labels)
        ax[k].bar(x - 0.2, before, 0.4, label="nominal")
        ax[k].bar(x + 0.2, after, 0.4, label="diagnosed")
        ax[k].axhline(1.0, color="k", ls=":", lw=1)
        ax[k].set_xticks(x, [p.replace("_", "\n") for p in PHASES], fontsize=8)
        ax[k].set_ylabel("RMS residual / noise RMS [1]")
        ax[k].set_title(f"{ch} residual by phase", fontsize=9)
        ax[k].grid(True, alpha=0.3, axis="y")
        ax[k].legend(fontsize=7)
    fig.suptitle(literal(rd.run_id), fontsize=9)
    return _save(fig, path)


def _loop(rd: RunData, p: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    on = contact_mask(p)
    idx = np.flatnonzero(on)
    a, b = max(idx[0] - 3, 0), min(idx[-1] + 3, len(p) - 1)
    return p[a : b + 1], f[a : b + 1], loop_energy(p, f, on)


def plot_force_deflection(d: Diagnosis, i: int, path: Path) -> Path:
    """Reading (``M`` ticks later, ``M`` the nominal delay) against penetration:
    measured, and predicted by the nominal and the diagnosed models."""
    rd = d.data[i]
    r, m = rd.run, rd.delay_ticks

    def aligned(f):
        return np.concatenate([np.asarray(f)[m:], np.full(m, np.nan)])

    valid = np.isfinite(aligned(r.f_mea_n))
    fig, ax = plt.subplots(figsize=(6, 5))
    p, f, e = _loop(rd, r.p_act_m[valid], aligned(r.f_mea_n)[valid])
    ax.plot(p * 1e3, f, ".-", ms=2, lw=0.5, color="0.4", label=f"measured ({e:+.3g} J)")
    for name, ev in (("nominal", d.nominal[i]), ("diagnosed", d.final[i])):
        pred = ev.prediction
        p, f, e = _loop(rd, pred["p_act_m"][valid], aligned(pred["f_mea_n"])[valid])
        ax.plot(p * 1e3, f, lw=1.4, label=f"{name} model ({e:+.3g} J)")
    ax.set_xlabel("penetration p_act [mm]")
    ax.set_ylabel(f"force reading {m} ticks later [N]")
    ax.set_title(f"{rd.run_id}: force-deflection loops (enclosed energy)", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


#: The caption line under each figure of a run in ``report.md``.
_CAPTIONS = {
    "overlay": "Measured force and the nominal and diagnosed models' replays [N] against "
    "time [s], with the force residual [N] and the table-position residual [um] of each.",
    "phases": "RMS residual per contact phase in units of the noise RMS [1], nominal against "
    "diagnosed model, force and table position.",
    "force_deflection": "Force reading [N] against penetration [mm] over the contact: the "
    "area a loop encloses is the energy [J] the contact (and the loop's delay) dissipates "
    "or creates.",
}


def write_report(d: Diagnosis, folder: str | Path) -> list[Path]:
    """Write ``report.md`` and the figures into ``folder``; returns the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = [plot_staircase(d, folder / "staircase.png")]
    md = [
        "# Which physical effect is missing",
        "",
        summary_sentence(d),
        "",
        f"Verdict: **{d.verdict}** (explained: {'yes' if d.explained else 'no'})"
        + (f"; model selected: {' + '.join(d.selected)}" if d.selected else "")
        + ". Definitions: `docs/diagnose.md`.",
        "",
        "```",
        format_ranking(d),
        "```",
        "",
        "## Ranking",
        "",
        "| effect | delta BIC | held-out z | error before | error after | held-out error after "
        "| excess removed | accepted | why | indistinguishable from | parameters |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for c in d.ranking:
        md.append(
            f"| {c.effect} | {_fmt(c.delta_bic, '.1f')} | {_fmt(c.heldout_z, '.1f')} "
            f"| {_fmt(c.error_before, '.4g')} | {_fmt(c.error_after, '.4g')} "
            f"| {_fmt(c.heldout_error_after, '.4g')} | {_fmt(c.excess_removed * 100, '.0f')} % "
            f"| {'yes' if c.accepted else 'no'} | {c.reason} "
            f"| {', '.join(c.indistinguishable_from) or '-'} "
            f"| {format_parameters(c.effect, c.parameters)} |"
        )
    md += ["", *[separation_text(c) for c in d.ranking if c.separation and c.effect in d.selected]]
    md += [
        "",
        "Errors: RMS residual / noise RMS over the runs and both channels (1 = noise floor).",
        "",
        "## Audit of the rig computer",
        "",
        "```",
        format_audit(d),
        "```",
        "",
        "## What remains",
        "",
        "```",
        format_remaining(d),
        "```",
        "",
        "## Staircase",
        "",
        "| model | error | held-out error | delta BIC of the step |",
        "| --- | --- | --- | --- |",
    ]
    for s in d.staircase:
        md.append(
            f"| {' + '.join(s['effects']) or 'nominal'} | {_fmt(s['error'], '.4g')} "
            f"| {_fmt(s['heldout_error'], '.4g')} | {_fmt(s['delta_bic'], '.1f')} |"
        )
    md += [
        "",
        "![staircase](staircase.png)",
        "*The error of each model of the staircase (nominal, then one effect added at a "
        "time), RMS residual over the runs in units of the noise RMS [1]: 1 is the noise "
        "floor.*",
        "",
        "## Closed loop",
        "",
    ]
    md += [
        "| run | CoR measured | CoR nominal | CoR diagnosed | v_des RMS error nominal -> diagnosed [m/s] |"
    ]
    md += ["| --- | --- | --- | --- | --- |"]
    for b, a in zip(d.closed_loop["before"]["runs"], d.closed_loop["after"]["runs"], strict=True):
        md.append(
            f"| {b['run_id']} | {_fmt(b.get('cor_measured'), '.5f')} | "
            f"{_fmt(b.get('cor_model'), '.5f')} | {_fmt(a.get('cor_model'), '.5f')} | "
            f"{_fmt(b['v_des_rms_error_m_per_s'], '.3g')} -> {_fmt(a['v_des_rms_error_m_per_s'], '.3g')} |"
        )
    md.append("")
    for i, rd in enumerate(d.data):
        stem = figure_stem(i, rd.run_id)
        figs = {
            "overlay": plot_overlay(d, i, folder / f"{stem}_overlay.png"),
            "phases": plot_phases(d, i, folder / f"{stem}_phases.png"),
            "force_deflection": plot_force_deflection(
                d, i, folder / f"{stem}_force_deflection.png"
            ),
        }
        written.extend(figs.values())
        nz = rd.noise
        md += [
            f"## {rd.run_id}",
            "",
            f"`{rd.run.csv_path}`, compensator {rd.run.info.compensator}, approach "
            f"{rd.run.info.initial_velocity_m_per_s:g} m/s. Noise: f_mea "
            f"{nz['f_mea_n'].sigma:.3g} N ({nz['f_mea_n'].describe()}), p_act "
            f"{nz['p_act_m'].sigma * 1e6:.3g} um ({nz['p_act_m'].describe()}).",
            "",
        ]
        md += [f"Note: {n}" for n in rd.notes]
        for title, p in figs.items():
            md += [f"![{rd.run_id} {title}]({p.name})", f"*{_CAPTIONS[title]}*", ""]
    if d.notes:
        md += ["", *[f"Note: {n}" for n in d.notes]]
    report = folder / "report.md"
    report.write_text("\n".join(md) + "\n")
    from hybridtable.reports.html import write_html_report

    write_html_report(report)  # report.html beside it: the same text, figures embedded
    return [report, *written]
