"""The figures of ``hybridtable compare --report``: per run, the measured and
model signals, the replay residuals by phase, their whiteness, and the
force-deflection loop; every axis with its unit, each figure with its caption
(:data:`FIGURES`) for report.md.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridtable.measurement.comparison import RunComparison  # noqa: E402
from hybridtable.measurement.phases import PHASES  # noqa: E402
from hybridtable.measurement.stats import Correlation  # noqa: E402
from hybridtable.reports.figure_text import literal  # noqa: E402

__all__ = [
    "FIGURES",
    "figure_stem",
    "plot_overlay",
    "plot_residuals",
    "plot_correlation",
    "plot_force_deflection",
]

_PHASE_COLORS = {
    "approach": "tab:blue",
    "compression": "tab:red",
    "restitution": "tab:orange",
    "free_flight": "tab:green",
}

#: Each figure's short title and its caption (units in brackets) in report.md.
FIGURES = {
    "overlay": (
        "Measured and model signals",
        "Top two: table position p_act [mm] and force reading f_mea [N], measured (dots) and "
        "replayed from the recorded command p_des (grey); bottom two: command velocity v_des "
        "[m/s] and compensated force f_comp [N], measured and re-run in closed loop; against "
        "time [s].",
    ),
    "residuals": (
        "Replay residuals by phase",
        "Left: measured minus replayed f_mea [N] and p_act [um] against time [s], coloured by "
        "contact phase, dotted at +-2 noise RMS; right: each phase's share of the squared "
        "error beside its share of the time [1] (an error share well above the time share "
        "points at the phase where the model is wrong).",
    ),
    "correlation": (
        "Whiteness of the residuals",
        "Normalized autocorrelation of the replay residuals (left) and their cross-correlation "
        "with the command increment (right) [1] against lag [ms]; the shaded band holds 99 % "
        "of the lags of a white residual.",
    ),
    "force_deflection": (
        "Force-deflection loop",
        "Contact force [N] against penetration p_act [mm] over the contact: measured (reading "
        "taken the sensor delay later) and replay model; the area the loop encloses is the "
        "energy the contact absorbs [J].",
    ),
}


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
        f"{literal(c.run_id)}\nreplay (top two) and closed loop (bottom two); "
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
            ax.plot(
                t[sel],
                e[sel] * scale,
                ".",
                ms=2,
                color=_PHASE_COLORS[ph],
                label=ph.replace("_", " "),
            )
        noise = c.noise_rms[name] * scale
        if math.isfinite(noise):
            for s in (-2, 2):
                ax.axhline(s * noise, color="k", lw=0.8, ls=":")
        ax.set_ylabel(ylabel)
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
        if row == 0:
            ax.legend(loc="best", fontsize=7, markerscale=4)
            ax.set_title(
                f"{literal(c.run_id)}: replay residuals (dotted: +-2 noise RMS)", fontsize=9
            )
        # Horizontal bars: the phase names read along the y axis, never overlapping.
        bx = fig.add_subplot(grid[row, 2])
        shares = [np.nan_to_num(c.phases[name][ph]["share"]) for ph in PHASES]
        fracs = [c.phases[name][ph]["time_fraction"] for ph in PHASES]
        y = np.arange(len(PHASES))
        bx.barh(y - 0.2, shares, 0.4, color=[_PHASE_COLORS[p] for p in PHASES], label="error")
        bx.barh(y + 0.2, fracs, 0.4, color="0.75", label="time")
        bx.set_yticks(y, [p.replace("_", " ") for p in PHASES], fontsize=8)
        bx.invert_yaxis()
        bx.set_xlim(0, 1)
        bx.set_xlabel("share [1]")
        bx.set_title(f"{name}: share of squared error and of time", fontsize=8)
        bx.grid(True, axis="x", alpha=0.3)
        bx.legend(fontsize=6, loc="upper right")
    return _save(fig, path)


def _corr_panel(ax, corr: Correlation, values: np.ndarray, lags: np.ndarray, title: str) -> None:
    h = corr.sample_period_s * 1e3
    ax.vlines(lags * h, 0, values, lw=1.2)
    ax.plot(lags * h, values, ".", ms=3)
    ax.axhspan(-corr.band, corr.band, color="tab:blue", alpha=0.15, label="99 % band")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_title(title, fontsize=8)
    ax.set_xlabel("lag [ms]")
    ax.set_ylabel("correlation [1]")
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
    fig.suptitle(f"{literal(c.run_id)}: whiteness of the replay residuals", fontsize=9)
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
    ax.set_title(f"{literal(c.run_id)}: force-deflection loop", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)
