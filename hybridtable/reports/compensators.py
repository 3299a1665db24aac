"""Summary, figures and Markdown report of a compensator sweep
(:mod:`hybridtable.studies.compensator_sweep`), and of the compensators on a
modelled rig (:mod:`hybridtable.studies.model_compensators`).

Why one module: the grid sweep's report and the modelled rig's share one
colour per compensator (:func:`compensator_colours`), the summary's wording
and the figure style; apart, each would import the other's helpers.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hybridtable.reports.figure_text import literal
from hybridtable.studies.compensator_sweep import (
    ONLINE_COR_TOLERANCE,
    SCENARIOS,
    STIFFNESS_FREE,
    SweepResult,
    case_inputs,
    checks,
    reference_inputs,
    summarize,
)

__all__ = [
    "sweep_verdict",
    "format_checks",
    "format_summary",
    "write_report",
    "compensator_colours",
    "model_verdict",
    "format_model_summary",
    "write_model_report",
]


def _worst(by: dict[str, dict], metric: str) -> float:
    """The largest ``metric`` over the scenarios of one compensator (inf: a run failed)."""
    values = [v[metric] for v in by.values()]
    return max(values) if values else math.nan


def _where(result: SweepResult) -> str:
    n = len(result.points)
    return "at the Table 1 point" if n == 1 else f"over the {n} grid points"


def _scenario_words(result: SweepResult) -> str:
    """What the scenarios vary, in words (the believed stiffness, noise, damping)."""
    st = result.settings
    words = []
    for s in st.scenarios:
        if s == "mismatch":
            lo, hi = min(st.prior_ratios), max(st.prior_ratios)
            words.append(f"a believed stiffness {lo:g}-{hi:g}x the true one")
        elif s == "noise":
            words.append("sensor noise")
        elif s == "damped":
            words.append(f"a damped contact (damping ratio {st.contact_damping_ratio:g})")
    return ", ".join(words[:-1]) + (" and " if len(words) > 1 else "") + words[-1]


def _point_words(result: SweepResult, index: int | None) -> str:
    """A grid point in words (its delay, table, contact, stiffness, approach)."""
    if index is None or not 0 <= int(index) < len(result.points):
        return "a grid point"
    d = result.points[int(index)]
    try:
        return (
            f"{d['sensor_delay_ms']:g} ms delay, {d['table_response_hz']:g} Hz table, "
            f"{d['contact_frequency_hz']:g} Hz contact, k "
            f"{d['contact_stiffness_n_per_mm']:g} N/mm, v0 {d['initial_velocity_mm_per_s']:g} mm/s"
        )
    except KeyError:  # a point given without its parameters
        return f"point {int(index) + 1} of the grid"


def sweep_verdict(result: SweepResult) -> str:
    """One sentence: the compensator (or guarded variant) whose worst |CoR
    error| over every scenario is smallest, beside SDMDC and no compensation."""
    summ = summarize(result)
    worst = {key: _worst(by, "max_abs_cor_error") for key, by in summ.items()}
    ranked = sorted((k for k in worst if math.isfinite(worst[k])), key=lambda k: worst[k])
    if not ranked:
        return f"Every compensator failed {_where(result)} (no run ended with a separation)"
    best = ranked[0]
    line = (
        f"Closest to the ideal loop {_where(result)} under {_scenario_words(result)}: "
        f"{best} (worst |CoR error| {worst[best]:.3f})"
    )
    others = []
    for key, name in (("SDMDC", "SDMDC"), ("none", "no compensation")):
        if key in worst and key != best:
            text = f"{worst[key]:.3f}" if math.isfinite(worst[key]) else "failed runs"
            if key == "none" and math.isfinite(worst[key]):
                energy = _worst(summ[key], "max_abs_energy_drift")
                text += f" (kinetic energy {energy:+.0%})"
            others.append(f"{name} {'leaves ' if not others else ''}{text}")
    if others:
        line += "; " + ", ".join(others)
    return line


def _n_runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def format_checks(result: SweepResult) -> list[str]:
    """What the sweep shows of the online identification, the passivity guard
    and fixed-k SDMDC with a wrong stiffness, as plain sentences."""
    found = checks(result)
    lines = []
    o = found["sdmdc_online"]
    if o["runs"]:
        if o["passed"]:
            lines.append(
                f"sdmdc-online keeps |CoR error| <= {o['max_abs_cor_error']:.4f} for every "
                f"believed stiffness ({_n_runs(o['runs'])}; it should stay within "
                f"{o['tolerance']:g})"
            )
        else:
            lines.append(
                f"sdmdc-online misses the ideal CoR by up to {o['max_abs_cor_error']:.4f} at "
                f"some believed stiffness ({_n_runs(o['runs'])}), more than {o['tolerance']:g}"
            )
    p = found["passivity"]
    if p["runs"]:
        if p["passed"]:
            every = "the guarded run" if p["runs"] == 1 else f"all {p['runs']} guarded runs"
            bound = math.ceil(round(p["max_cor"] * 1e3, 6)) / 1e3
            lines.append(f"the passivity guard holds CoR <= {bound:.3f} in {every}")
        else:
            w = p["worst_case"] or {}
            largest = "a failed run" if p["max_cor"] is None else f"CoR {p['max_cor']:.4f}"
            lines.append(
                f"the passivity guard does not hold CoR <= {p['limit']:g} in every guarded run: "
                f"{largest} ({w.get('compensator')}, {w.get('scenario')} scenario, "
                f"{_point_words(result, w.get('point'))})"
            )
    half = found["fixed_k_sdmdc_at_half_k"]
    if half:
        worst = max(half, key=lambda r: abs(r["cor_error"]))
        lines.append(
            f"fixed-k SDMDC with the stiffness believed 50 % low misses the ideal CoR by up to "
            f"{worst['cor_error']:+.4f} (at {_point_words(result, worst['point'])})"
        )
    return lines


def format_summary(result: SweepResult) -> str:
    """The verdict, the summary as a text table, and what the checks show."""
    summ = summarize(result)
    scen = [s for s in SCENARIOS if s in result.settings.scenarios]
    head = f"{'compensator':<26}" + "".join(f"{s + ' |dCoR|':>17}" for s in scen)
    head += f"{'max CoR':>10}{'|dF_peak|':>11}{'|dE|':>9}{'E created':>11}{'failed':>8}"
    n = len(result.points)
    lines = [
        sweep_verdict(result),
        f"{n} grid point{'s' if n != 1 else ''}, {len(result.runs)} runs "
        f"({result.wall_time_s:.0f} s); errors [1] against an ideal loop with the same contact "
        "(no delay, ideal table, no compensation), worst over the grid",
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
    lines.append("")
    lines += format_checks(result)
    return "\n".join(lines)


def _label(point: dict[str, float]) -> str:
    return (
        f"{point['sensor_delay_ms']:g}ms/{point['table_response_hz']:g}Hz/"
        f"{point['contact_frequency_hz']:g}Hz/{point['contact_stiffness_n_per_mm']:g}N/mm/"
        f"{point['initial_velocity_mm_per_s']:g}mm/s"
    )


def compensator_colours(names=None) -> dict[str, tuple]:
    """One colour per compensator, by the order of ``names`` (default: every
    registered compensator, so that a compensator keeps its colour from one
    figure and one run to the next); its ``+passivity`` variant takes the same
    colour. tab10 without its grey (kept for references) up to nine names,
    tab20 beyond (repeating only past twenty)."""
    import matplotlib

    if names is None:
        from hybridtable.compensators.registry import compensator_names

        names = compensator_names()
    names = list(dict.fromkeys(names))
    if len(names) <= 9:
        palette = [c for i, c in enumerate(matplotlib.colormaps["tab10"].colors) if i != 7]
    else:
        palette = list(matplotlib.colormaps["tab20"].colors)
    return {name: palette[i % len(palette)] for i, name in enumerate(names)}


def _colours(names) -> dict[str, tuple]:
    """:func:`compensator_colours` of the registry, and of ``names`` it lacks after it."""
    from hybridtable.compensators.registry import compensator_names

    return compensator_colours([*compensator_names(), *names])


#: Markers by compensator (cycled), so that coinciding curves stay apart.
_MARKERS = "osD^vP*Xph<>"


def _save_figure(fig, path: Path) -> str:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)


def write_report(result: SweepResult, out_dir: str | Path, traces: bool = True) -> list[str]:
    """Figures and a Markdown report of a sweep in ``out_dir``; returns paths.

    ``traces``: also run the first grid point with the believed stiffness 50 %
    low and plot the velocity, the compensated force and the online estimate
    of fixed-k SDMDC, ``sdmdc-online`` and ``smith-online`` against the ideal
    loop (the command checked the overwrite policy).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    report = out / "report.md"
    out.mkdir(parents=True, exist_ok=True)
    figures: list[tuple[str, str, str]] = []  # (path, title, caption)
    runs = result.runs
    comps = list(result.settings.compensators)
    colour = _colours(comps)
    markers = {c: _MARKERS[i % len(_MARKERS)] for i, c in enumerate(colour)}
    tol = ONLINE_COR_TOLERANCE

    # 1. CoR against the believed stiffness, worst over the grid.
    fig, ax = plt.subplots(figsize=(8, 5.5))
    for comp in comps:
        for guard in (False, True):
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
            ax.plot(
                ratios,
                worst,
                ls="--" if guard else "-",
                marker=markers[comp],
                ms=5 if guard else 4,
                mfc="none" if guard else colour[comp],
                color=colour[comp],
                lw=1.2,
                label=comp + (" +passivity" if guard else ""),
            )
    ax.axhspan(-tol, tol, color="0.9")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=tol)
    ax.set_xlabel("believed / true contact stiffness [1]")
    ax.set_ylabel("worst CoR error over the grid [1]")
    ax.set_title("Stiffness mismatch (undamped contact); dashed: with the passivity guard")
    ax.legend(fontsize=6, ncol=2, loc="best")
    ax.grid(True, alpha=0.3)
    figures.append(
        (
            _save_figure(fig, out / "cor_error_vs_prior_stiffness.png"),
            "CoR error against the believed stiffness",
            f"Worst CoR error [1] over the grid against the believed / true contact stiffness "
            f"[1], undamped contact; one colour and marker per compensator, dashed with hollow "
            f"markers: with the passivity guard; linear inside the grey band (±{tol:g}), "
            "logarithmic beyond.",
        )
    )

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
    ax.axhline(tol, color="k", lw=0.8, ls=":")
    ax.set_yscale("log")
    ax.set_ylim(bottom=1e-5)
    ax.set_xticks(
        x + width * (len(scen) - 1) / 2,
        [literal(k) for k in keys],
        rotation=45,
        ha="right",
        fontsize=7,
    )
    ax.set_ylabel("worst |CoR error| [1]")
    ax.set_title("Worst CoR error over the grid, per scenario")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    figures.append(
        (
            _save_figure(fig, out / "cor_error_by_scenario.png"),
            "Worst CoR error per scenario",
            f"Worst |CoR error| [1] over the grid per compensator and scenario, log scale "
            f"(an error below 1e-5 shows no bar; a failed run shows 1); dotted: {tol:g}.",
        )
    )

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
            ys = [rs[i] for i in pts]
            ax.plot(pts, ys, "-", marker=markers[comp], ms=4, color=colour[comp], label=comp)
    ax.axhspan(-tol, tol, color="0.9")
    ax.set_xticks(
        range(len(result.points)),
        [_label(q) for q in result.points],
        rotation=60,
        ha="right",
        fontsize=6,
    )
    ax.set_ylabel("CoR error [1]")
    ax.set_title(f"Grid points, believed stiffness x{lowest:g} (k-free compensators: x1)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, alpha=0.3)
    figures.append(
        (
            _save_figure(fig, out / "cor_error_grid.png"),
            "CoR error per grid point",
            f"CoR error [1] at each grid point (delay / table / contact frequency / k / v0) "
            f"with the stiffness believed x{lowest:g} (compensators that use no stiffness: "
            f"x1), no passivity guard; grey band: ±{tol:g}.",
        )
    )

    if traces:
        path = _plot_half_stiffness(result, out / "table1_prior_k_half.png", colour)
        figures.append(
            (
                str(path),
                "Grid point 0 with the stiffness believed 50 % low",
                "Spacecraft velocity [m/s], compensated force [N] and the online stiffness "
                "estimate over the true stiffness [1] against time [s] at grid point 0, the "
                "stiffness believed 50 % low, beside the ideal loop (wide, light).",
            )
        )

    verdict, _, table = format_summary(result).partition("\n")
    title = "at the Table 1 point" if len(result.points) == 1 else "over the Table 2 grid"
    lines = [f"# Compensators {title}", "", f"**{verdict}.**", "", "```", table, "```", ""]
    lines += ["Grid points (index: delay / table / contact f / k / v0):", ""]
    lines += [f"- {i}: {_label(q)}" for i, q in enumerate(result.points)]
    for path, title, caption in figures:
        lines += ["", f"![{title}]({Path(path).name})", f"*{caption}*"]
    report.write_text("\n".join(lines) + "\n")
    paths = [f[0] for f in figures] + [str(report)]
    from hybridtable.reports.html import write_html_report

    paths.append(str(write_html_report(report)))  # the same text, figures embedded
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


def _plot_half_stiffness(result: SweepResult, path: Path, colour: dict[str, tuple]) -> Path:
    import matplotlib.pyplot as plt

    from hybridtable.compensators.registry import compensator_names
    from hybridtable.loop.builder import LOG_ROWS
    from hybridtable.loop.simulation import simulate
    from hybridtable.sweeps.inputs import loop_params

    row, settings = result.points[0], result.settings
    ideal = loop_params(reference_inputs(row, False, settings))
    t_end = simulate(ideal).time_s[-1] + 0.1
    wide = dict(color="k", lw=4.0, alpha=0.25, zorder=1)
    runs = [("ideal loop", ideal, wide)]
    styles = {"SDMDC": "-", "sdmdc-online": "--", "smith-online": "-."}
    for name, ls in styles.items():
        if name in compensator_names():
            params = loop_params(case_inputs(row, "mismatch", name, 0.5, False, settings))
            style = dict(color=colour.get(name, "k"), ls=ls, lw=1.5, zorder=2)
            runs.append((f"{name}, k believed 50 % low", params, style))
    v_row, f_row = LOG_ROWS.index("v_des_m_per_s"), LOG_ROWS.index("f_comp_n")
    k_true = ideal.contact_stiffness_n_per_m
    fig, axes = plt.subplots(3, 1, figsize=(7, 8.5), sharex=True)
    for label, params, style in runs:
        (t, data), est = _simulate_logged(params, t_end)
        v = data[v_row]
        cor = abs(v[-1]) / abs(v[0])
        axes[0].plot(t, v, label=f"{label}: CoR {cor:.4f}", **style)
        axes[1].plot(t, data[f_row], label=label, **style)
        if est is not None:
            axes[2].plot(est[0], est[1][0] / k_true, label=label, **style)
    axes[0].set_ylabel("spacecraft velocity [m/s]")
    axes[1].set_ylabel("compensated force [N]")
    axes[2].set_ylabel("k estimate / true k [1]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.lines:
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
        line += f"; no compensation gives {_cor(none['cor'])}"
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
    reference) and ``report.md`` in ``out_dir``; returns the paths (the
    command checked the overwrite policy)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    report = out / "report.md"
    out.mkdir(parents=True, exist_ok=True)
    ranking = result.ranking()
    colour = _colours(e["compensator"] for e in ranking)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    x = np.arange(len(ranking))
    cors = [e["cor"] if math.isfinite(e["cor"]) else np.nan for e in ranking]
    for xi, e, c in zip(x, ranking, cors, strict=True):
        guard = e["passivity"]
        ax.bar(
            xi,
            c,
            color=colour[e["compensator"]],
            alpha=0.55 if guard else 1.0,
            hatch="//" if guard else None,
            edgecolor="k" if guard else None,
            lw=0.5,
        )
    for q in result.points:
        ax.axhline(q["cor_reference"], color="k", lw=0.8, ls="--")
    ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    finite = [c for c in cors if np.isfinite(c)] + [q["cor_reference"] for q in result.points]
    if finite:
        ax.set_ylim(min(finite) - 0.05, max(finite) + 0.05)
    ax.set_xticks(x, [literal(e["key"]) for e in ranking], rotation=45, ha="right", fontsize=7)
    ax.set_ylabel("CoR on the modelled rig [1]")
    ax.set_title("Compensators on the modelled rig (dashed: the model's contact, ideal rig)")
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    figure = out / "model_cor.png"
    fig.savefig(figure, dpi=120)
    plt.close(fig)
    caption = (
        "CoR [1] of every compensator on the modelled rig, best first; one colour per "
        "compensator, hatched and lighter with the passivity guard; dashed: the CoR of the "
        "model's contact on an ideal rig (the target), dotted: 1."
    )
    verdict, _, table = format_model_summary(result, rig).partition("\n")
    text = ["# Compensators on the modelled rig", "", f"**{verdict}.**", "", "```", table]
    text += ["```", "", f"![CoR of every compensator on the modelled rig]({figure.name})"]
    text += [f"*{caption}*", ""]
    report.write_text("\n".join(text))
    from hybridtable.reports.html import write_html_report

    html = write_html_report(report)  # the same text, figures embedded
    result.figures = [str(figure), str(report), str(html)]
    return list(result.figures)
