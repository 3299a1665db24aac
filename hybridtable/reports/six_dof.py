"""What ``simulate6`` says and draws: the verdict, the metrics' lines, the wrench plot."""

from __future__ import annotations

import math
from pathlib import Path

from hybridtable.six_dof.metrics import ENERGY_MATCH_TOLERANCE

__all__ = ["docking_verdict", "format_docking", "plot_wrench"]


def docking_verdict(compensator: str, metrics, reference) -> str:
    """One plain sentence: the energy the contact returned against the
    ideal rig's (no delay, ideal table) and the CoR along the normal."""
    er, er0 = metrics.energy_ratio, reference.energy_ratio
    excess = er - er0
    if abs(excess) <= ENERGY_MATCH_TOLERANCE:
        judgement = "matches the ideal rig"
    elif excess > 0:
        judgement = f"creates {100 * excess:.1f} % more energy than the ideal rig"
    else:
        judgement = f"removes {100 * -excess:.1f} % more energy than the ideal rig"
    pushed = metrics.peak_compensated_force_n / metrics.peak_force_n
    but = (
        f"; but the compensator fed the model forces up to {metrics.peak_compensated_force_n:.0f} N, "
        f"{pushed:.1f} times the contact's peak"
        if pushed > _PUSHED
        else ""
    )
    return (
        f"{compensator}: the docking contact {judgement} (energy ratio {er:.4f} against "
        f"{er0:.4f}); CoR along the normal {metrics.cor_normal:.4f} "
        f"(ideal rig {reference.cor_normal:.4f}){but}."
    )


#: A compensated force above this many times the contact's peak is said in the
#: verdict: the compensator, not the contact, pushes the model.
_PUSHED = 1.5


def format_docking(compensator: str, metrics, reference, modes, wall_time_s: float, sim_s: float):
    """The lines after the verdict."""
    m = metrics
    lines = [
        f"{compensator}: CoR normal {m.cor_normal:.5f}  energy ratio {m.energy_ratio:.5f}  "
        f"peak force {m.peak_force_n:.1f} N  peak moment {m.peak_moment_n_m:.1f} N m  "
        f"contact {m.contact_duration_s:.3f} s",
        f"after the contact: {'captured' if m.captured else 'not captured'}"
        + (
            f" (the ideal rig: {'captured' if reference.captured else 'not captured'})"
            if reference is not None and reference.captured != m.captured
            else ""
        )
        + f", rotation {m.rotational_energy_j:.4g} J, the port's lateral velocity "
        f"{1000 * m.lateral_velocity_m_per_s:.3f} mm/s",
    ]
    if modes is not None:
        crit = (
            "none up to 50 ms"
            if math.isinf(modes.critical_delay_s)
            else f"{1000 * modes.critical_delay_s:.3g} ms"
        )
        reported = list(zip(modes.frequencies_hz, modes.growth_rates_per_s, strict=True))
        slow = ", ".join(f"{f:.3f} Hz ({g:+.4f}/s)" for f, g in reported[:3])
        if modes.stable:
            state = "stable"
        else:  # name the mode that grows: it need not be among the slowest
            f, g = max(reported, key=lambda mode: mode[1])
            state = f"a mode grows: {f:.3f} Hz at {g:+.4f}/s, the fastest-growing"
        lines.append(
            f"linearized in contact: {state}; slowest modes {slow}; growth starts at a "
            f"sensor delay of {crit}"
        )
    rtf = sim_s / wall_time_s if wall_time_s > 0 else math.inf
    lines.append(f"{sim_s:.2f} s simulated in {wall_time_s:.2f} s ({rtf:.2f} x real time)")
    return "\n".join(lines)


def plot_wrench(run, path: str | Path) -> Path:
    """The six components of the actual and compensated wrench over time."""
    import matplotlib.pyplot as plt

    from hybridtable.reports.figures import save_figure

    t = run.time_s
    w = run.log["contact_wrench"]
    wc = run.log["compensated_wrench"]
    fig, axes = plt.subplots(3, 2, figsize=(10, 7.5), sharex=True)
    labels = ("x", "y", "z")
    for i in range(3):
        ax = axes[i, 0]
        ax.plot(t, w[:, 3 + i], label="contact")
        ax.plot(t, wc[:, 3 + i], "--", label="fed to the model")
        ax.set_ylabel(f"force {labels[i]} [N]")
        ax = axes[i, 1]
        ax.plot(t, w[:, i], label="contact")
        ax.plot(t, wc[:, i], "--", label="fed to the model")
        ax.set_ylabel(f"moment {labels[i]} [N m]")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    axes[0, 0].legend(loc="best", fontsize=8)
    p = run.params
    fig.suptitle(
        f"{p.compensator}: wrench on the spacecraft at the port (target frame), "
        f"delay {1000 * p.sensor_delay_s:g} ms"
    )
    return save_figure(fig, path)
