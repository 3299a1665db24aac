"""The report of ``hybridtable compare``: a text table and Markdown with PNG figures."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridtable.measurement.comparison import RunComparison  # noqa: E402
from hybridtable.measurement.phases import PHASES
from hybridtable.measurement.run_format import RUN_COLUMNS  # noqa: E402
from hybridtable.measurement.stats import Correlation

__all__ = ["REPORT_MARKER", "format_table", "format_error_fall", "write_report", "figure_stem"]

#: File that marks a folder as written by ``hybridtable compare --report``
#: (such a folder may be written again; any other non-empty folder is refused).
REPORT_MARKER = ".hybridtable-compare-report"

_PHASE_COLORS = {
    "approach": "tab:blue",
    "compression": "tab:red",
    "restitution": "tab:orange",
    "free_flight": "tab:green",
}


def _fmt(x: float, spec: str) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def format_table(comparisons: Sequence[RunComparison]) -> str:
    """One line per run: replay errors against the noise floor, CoR, worst phase."""
    head = (
        f"{'run':<16} {'comp':<6} {'f_mea rms/noise [N]':>21} {'p_act rms/noise [um]':>22} "
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
        lines.append(
            f"{c.run_id[:16]:<16} {c.run.info.compensator:<6} "
            f"{_fmt(f_err, '#.3g'):>6}/{_fmt(f_noise, '#.3g'):<6} x{_fmt(c.error_to_noise('f_mea_n'), '.2f'):<5} "
            f"{_fmt(p_err, '#.3g'):>7}/{_fmt(p_noise, '#.3g'):<6} x{_fmt(c.error_to_noise('p_act_m'), '.2f'):<5} "
            f"{_fmt(c.cor_measured, '.5f'):>9} {_fmt(c.cor_model, '.5f'):>9} "
            f"{_fmt(c.cor_model - c.cor_measured, '+.5f'):>8}  {worst} "
            f"x{_fmt(worst_ratio, '.2f')} ({_fmt(ph[worst]['share'], '.0%')} of the error)"
        )
    return "\n".join(lines)


def figure_stem(index: int, run_id: str) -> str:
    """A file-name-safe, unique stem for a run's figures."""
    return f"{index:02d}_" + (re.sub(r"[^A-Za-z0-9._-]+", "_", run_id).strip("._") or "run")


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _contact_window(c: RunComparison, margin_s: float = 0.06) -> tuple[float, float]:
    t = c.run.time_s
    idx = np.flatnonzero((c.labels == 1) | (c.labels == 2))
    a = t[idx[0]] - margin_s
    b = t[min(idx[-1] + c.delay_ticks, len(t) - 1)] + margin_s
    return max(a, t[0]), min(b, t[-1])


