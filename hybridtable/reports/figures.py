"""Matplotlib figures of hybrid-loop runs (Agg backend, PNG files)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hybridtable._files import atomic_path  # noqa: E402
from hybridtable.loop.simulation import SimulationResult  # noqa: E402

__all__ = ["plot_run", "plot_velocities", "plot_forces", "save_figure"]


#: Line styles of overlaid runs, so that coinciding curves stay visible.
_STYLES = ("-", "--", "-.", ":")


def _contact_window(results: Sequence[SimulationResult], margin_s: float = 0.1):
    starts, ends = [], []
    for r in results:
        on = r.f_act_n > 0
        if on.any():
            starts.append(r.time_s[on.argmax()])
            ends.append(r.time_s[len(on) - 1 - on[::-1].argmax()])
    if not starts:
        return None
    return min(starts) - margin_s, max(ends) + margin_s


def save_figure(fig, path: str | Path) -> Path:
    """Lay out ``fig``, save it to ``path`` atomically (creating the folder) and close it."""
    fig.tight_layout()
    path = Path(path)
    try:
        with atomic_path(path) as tmp:  # an interrupted save leaves no half figure
            fig.savefig(tmp, dpi=120, format=path.suffix.lstrip(".").lower() or None)
    finally:
        plt.close(fig)
    return path


def _overlay(
    results: Sequence[SimulationResult],
    series: Sequence[tuple[str, object]],
    path: str | Path,
    title: str,
    ylabel: str,
    margin_s: float,
) -> Path:
    """Curves ``(label, (t, y))`` of several runs on one axis, zoomed on the contact."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for i, (label, (t, y)) in enumerate(series):
        ax.plot(t, y, ls=_STYLES[i % len(_STYLES)], lw=1.6, label=label)
    window = _contact_window(results, margin_s)
    if window:
        ax.set_xlim(*window)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    ax.grid(True, alpha=0.3)
    return save_figure(fig, path)


def plot_velocities(
    results: Sequence[SimulationResult], labels: Sequence[str], path: str | Path, title: str
) -> Path:
    """Spacecraft velocity of several runs, overlaid (the paper's Figs. 3-6)."""
    series = [
        (f"{label} (CoR {r.metrics.cor:.4f})", (r.time_s, r.v_des_m_per_s))
        for r, label in zip(results, labels, strict=True)
    ]
    return _overlay(results, series, path, title, "spacecraft velocity v_des [m/s]", 0.1)


def plot_forces(
    results: Sequence[SimulationResult], labels: Sequence[str], path: str | Path, title: str
) -> Path:
    """Compensated force of several runs with the actual force of the first
    (the paper's Fig. 7), and below it each run's compensated minus actual force.

    The actual force is drawn wide and grey beneath the compensated forces
    (one line style each), so that a compensated force on top of it (SDC's)
    stays visible; the lower panel shows what each compensator adds.
    """
    fig, (ax, dax) = plt.subplots(
        2, 1, figsize=(7, 6), sharex=True, gridspec_kw=dict(height_ratios=(2, 1))
    )
    if results:
        first = f"actual force f_act ({labels[0]} run)"
        ax.plot(results[0].time_s, results[0].f_act_n, color="0.55", lw=5, alpha=0.5, label=first)
    for i, (r, label) in enumerate(zip(results, labels, strict=True)):
        style = dict(color=f"C{i}", ls=_STYLES[i % len(_STYLES)], lw=1.6, zorder=3)
        ax.plot(r.time_s, r.f_comp_n, label=f"{label}: f_comp", **style)
        dax.plot(r.time_s, r.f_comp_n - r.f_act_n, label=f"{label}: f_comp - f_act", **style)
    window = _contact_window(results, 0.05)
    for a in (ax, dax):
        if window:
            a.set_xlim(*window)
        a.axhline(0.0, color="0.6", lw=0.8)
        a.grid(True, alpha=0.3)
        a.legend(loc="best", fontsize=8)
    ax.set_ylabel("force [N]")
    dax.set_ylabel("f_comp - f_act [N]")
    dax.set_xlabel("time [s]")
    ax.set_title(title)
    return save_figure(fig, path)


def plot_run(result: SimulationResult, path: str | Path) -> Path:
    """One run: positions, velocity, and forces against time."""
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    t = result.time_s
    axes[0].plot(t, result.p_des_m * 1e3, label="p_des (command)")
    axes[0].plot(t, result.p_act_m * 1e3, label="p_act (table)")
    axes[0].set_ylabel("position [mm]")
    axes[1].plot(t, result.v_des_m_per_s, label="v_des (spacecraft)")
    axes[1].plot(t, result.v_act_m_per_s, label="v_act (table)", alpha=0.7)
    axes[1].set_ylabel("velocity [m/s]")
    axes[2].plot(t, result.f_act_n, label="f_act")
    axes[2].plot(t, result.f_mea_n, label="f_mea")
    axes[2].plot(t, result.f_comp_n, label="f_comp")
    axes[2].set_ylabel("force [N]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    p = result.params
    m = result.metrics
    axes[0].set_title(
        f"{p.compensator}, T_fms {p.sensor_delay_s * 1e3:g} ms, table {p.table_response_hz:g} Hz: "
        f"CoR {m.cor:.4f}"
    )
    return save_figure(fig, path)
