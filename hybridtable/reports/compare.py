"""The report of ``hybridtable compare``: the verdict, the text tables, the
whiteness in words, and report.md with the figures of
:mod:`~hybridtable.reports.compare_figures`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from hybridtable.measurement.comparison import COR_MATCH_TOLERANCE, RunComparison
from hybridtable.measurement.phases import PHASES
from hybridtable.measurement.run_format import RUN_COLUMNS
from hybridtable.reports.compare_figures import (
    FIGURES,
    figure_stem,
    plot_correlation,
    plot_force_deflection,
    plot_overlay,
    plot_residuals,
)

__all__ = [
    "format_table",
    "format_error_fall",
    "format_whiteness",
    "verdict",
    "whiteness_sentence",
    "write_report",
    "figure_stem",
]

#: The replay channels and their plain names.
_CHANNEL_WORDS = {"f_mea_n": "force", "p_act_m": "position"}


def _fmt(x: float, spec: str) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def _fit(x: float) -> str:
    """A fit in %, one decimal, never rounded up to a perfect 100.0."""
    if not math.isfinite(x):
        return "n/a"
    text = f"{x:.1f}"
    if text == "100.0" and x < 100.0:
        text = f"{math.floor(x * 100.0) / 100.0:.2f}"
    return text


def _span(values: Sequence[float], fmt) -> str:
    """``a-b`` from the smallest to the largest value (one value if they print alike)."""
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return "n/a"
    lo, hi = fmt(min(finite)), fmt(max(finite))
    return lo if lo == hi else f"{lo}-{hi}"


def _id_width(comparisons: Sequence[RunComparison]) -> int:
    return max([3, *(len(c.run_id) for c in comparisons)])


def verdict(comparisons: Sequence[RunComparison], subject: str = "The model") -> str:
    """One plain sentence: does ``subject`` match the runs within the noise,
    and if not, where is it worst.

    A run is matched when the replay RMS error of force and position is at most
    :data:`~hybridtable.measurement.comparison.WITHIN_NOISE_RATIO` times its noise
    RMS and the closed loop's CoR is within
    :data:`~hybridtable.measurement.comparison.COR_MATCH_TOLERANCE` of the recorded one. The ratios are printed as ``1.03x`` (error over noise), the fit in %
    (``100 (1 - NRMSE)``, see :func:`~hybridtable.measurement.stats.channel_error`).
    """
    n = len(comparisons)
    chans = tuple(_CHANNEL_WORDS)
    unjudged = [
        c for c in comparisons if not all(math.isfinite(c.error_to_noise(ch)) for ch in chans)
    ]
    missed = [
        c
        for c in comparisons
        if not c.cor_matches()
        or (c not in unjudged and not all(c.within_noise(ch) for ch in chans))
    ]
    if missed:
        if len(missed) < n:
            where = f"{len(missed)} of {n} runs"
        else:
            where = {1: "the run", 2: "both runs"}.get(n, f"all {n} runs")
        parts = []
        for ch in chans:
            bad = [c for c in missed if c not in unjudged and not c.within_noise(ch)]
            if not bad:
                continue
            worst = max(bad, key=lambda c: c.error_to_noise(ch))
            phase = worst.worst_phase(ch)
            up_to = "" if len(bad) == 1 else "up to "
            parts.append(
                f"{_CHANNEL_WORDS[ch]} error {up_to}{worst.error_to_noise(ch):.2f}x the noise, "
                f"worst in {phase.replace('_', ' ')} "
                f"({worst.phase_error_to_noise(ch, phase):.1f}x)"
            )
        off = [c for c in missed if not c.cor_matches()]
        if off:
            worst = max(off, key=lambda c: abs(c.cor_model - c.cor_measured))
            up_to = "" if len(off) == 1 else "up to "
            parts.append(
                f"CoR off by {up_to}{worst.cor_model - worst.cor_measured:+.3f} (measured "
                f"{worst.cor_measured:.3f}, model {worst.cor_model:.3f}, tolerance "
                f"{COR_MATCH_TOLERANCE:g})"
            )
        return (
            f"{subject} misses something in {where}: {'; '.join(parts)}; try hybridtable diagnose"
        )
    judged = [c for c in comparisons if c not in unjudged]
    if not judged:
        return f"{subject} cannot be judged: no run has a noise estimate (no quiet ticks)"
    runs = "the run" if len(judged) == 1 else f"the {len(judged)} runs"
    ratios = {
        ch: _span([c.error_to_noise(ch) for c in judged], lambda x: f"{x:.2f}") for ch in chans
    }
    fits = {ch: _span([c.replay_errors[ch].fit_percent for c in judged], _fit) for ch in chans}
    text = (
        f"{subject} matches {runs} within the noise (force error {ratios['f_mea_n']}x, "
        f"position {ratios['p_act_m']}x the noise; fit {fits['f_mea_n']} % force, "
        f"{fits['p_act_m']} % position)"
    )
    for ch in chans:  # structure too small to matter is still said, not hidden
        shaped = [c for c in judged if ch in c.whiteness and not c.whiteness[ch].white]
        if shaped:
            where = "the run" if len(judged) == 1 else f"{len(shaped)} of {len(judged)} runs"
            text += (
                f"; the {_CHANNEL_WORDS[ch]} residual still has structure in {where} (a "
                f"systematic effect too small to matter: error at most "
                f"{max(c.error_to_noise(ch) for c in shaped):.2f}x the noise)"
            )
    if unjudged:
        names = ", ".join(c.run_id for c in unjudged)
        text += f"; {names}: no noise estimate (no quiet ticks), not judged"
    return text


def _why_not_white(s: dict, kind: str) -> str:
    """Why the ``kind`` ("auto" or "cross") correlation of a summary is not white."""
    name = {"auto": "autocorrelation", "cross": "command cross-correlation"}[kind]
    k, n, most = s[f"{kind}_lags_outside"], s[f"{kind}_lags"], s[f"{kind}_chance_limit"]
    if k > most:
        return f"{k} of {n} {name} lags lie outside the 99 % band (at most {most} by chance)"
    return (
        f"its {name} reaches {s[f'{kind}_max_abs']:.2f} at {s[f'{kind}_max_lag_s'] * 1e3:.0f} ms "
        f"(a white residual stays below {s[f'{kind}_peak_limit']:.2f})"
    )


def whiteness_sentence(c: RunComparison, channel: str) -> str:
    """What the whiteness tests of ``channel``'s replay residual imply, in words.

    A correlation beyond what chance gives a white residual
    (:attr:`~hybridtable.measurement.stats.Correlation.auto_white`) means the
    residual holds structure: an effect the model lacks. Its size is judged by
    the error over the noise (:meth:`RunComparison.within_noise`).
    """
    corr = c.whiteness[channel]
    s = corr.summary()
    ratio = _fmt(c.error_to_noise(channel), ".2f")
    if corr.white:
        counts = (
            f"{s['auto_lags_outside']} of {s['auto_lags']} autocorrelation lags, "
            f"{s['cross_lags_outside']} of {s['cross_lags']} command cross-correlation lags "
            "outside the 99 % band"
        )
        if c.within_noise(channel):
            return f"the residual is white: what is left is sensor noise ({counts})"
        return (
            f"the residual is white but {ratio}x the noise measured while apart: the readings "
            f"are noisier in contact, or the model misses an effect without memory ({counts})"
        )
    if not corr.auto_white and not corr.cross_white:
        if (
            s["auto_lags_outside"] > s["auto_chance_limit"]
            and s["cross_lags_outside"] > s["cross_chance_limit"]
        ):
            why = (
                f"{s['auto_lags_outside']} of {s['auto_lags']} autocorrelation and "
                f"{s['cross_lags_outside']} of {s['cross_lags']} command cross-correlation lags "
                f"lie outside the 99 % band (at most {s['auto_chance_limit']} by chance)"
            )
        else:
            why = f"{_why_not_white(s, 'auto')}; {_why_not_white(s, 'cross')}"
        text = f"the residual is not noise and follows the command: {why}"
    elif not corr.auto_white:
        text = f"the residual is not noise: {_why_not_white(s, 'auto')}"
    else:
        text = f"the residual follows the command: {_why_not_white(s, 'cross')}"
    if c.within_noise(channel):
        return text + f"; a systematic effect but a small one (error {ratio}x the noise)"
    return text + (
        f"; so the model misses a systematic effect (error {ratio}x the noise; "
        "try hybridtable diagnose)"
    )


def format_whiteness(comparisons: Sequence[RunComparison]) -> str:
    """Per run and channel, what the whiteness of the replay residual implies."""
    w = _id_width(comparisons)
    lines = ["whiteness of the replay residuals:"]
    for c in comparisons:
        for ch, word in _CHANNEL_WORDS.items():
            lines.append(f"  {c.run_id:<{w}}  {word + ':':<9} {whiteness_sentence(c, ch)}")
    return "\n".join(lines)


def format_table(comparisons: Sequence[RunComparison]) -> str:
    """One line per run: replay errors against the noise floor, fit, CoR, worst
    phase. Run ids are shown whole; the columns widen to the longest."""
    w = _id_width(comparisons)
    wc = max([4, *(len(c.run.info.compensator) for c in comparisons)])
    head = (
        f"{'run':<{w}} {'comp':<{wc}} {'f_mea rms/noise [N]':>21} {'p_act rms/noise [um]':>22} "
        f"{'fit f_mea/p_act [%]':>20} "
        f"{'CoR meas':>9} {'CoR model':>9} {'dCoR':>8}  worst f_mea phase: rms/noise (share)"
    )
    lines = [head, "-" * len(head)]
    for c in comparisons:
        f_err = c.replay_errors["f_mea_n"].rms_error
        p_err = c.replay_errors["p_act_m"].rms_error * 1e6
        f_noise = c.noise_rms["f_mea_n"]
        p_noise = c.noise_rms["p_act_m"] * 1e6
        ph = c.phases["f_mea_n"]
        worst = max(PHASES, key=lambda n: np.nan_to_num(ph[n]["rms_error"], nan=-1.0))
        worst_ratio = ph[worst]["rms_error"] / f_noise if f_noise > 0 else math.nan
        fit = (
            f"{_fit(c.replay_errors['f_mea_n'].fit_percent)}/"
            f"{_fit(c.replay_errors['p_act_m'].fit_percent)}"
        )
        lines.append(
            f"{c.run_id:<{w}} {c.run.info.compensator:<{wc}} "
            f"{_fmt(f_err, '#.3g'):>6}/{_fmt(f_noise, '#.3g'):<6} x{_fmt(c.error_to_noise('f_mea_n'), '.2f'):<5} "
            f"{_fmt(p_err, '#.3g'):>7}/{_fmt(p_noise, '#.3g'):<6} x{_fmt(c.error_to_noise('p_act_m'), '.2f'):<5} "
            f"{fit:>20} "
            f"{_fmt(c.cor_measured, '.5f'):>9} {_fmt(c.cor_model, '.5f'):>9} "
            f"{_fmt(c.cor_model - c.cor_measured, '+.5f'):>8}  {worst} "
            f"x{_fmt(worst_ratio, '.2f')} ({_fmt(ph[worst]['share'], '.0%')} of the error)"
        )
    return "\n".join(lines)


def _md_num(x: float, spec: str) -> str:
    return _fmt(x, spec)


def write_report(
    comparisons: Sequence[RunComparison],
    folder: str | Path,
    verdict_text: str | None = None,
) -> list[Path]:
    """Write ``report.md`` (and ``report.html``) and the figures into ``folder``;
    returns the files written.

    Parameters
    ----------
    comparisons : sequence of RunComparison
    folder : path
    verdict_text : str, optional
        The report's opening sentence (default: :func:`verdict` of ``comparisons``).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    md = [
        "# Model against measured runs",
        "",
        f"**{verdict_text or verdict(comparisons)}.**",
        "",
        "Replay: the rig's physical part (table, contact, force sensor) driven by the recorded "
        "command; closed loop: the whole rig loop re-run from the run's initial state. "
        "Definitions of every number: `docs/compare.md`.",
        "",
        "```",
        format_table(comparisons),
        "```",
        "",
    ]
    for i, c in enumerate(comparisons):
        stem = figure_stem(i, c.run_id)
        figs = {
            "overlay": plot_overlay(c, folder / f"{stem}_overlay.png"),
            "residuals": plot_residuals(c, folder / f"{stem}_residuals.png"),
            "correlation": plot_correlation(c, folder / f"{stem}_correlation.png"),
            "force_deflection": plot_force_deflection(c, folder / f"{stem}_force_deflection.png"),
        }
        written.extend(figs.values())
        j = c.to_json()
        md += [
            f"## {c.run_id}",
            "",
            f"`{c.run.csv_path}`, compensator {c.run.info.compensator}, "
            f"{c.run.n} ticks at {c.run.info.sample_rate_hz:g} Hz, physics: {c.physics}.",
            "",
            "| channel | RMS error | noise RMS | error / noise | NRMSE | fit % |",
            "| --- | --- | --- | --- | --- | --- |",
        ]
        for ch, unit, scale in (("f_mea_n", "N", 1.0), ("p_act_m", "um", 1e6)):
            e = c.replay_errors[ch]
            md.append(
                f"| replay {ch} | {_md_num(e.rms_error * scale, '.4g')} {unit} "
                f"| {_md_num(c.noise_rms[ch] * scale, '.4g')} {unit} "
                f"| {_md_num(c.error_to_noise(ch), '.3f')} | {_md_num(e.nrmse, '.4f')} "
                f"| {_md_num(e.fit_percent, '.2f')} |"
            )
        for ch, e in c.closed_loop_errors.items():
            md.append(
                f"| closed loop {ch} | {_md_num(e.rms_error, '.4g')} {RUN_COLUMNS[ch]} | | | "
                f"{_md_num(e.nrmse, '.4f')} | {_md_num(e.fit_percent, '.2f')} |"
            )
        md += [
            "",
            f"CoR measured {_md_num(c.cor_measured, '.5f')}, model {_md_num(c.cor_model, '.5f')} "
            f"(difference {_md_num(c.cor_model - c.cor_measured, '+.5f')}). "
            f"Peak force measured {j['peak_force_n']['measured']:.1f} N, replay "
            f"{j['peak_force_n']['replay']:.1f} N, closed loop {j['peak_force_n']['closed_loop']:.1f} N. "
            f"Contact duration measured {_md_num(j['contact_duration_s']['measured'], '.4f')} s, "
            f"replay {_md_num(j['contact_duration_s']['replay'], '.4f')} s, closed loop "
            f"{_md_num(j['contact_duration_s']['closed_loop'], '.4f')} s. "
            f"Mean no-contact reading (sensor offset) {_md_num(c.no_contact_mean_f_mea_n, '+.3g')} N.",
            "",
            "| phase | ticks | time share | f_mea RMS error [N] | f_mea mean error [N] | share "
            "| p_act RMS error [um] | share |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for ph in PHASES:
            f = c.phases["f_mea_n"][ph]
            p = c.phases["p_act_m"][ph]
            md.append(
                f"| {ph} | {f['samples']} | {f['time_fraction']:.2f} | "
                f"{_md_num(f['rms_error'], '.3g')} | {_md_num(f['mean_error'], '+.3g')} | "
                f"{_md_num(f['share'], '.1%')} | {_md_num(p['rms_error'] * 1e6, '.3g')} | "
                f"{_md_num(p['share'], '.1%')} |"
            )
        md += ["", "Whiteness of the replay residuals (99 % band):", ""]
        for ch, word in _CHANNEL_WORDS.items():
            s = c.whiteness[ch].summary()
            md.append(
                f"- {word} ({ch}): {whiteness_sentence(c, ch)}. Largest autocorrelation "
                f"{s['auto_max_abs']:.3f}, largest cross-correlation {s['cross_max_abs']:.3f} at "
                f"{s['cross_max_lag_s'] * 1e3:.0f} ms (band {s['band']:.3f})."
            )
        md += [
            "",
            f"Force-deflection loop energy: measured {c.loop_energy_j['measured']:+.4g} J, "
            f"model {c.loop_energy_j['model']:+.4g} J (> 0: the contact dissipates).",
            "",
        ]
        if c.notes:
            md += [f"Note: {n}" for n in c.notes] + [""]
        for key, p in figs.items():
            title, caption = FIGURES[key]
            md += [f"![{title}, {c.run_id}]({p.name})", f"*{caption}*", ""]
    report = folder / "report.md"
    report.write_text("\n".join(md))
    written.insert(0, report)
    from hybridtable.reports.html import write_html_report

    write_html_report(report)  # report.html beside it: the same text, figures embedded
    return written


def format_error_fall(nominal, with_effect, label: str) -> str:
    """Per run: replay errors over the noise and closed-loop errors, nominal
    model -> model with the effect."""
    w = _id_width(nominal)
    head = (
        f"{'run':<{w}} {'f_mea rms/noise':>17} {'p_act rms/noise':>17} "
        f"{'v_des rms [mm/s]':>19} {'CoR error':>21}"
    )
    lines = [f"error fall with {label}:", head, "-" * len(head)]
    for a, b in zip(nominal, with_effect, strict=True):
        va = a.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        vb = b.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        lines.append(
            f"{a.run_id:<{w}} {a.error_to_noise('f_mea_n'):7.3f} -> {b.error_to_noise('f_mea_n'):<6.3f} "
            f"{a.error_to_noise('p_act_m'):7.3f} -> {b.error_to_noise('p_act_m'):<6.3f} "
            f"{va:8.3g} -> {vb:<8.3g} "
            f"{a.cor_model - a.cor_measured:+9.5f} -> {b.cor_model - b.cor_measured:<+9.5f}"
        )
    return "\n".join(lines)
