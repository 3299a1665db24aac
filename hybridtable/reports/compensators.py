"""Summary, figures and Markdown report of a compensator sweep
(:mod:`hybridtable.studies.compensator_sweep`), and of the compensators on a
modelled rig (:mod:`hybridtable.studies.model_compensators`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hybridtable.errors import ParameterError
from hybridtable.studies.compensator_sweep import (
    ONLINE_COR_TOLERANCE,
    SCENARIOS,
    STIFFNESS_FREE,
    SweepCase,
    SweepResult,
    acceptance,
    case_params,
    summarize,
)

__all__ = [
    "format_summary",
    "write_report",
    "model_verdict",
    "format_model_summary",
    "write_model_report",
]


def format_summary(result: SweepResult) -> str:
    """The summary as a text table, and the acceptance lines."""
    summ = summarize(result)
    scen = [s for s in SCENARIOS if s in result.settings.scenarios]
    head = f"{'compensator':<26}" + "".join(f"{s + ' |dCoR|':>17}" for s in scen)
    head += f"{'max CoR':>10}{'|dF_peak|':>11}{'|dE|':>9}{'E created':>11}{'failed':>8}"
    lines = [
        f"{len(result.points)} grid points, {len(result.runs)} runs "
        f"({result.wall_time_s:.0f} s); errors against an ideal loop with the same contact",
        head,
    ]
    for key, by in summ.items():
        row = f"{key:<26}"
        for s in scen:
            row += f"{by[s]['max_abs_cor_error']:>17.4f}" if s in by else f"{'-':>17}"
        vals = list(by.values())
        row += f"{max(v['max_cor'] for v in vals):>10.4f}"
        row += f"{max(v['max_abs_peak_force_error'] for v in vals):>11.4f}"
        row += f"{max(v['max_abs_energy_drift'] for v in vals):>9.4f}"
        row += f"{max(v['max_energy_created'] for v in vals):>11.4f}"
        row += f"{sum(v['failed'] for v in vals):>8d}"
        lines.append(row)
    acc = acceptance(result)
    lines.append("")
    half = acc["fixed_k_sdmdc_at_half_k"]
    if half:
        worst = max(half, key=lambda r: abs(r["cor_error"]))
        lines.append(
            f"fixed-k SDMDC, prior k 50% low: CoR error up to {worst['cor_error']:+.4f} "
            f"(point {worst['point']})"
        )
    o = acc["sdmdc_online"]
    lines.append(
        f"sdmdc-online, every prior ratio: |CoR error| <= {o['max_abs_cor_error']:.4f} "
        f"over {o['runs']} runs (acceptance {o['tolerance']}): "
        f"{'PASS' if o['passed'] else 'FAIL'}"
    )
    p = acc["passivity"]
    if p["runs"]:
        lines.append(
            f"passivity guard: largest CoR {p['max_cor']:.5f} over {p['runs']} runs "
            f"(acceptance <= {p['limit']}): {'PASS' if p['passed'] else 'FAIL'}"
        )
    return "\n".join(lines)


def _label(point: dict[str, float]) -> str:
    return (
        f"{point['sensor_delay_ms']:g}ms/{point['table_response_hz']:g}Hz/"
        f"{point['contact_frequency_hz']:g}Hz/{point['contact_stiffness_n_per_mm']:g}N/mm/"
        f"{point['initial_velocity_mm_per_s']:g}mm/s"
    )


def write_report(result: SweepResult, out_dir: str | Path, traces: bool = True) -> list[str]:
    """Figures and a Markdown report of a sweep in ``out_dir``; returns paths.

    ``traces``: also run the first grid point with the believed stiffness 50 %
    low and plot the velocity, the compensated force and the online estimate
    of fixed-k SDMDC, ``sdmdc-online`` and ``smith-online`` against the ideal
    loop. Refuses (ParameterError) to overwrite an existing ``report.md``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    report = out / "report.md"
    if report.exists():
        raise ParameterError(f"{report} exists; choose another --report directory")
    out.mkdir(parents=True, exist_ok=True)
    paths: list[str] = []
    runs = result.runs
    comps = list(result.settings.compensators)

    # 1. CoR against the believed stiffness, worst over the grid.
    fig, ax = plt.subplots(figsize=(8, 5))
    colors = plt.get_cmap("tab10")
    for ci, comp in enumerate(comps):
        for guard, style in ((False, "-o"), (True, "--x")):
            rs = [
                r
                for r in runs
                if r["compensator"] == comp
                and r["passivity"] == guard
                and r["scenario"] == "mismatch"
            ]
            if not rs:
                continue
            ratios = sorted({r["prior_ratio"] for r in rs})
            worst = [
                max((r["cor_error"] for r in rs if r["prior_ratio"] == q), key=abs) for q in ratios
            ]
            if len(ratios) == 1:
                ratios = list(result.settings.prior_ratios)
                worst = worst * len(ratios)
            label = comp + (" +passivity" if guard else "")
            ax.plot(ratios, worst, style, label=label, ms=4, color=colors(ci % 10))
    ax.axhspan(-ONLINE_COR_TOLERANCE, ONLINE_COR_TOLERANCE, color="0.9")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=ONLINE_COR_TOLERANCE)
    ax.set_xlabel("believed / true contact stiffness")
    ax.set_ylabel("worst CoR error over the grid (symlog)")
    ax.set_title("Stiffness mismatch (undamped contact); dashed: with the passivity guard")
    ax.legend(fontsize=6, ncol=2, loc="best")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    p = out / "cor_error_vs_prior_stiffness.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(str(p))

    # 2. Worst |CoR error| per compensator and scenario.
    summ = summarize(result)
    keys = list(summ)
    scen = [s for s in SCENARIOS if s in result.settings.scenarios]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    width = 0.8 / max(len(scen), 1)
    x = np.arange(len(keys))
    for j, s in enumerate(scen):
        vals = [summ[k].get(s, {}).get("max_abs_cor_error", math.nan) for k in keys]
        vals = [v if math.isfinite(v) else 1.0 for v in vals]
        ax.bar(x + j * width, vals, width, label=s)
    ax.axhline(ONLINE_COR_TOLERANCE, color="k", lw=0.8, ls=":")
    ax.set_yscale("log")
    ax.set_ylim(bottom=1e-5)
    ax.set_xticks(x + width * (len(scen) - 1) / 2, keys, rotation=45, ha="right", fontsize=7)
    ax.set_ylabel("worst |CoR error|")
    ax.set_title("Worst CoR error over the grid, per scenario")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    p = out / "cor_error_by_scenario.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(str(p))

    # 3. CoR error per grid point at the smallest prior ratio.
    lowest = min(result.settings.prior_ratios)
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for comp in comps:
        rs = {
            r["point"]: r["cor_error"]
            for r in runs
            if r["compensator"] == comp
            and not r["passivity"]
            and r["scenario"] == "mismatch"
            and r["prior_ratio"] == (1.0 if comp in STIFFNESS_FREE else lowest)
        }
        if rs:
            pts = sorted(rs)
            ax.plot(pts, [rs[i] for i in pts], "-o", ms=4, label=comp)
    ax.axhspan(-ONLINE_COR_TOLERANCE, ONLINE_COR_TOLERANCE, color="0.9")
    ax.set_xticks(
        range(len(result.points)),
        [_label(q) for q in result.points],
        rotation=60,
        ha="right",
        fontsize=6,
    )
    ax.set_ylabel("CoR error")
    ax.set_title(f"Grid points, believed stiffness x{lowest:g} (k-free compensators: x1)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    p = out / "cor_error_grid.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(str(p))

    if traces:
        paths.append(str(_plot_half_stiffness(result, out / "table1_prior_k_half.png")))

    lines = ["# Compensators over the Table 2 grid", "", "```", format_summary(result), "```", ""]
    lines += ["Grid points (index: delay / table / contact f / k / v0):", ""]
    lines += [f"- {i}: {_label(q)}" for i, q in enumerate(result.points)]
    lines += [""] + [f"![{Path(q).stem}]({Path(q).name})" for q in paths]
    report.write_text("\n".join(lines) + "\n")
    paths.append(str(report))
    result.figures = paths
    return paths


def _simulate_logged(params, t_end: float):
    """Run a loop to ``t_end`` with run_loop's integrator settings; return the
    loop's log and, for a compensator with a ``contact_parameters`` output,
    the log of the estimate."""
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import LogVectorOutput

    from hybridtable.loop.builder import add_hybrid_loop

    builder = DiagramBuilder()
    loop = add_hybrid_loop(builder, params)
    sink = None
    if loop.compensator.HasOutputPort("contact_parameters"):
        sink = LogVectorOutput(loop.compensator.GetOutputPort("contact_parameters"), builder)
    loop.diagram = builder.Build()
    simulator = Simulator(loop.diagram)
    ctx = simulator.get_mutable_context()
    loop.set_initial_conditions(ctx)
    ResetIntegratorFromFlags(simulator, "runge_kutta3", loop.computer_period_s)
    simulator.get_mutable_integrator().set_target_accuracy(1e-8)
    simulator.AdvanceTo(t_end)
    log = loop.logger.FindLog(ctx)
    est = sink.FindLog(ctx) if sink is not None else None
    return (log.sample_times(), log.data()), (
        None if est is None else (est.sample_times(), est.data())
    )


def _plot_half_stiffness(result: SweepResult, path: Path) -> Path:
    import matplotlib.pyplot as plt

    from hybridtable.compensators.registry import compensator_names
    from hybridtable.loop.builder import LOG_ROWS
    from hybridtable.loop.simulation import simulate

    row = tuple(sorted(result.points[0].items()))
    settings = result.settings
    ideal, _ = case_params(SweepCase(0, row, "mismatch", "ideal", 1.0, False), settings)
    t_end = simulate(ideal).time_s[-1] + 0.1
    runs = [("ideal loop", ideal)]
    for name in ("SDMDC", "sdmdc-online", "smith-online"):
        if name in compensator_names():
            params, _ = case_params(SweepCase(0, row, "mismatch", name, 0.5, False), settings)
            runs.append((f"{name}, k believed 50 % low", params))
    v_row, f_row = LOG_ROWS.index("v_des_m_per_s"), LOG_ROWS.index("f_comp_n")
    k_true = ideal.contact_stiffness_n_per_m
    fig, axes = plt.subplots(3, 1, figsize=(7, 8.5), sharex=True)
    for label, params in runs:
        (t, data), est = _simulate_logged(params, t_end)
        v = data[v_row]
        cor = abs(v[-1]) / abs(v[0])
        axes[0].plot(t, v, label=f"{label}: CoR {cor:.4f}")
        axes[1].plot(t, data[f_row], label=label)
        if est is not None:
            axes[2].plot(est[0], est[1][0] / k_true, label=f"{label}: k estimate / true k")
    axes[0].set_ylabel("spacecraft velocity [m/s]")
    axes[1].set_ylabel("compensated force [N]")
    axes[2].set_ylabel("k estimate / true k")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title(f"Grid point 0 ({_label(result.points[0])})")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# -- compensators --model ------------------------------------------------------
def _cor(x: float) -> str:
    return f"{x:.3f}" if math.isfinite(x) else "failed"


def model_verdict(result) -> str:
    """One line: the compensator that comes closest to the model's contact
    and what no compensation gives."""
    ranking = result.ranking()
    if not ranking or not math.isfinite(ranking[0]["max_abs_cor_error"]):
        return "On the modelled rig no compensator ran through a contact (every run failed)"
    best = ranking[0]
    line = (
        f"On the modelled rig {best['key']} comes closest: CoR {best['cor']:.3f} against "
        f"the contact's {best['cor_reference']:.3f} ({best['cor_error']:+.3f})"
    )
    if len(result.points) > 1:
        line += f" at {best['initial_velocity_m_per_s']:g} m/s, its worst approach"
    none = next((e for e in ranking if e["key"] == "none"), None)
    if none is not None and none is not best:
        line += f"; none gives {_cor(none['cor'])}"
    return line


def format_model_summary(result, rig: str = "") -> str:
    """The verdict, then every compensator ranked by its CoR error against
    the ideal rig with the model's contact; ``rig`` describes the rig (a line)."""
    lines = [model_verdict(result), f"model: {result.description}"]
    if rig:
        lines.append(f"rig (nominal): {rig}")
    refs = ", ".join(
        f"{q['initial_velocity_m_per_s']:g} m/s: CoR {_cor(q['cor_reference'])}"
        for q in result.points
    )
    lines.append(
        "reference: an ideal rig (continuous, no delay, ideal table, no compensation) with "
        f"the model's contact only ({refs})"
    )
    worst = " (worst approach)" if len(result.points) > 1 else ""
    lines.append(
        f"{len(result.runs)} runs, {result.wall_time_s:.1f} s; ranked by |CoR error|{worst}"
    )
    lines.append(
        f"{'rank':>4}  {'compensator':<26}{'CoR':>8}{'reference':>11}{'CoR error':>11}"
        f"{'|dF_peak|':>11}{'E created':>11}{'failed':>8}"
    )
    for e in result.ranking():
        ok = math.isfinite(e["cor"])
        lines.append(
            f"{e['rank']:>4}  {e['key']:<26}"
            + (f"{e['cor']:>8.4f}" if ok else f"{'failed':>8}")
            + f"{e['cor_reference']:>11.4f}"
            + (f"{e['cor_error']:>+11.4f}" if ok else f"{'-':>11}")
            + f"{e['max_abs_peak_force_error']:>11.4f}{e['max_energy_created']:>11.4f}"
            + f"{e['failed']:>8d}"
        )
    return "\n".join(lines)


def write_model_report(result, out_dir: str | Path, rig: str = "") -> list[str]:
    """``model_cor.png`` (CoR per compensator and guard against the
    reference) and ``report.md`` in ``out_dir``; returns the paths. Refuses
    (ParameterError) to overwrite an existing ``report.md``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    report = out / "report.md"
    if report.exists():
        raise ParameterError(f"{report} exists; choose another --report directory")
    out.mkdir(parents=True, exist_ok=True)
    ranking = result.ranking()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    x = np.arange(len(ranking))
    cors = [e["cor"] if math.isfinite(e["cor"]) else np.nan for e in ranking]
    ax.bar(x, cors, color=["C1" if e["passivity"] else "C0" for e in ranking])
    for q in result.points:
        ax.axhline(q["cor_reference"], color="k", lw=0.8, ls="--")
    ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    finite = [c for c in cors if np.isfinite(c)] + [q["cor_reference"] for q in result.points]
    if finite:
        ax.set_ylim(min(finite) - 0.05, max(finite) + 0.05)
    ax.set_xticks(x, [e["key"] for e in ranking], rotation=45, ha="right", fontsize=7)
    ax.set_ylabel("CoR on the modelled rig")
    ax.set_title("Compensators on the modelled rig (dashed: the model's contact, ideal rig)")
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    figure = out / "model_cor.png"
    fig.savefig(figure, dpi=120)
    plt.close(fig)
    text = ["# Compensators on the modelled rig", "", "```", format_model_summary(result, rig)]
    text += ["```", "", f"![model_cor]({figure.name})", ""]
    report.write_text("\n".join(text))
    result.figures = [str(figure), str(report)]
    return list(result.figures)