def plot_overlay(c: RunComparison, path: Path) -> Path:
    """Measured and model signals: replay (p_act, f_mea), closed loop (v_des, f_comp)."""
    r, rp, cl = c.run, c.replay, c.closed_loop
    t = r.time_s
    fig, ax = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    ax[0].plot(t, r.p_des_m * 1e3, color="0.6", lw=1, label="p_des (recorded command)")
    ax[0].plot(t, r.p_act_m * 1e3, ".", ms=2, label="p_act measured")
    ax[0].plot(t, rp.p_act_m * 1e3, lw=1.2, label="p_act replay")
    ax[0].set_ylabel("position [mm]")
    ax[1].plot(t, r.f_mea_n, ".", ms=2, label="f_mea measured")
    ax[1].plot(t, rp.f_mea_n, lw=1.2, label="f_mea replay")
    ax[1].set_ylabel("force [N]")
    ax[2].plot(t, r.v_des_m_per_s, lw=1.5, label="v_des measured")
    ax[2].plot(t, cl.v_des_m_per_s, "--", lw=1.2, label="v_des closed-loop model")
    ax[2].set_ylabel("velocity [m/s]")
    ax[3].plot(t, r.f_comp_n, lw=1.5, label="f_comp measured")
    ax[3].plot(t, cl.f_comp_n, "--", lw=1.2, label="f_comp closed-loop model")
    ax[3].set_ylabel("force [N]")
    ax[3].set_xlabel("time [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(loc="best", fontsize=7)
    ax[0].set_title(
        f"{c.run_id}: replay (top two) and closed loop (bottom two); "
        f"CoR {c.cor_measured:.4f} measured, {c.cor_model:.4f} model",
        fontsize=9,
    )
    return _save(fig, path)


def plot_residuals(c: RunComparison, path: Path) -> Path:
    """Replay residuals against time coloured by phase, and each phase's share."""
    r, rp = c.run, c.replay
    t = r.time_s
    fig = plt.figure(figsize=(9, 7))
    grid = fig.add_gridspec(2, 3)
    chans = (
        ("f_mea_n", r.f_mea_n - rp.f_mea_n, c.f_labels, 1.0, "f_mea residual [N]"),
        ("p_act_m", r.p_act_m - rp.p_act_m, c.labels, 1e6, "p_act residual [um]"),
    )
    for row, (name, e, labels, scale, ylabel) in enumerate(chans):
        ax = fig.add_subplot(grid[row, :2])
        for i, ph in enumerate(PHASES):
            sel = labels == i
            ax.plot(t[sel], e[sel] * scale, ".", ms=2, color=_PHASE_COLORS[ph], label=ph)
        noise = c.noise_rms[name] * scale
        if math.isfinite(noise):
            for s in (-2, 2):
                ax.axhline(s * noise, color="k", lw=0.8, ls=":")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if row == 0:
            ax.legend(loc="best", fontsize=7, markerscale=4)
            ax.set_title(f"{c.run_id}: replay residuals (dotted: +-2 noise RMS)", fontsize=9)
        else:
            ax.set_xlabel("time [s]")
        bx = fig.add_subplot(grid[row, 2])
        shares = [np.nan_to_num(c.phases[name][ph]["share"]) for ph in PHASES]
        fracs = [c.phases[name][ph]["time_fraction"] for ph in PHASES]
        x = np.arange(len(PHASES))
        bx.bar(x - 0.2, shares, 0.4, color=[_PHASE_COLORS[p] for p in PHASES], label="error share")
        bx.bar(x + 0.2, fracs, 0.4, color="0.75", label="time share")
        bx.set_xticks(x, [p.replace("_", "\n") for p in PHASES], fontsize=7)
        bx.set_ylim(0, 1)
        bx.set_title(f"{name}: share of squared error", fontsize=8)
        bx.legend(fontsize=6)
    return _save(fig, path)


def _corr_panel(ax, corr: Correlation, values: np.ndarray, lags: np.ndarray, title: str) -> None:
    h = corr.sample_period_s * 1e3
    ax.vlines(lags * h, 0, values, lw=1.2)
    ax.plot(lags * h, values, ".", ms=3)
    ax.axhspan(-corr.band, corr.band, color="tab:blue", alpha=0.15, label="99 % band")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_title(title, fontsize=8)
    ax.set_xlabel("lag [ms]")
    ax.grid(True, alpha=0.3)


def plot_correlation(c: RunComparison, path: Path) -> Path:
    """Residual autocorrelation and cross-correlation with the input, with bands."""
    fig, ax = plt.subplots(2, 2, figsize=(9, 6))
    for row, name in enumerate(("f_mea_n", "p_act_m")):
        corr = c.whiteness[name]
        _corr_panel(
            ax[row, 0], corr, corr.auto[1:], corr.lags[1:], f"{name} residual autocorrelation"
        )
        _corr_panel(
            ax[row, 1], corr, corr.cross, corr.lags, f"{name} residual vs input (command increment)"
        )
    ax[0, 0].legend(fontsize=7)
    fig.suptitle(f"{c.run_id}: whiteness of the replay residuals", fontsize=9)
    return _save(fig, path)


def plot_force_deflection(c: RunComparison, path: Path) -> Path:
    """Force against penetration: measured (reading M ticks later) and replay model."""
    r, rp, m = c.run, c.replay, c.delay_ticks
    n = len(r.time_s)
    window = np.flatnonzero((c.labels == 1) | (c.labels == 2))
    a, b = max(window[0] - 3, 0), min(window[-1] + 3, n - 1 - m)
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot(
        r.p_act_m[a : b + 1] * 1e3,
        r.f_mea_n[a + m : b + 1 + m],
        ".-",
        ms=2,
        lw=0.6,
        label=f"measured (loop energy {c.loop_energy_j['measured']:+.3g} J)",
    )
    ax.plot(
        rp.p_act_m[a : b + 1] * 1e3,
        rp.f_act_n[a : b + 1],
        lw=1.4,
        label=f"model (loop energy {c.loop_energy_j['model']:+.3g} J)",
    )
    ax.set_xlabel("penetration p_act [mm]")
    ax.set_ylabel("contact force [N]")
    ax.set_title(f"{c.run_id}: force-deflection loop", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def _md_num(x: float, spec: str) -> str:
    return _fmt(x, spec)


def write_report(comparisons: Sequence[RunComparison], folder: str | Path) -> list[Path]:
    """Write ``report.md`` and the figures into ``folder``; returns the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / REPORT_MARKER).write_text("written by hybridtable compare --report\n")
    written: list[Path] = []
    md = [
        "# Model against measured runs",
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
        md += ["", "Whiteness (99 % band):", ""]
        for ch in ("f_mea_n", "p_act_m"):
            s = c.whiteness[ch].summary()
            md.append(
                f"- {ch}: autocorrelation outside the band at {s['auto_lags_outside']} of "
                f"{s['auto_lags']} lags (max {s['auto_max_abs']:.3f}, band {s['band']:.3f}); "
                f"cross-correlation with the input at {s['cross_lags_outside']} of "
                f"{s['cross_lags']} lags (max {s['cross_max_abs']:.3f} at "
                f"{s['cross_max_lag_s'] * 1e3:.0f} ms)."
            )
        md += [
            f"- force-deflection loop energy: measured {c.loop_energy_j['measured']:+.4g} J, "
            f"model {c.loop_energy_j['model']:+.4g} J (> 0: the contact dissipates).",
            "",
        ]
        if c.notes:
            md += [f"Note: {n}" for n in c.notes] + [""]
        for title, p in figs.items():
            md += [f"![{c.run_id} {title}]({p.name})", ""]
    report = folder / "report.md"
    report.write_text("\n".join(md))
    written.insert(0, report)
    return written


def format_error_fall(nominal, with_effect, label: str) -> str:
    """Per run: replay errors over the noise and closed-loop errors, nominal
    model -> model with the effect."""
    head = (
        f"{'run':<16} {'f_mea rms/noise':>17} {'p_act rms/noise':>17} "
        f"{'v_des rms [mm/s]':>19} {'CoR error':>21}"
    )
    lines = [f"error fall with {label}:", head, "-" * len(head)]
    for a, b in zip(nominal, with_effect, strict=True):
        va = a.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        vb = b.closed_loop_errors["v_des_m_per_s"].rms_error * 1e3
        lines.append(
            f"{a.run_id[:16]:<16} {a.error_to_noise('f_mea_n'):7.3f} -> {b.error_to_noise('f_mea_n'):<6.3f} "
            f"{a.error_to_noise('p_act_m'):7.3f} -> {b.error_to_noise('p_act_m'):<6.3f} "
            f"{va:8.3g} -> {vb:<8.3g} "
            f"{a.cor_model - a.cor_measured:+9.5f} -> {b.cor_model - b.cor_measured:<+9.5f}"
        )
    return "\n".join(lines)
