"""The report of a margins sweep: operating points, Markdown summary, and the files.

:func:`write_report` writes these files (the figures are drawn by
:mod:`hybridtable.reports.margin_plots`, matplotlib with the Agg backend):

- ``cor_heatmaps.png``: predicted CoR over (table frequency, sensor delay) per
  compensator, the CoR = 1 contour, the paper's operating points (Tables 1-2)
  and the validated points;
- ``critical.png``: the sensor delay the loop takes per table frequency and
  the table frequency it needs per sensor delay, per compensator: stability
  (damped contact) and the predicted CoR within a limit;
- ``energy_growth.png``: energy growth per contact ``CoR^2 - 1`` against
  delay (at 25 Hz) and table frequency (at 5 ms), the useful figure for an
  undamped contact;
- ``bode_table1.png``: the loop ``L = -G`` at the paper's Table 1 point, Pade
  model and exact delay (and the sampled model when the sweep is sampled);
- ``report.md``: what the numbers mean, the margins at the operating point
  (:mod:`hybridtable.reports.margin_point`), the Table 1 point, the grid, the
  figures with their captions, the validation (and, with a model file, its
  rig's operating point).

With a model file (``margins --model``), the rig's own operating point is set
by :mod:`hybridtable.reports.margin_model` (re-exported here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.exact_delay import exact_margins
from hybridtable.analysis.margins import (
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    loop_margins,
)
from hybridtable.analysis.robustness import DEFAULT_COR_LIMIT, grid_cor_limits
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.analysis.sweep import SweepResult
from hybridtable.analysis.validation import EXPLAIN_ABOVE
from hybridtable.loop.params import HybridLoopParams
from hybridtable.reports.margin_model import (
    ModelPoint,
    format_model_point,
    model_operating_point,
    model_verdict,
)
from hybridtable.reports.margin_plots import (
    plot_bode,
    plot_cor_heatmaps,
    plot_critical,
    plot_energy_growth,
)
from hybridtable.reports.margin_point import PointMargins, point_markdown

__all__ = [
    "REPORT_FILES",
    "OperatingPoint",
    "table1_point",
    "operating_point",
    "write_summary",
    "write_report",
    "ModelPoint",
    "model_operating_point",
    "model_verdict",
    "format_model_point",
]

#: Files :func:`write_report` writes into its directory.
REPORT_FILES: tuple[str, ...] = (
    "cor_heatmaps.png",
    "critical.png",
    "energy_growth.png",
    "bode_table1.png",
    "report.md",
)


def table1_point(base: HybridLoopParams) -> HybridLoopParams:
    """The paper's Table 1 point (contact, table, delay, lead = delay) with
    the sample rate of ``base``."""
    from hybridtable.studies.paper import table1_params

    return table1_params(base.compensator).with_(sample_rate_hz=base.sample_rate_hz)


@dataclass
class OperatingPoint:
    """Every figure at one operating point, per compensator."""

    params: dict[str, HybridLoopParams]
    margins: dict[str, dict] = field(default_factory=dict)
    exact: dict[str, dict] = field(default_factory=dict)
    critical_delay_s: dict[str, float] = field(default_factory=dict)
    critical_table_hz: dict[str, float] = field(default_factory=dict)
    cor_sim: dict[str, float | None] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            c: {
                "sensor_delay_s": p.sensor_delay_s,
                "table_response_hz": p.table_response_hz,
                "margins": self.margins.get(c),
                "exact_delay": self.exact.get(c),
                "critical_delay_s": self.critical_delay_s.get(c),
                "critical_table_hz": self.critical_table_hz.get(c),
                "cor_sim": self.cor_sim.get(c),
            }
            for c, p in self.params.items()
        }


def operating_point(
    params_by_compensator: dict[str, HybridLoopParams],
    pade_order: int = 3,
    simulate: bool = False,
) -> OperatingPoint:
    """Margins (python-control ``stability_margins``), exact-delay figures,
    critical delay and table frequency, and optionally the simulated CoR, for
    each compensator at one point."""
    lin = ContactLoopLinearizer(pade_order)
    sampled = SampledLoopLinearizer(lin)
    out = OperatingPoint(dict(params_by_compensator))
    for c, p in params_by_compensator.items():
        model = sampled.open_loop if p.sample_rate_hz is not None else lin.open_loop
        out.margins[c] = loop_margins(model(p), pm_method="python-control").to_dict()
        if p.sample_rate_hz is None:
            out.exact[c] = exact_margins(lin, p).to_dict()
        g = growth_of(model)
        out.critical_delay_s[c] = critical_sensor_delay(g, p)
        out.critical_table_hz[c] = critical_table_frequency(g, p)
        if simulate:
            from hybridtable.errors import SimulationError
            from hybridtable.loop.simulation import simulate as sim

            try:
                out.cor_sim[c] = float(sim(p).metrics.cor)
            except SimulationError:
                out.cor_sim[c] = None
    return out


def _fmt(x, spec: str = ".5f") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec)


def _figures(
    result: SweepResult, table1: OperatingPoint | None, cor_limit: float, undamped: bool
) -> list[str]:
    """The figures of :func:`write_report`, each with its caption line."""
    f = result.table_response_hz
    j = int(np.argmin(np.abs(f - 25.0)))
    i = int(np.argmin(np.abs(result.sensor_delay_s - 0.005)))
    model = "sampled model" if result.sampled else f"Pade order {result.pade_order}"
    critical = (
        f"Dashed: where the predicted CoR reaches {cor_limit:g} (read off the grid); an "
        "undamped contact has no stability boundary to draw (critical delay 0)."
        if undamped
        else f"Solid: the stability boundary (critical delay, critical table frequency); dashed: "
        f"where the predicted CoR reaches {cor_limit:g} (read off the grid)."
    )
    L = [
        "## Figures",
        "",
        "![Predicted CoR over the grid](cor_heatmaps.png)",
        f"*Predicted CoR [1] per compensator over table response frequency [Hz] and sensor "
        f"delay [ms] ({model}); white at CoR = 1, black line CoR = 1, star: the paper's Table 1 "
        "point, dots: its Table 2 points, x: the validated points.*",
        "",
        "![Sensor delay and table frequency the loop allows](critical.png)",
        "*Left: sensor delay [ms] the loop takes against table response frequency [Hz]; right: "
        f"table response frequency [Hz] it needs against sensor delay [ms]. {critical} "
        "Triangles up: beyond the search or the grid; down: at every table frequency.*",
        "",
        "![Energy growth per contact](energy_growth.png)",
        f"*Energy growth per contact CoR^2 - 1 [1] against sensor delay [ms] at table "
        f"{f[j]:.4g} Hz (left) and against table response frequency [Hz] at sensor delay "
        f"{result.sensor_delay_s[i] * 1e3:.4g} ms (right).*",
        "",
    ]
    if table1 is not None:
        p0 = next(iter(table1.params.values()))
        L += [
            "![Bode plot at the Table 1 point](bode_table1.png)",
            f"*Loop L = -G at sensor delay {p0.sensor_delay_s * 1e3:g} ms, table "
            f"{p0.table_response_hz:g} Hz: magnitude [1] and phase [deg] against frequency [Hz], "
            "Pade (solid) and exact delay (dashed); bottom: phase + 180 [deg] near the contact "
            "crossover, dots at the phase margin.*",
            "",
        ]
    return L


def write_summary(
    result: SweepResult,
    table1: OperatingPoint | None,
    path: str | Path,
    model_lines: list[str] | None = None,
    point: PointMargins | None = None,
    cor_limit: float = DEFAULT_COR_LIMIT,
    verdict: str | None = None,
) -> Path:
    """The Markdown report of a sweep (see :func:`write_report`);
    ``model_lines``: the text of :func:`format_model_point`, a section of its
    own; ``point``: the margins at the operating point; ``verdict``: the
    sentence the report opens with."""
    b = result.base if result.transform is None else result.transform(result.base)
    undamped = b.contact_damping_n_s_per_m == 0.0
    L: list[str] = ["# Stability margins of the hybrid loop", ""]
    if verdict:
        L += [verdict[:1].upper() + verdict[1:] + ".", ""]
    kind = (
        f"sampled-data at {b.sample_rate_hz:g} Hz (ZOH plant, z^-M delay)"
        if result.sampled
        else f"continuous, Pade order {result.pade_order} delay"
    )
    L += [
        f"Model: {kind}, linearized in contact by Drake (bilateral contact, ungated "
        f"compensator). Contact {b.contact_stiffness_n_per_m:g} N/m, "
        f"{b.contact_frequency_hz:g} Hz (m = {b.spacecraft_mass_kg:.4g} kg), damping "
        f"{b.contact_damping_n_s_per_m:g} N s/m; table damping ratio {b.table_damping_ratio:g}; "
        f"lead time {'= sensor delay' if b.lead_time_s is None else f'{b.lead_time_s:g} s'}.",
        "",
        "- predicted CoR = exp(sigma pi / w_d) of the contact pole; energy growth per contact "
        "= CoR^2 - 1;",
        "- phase margin at the gain crossover nearest the ideal contact loop's; effective "
        "delay = (atan(c w / k) - PM) / w, the phase the rig takes at the crossover;",
        "- critical sensor delay: smallest delay with an unstable loop (0: unstable already at "
        "zero delay; inf: stable up to a quarter contact period); critical table frequency: "
        "stable above it (inf: no table fast enough).",
        "",
    ]
    if undamped:
        L += [
            "The contact is undamped: the ideal loop is marginally stable (CoR = 1), so any "
            "net delay makes it unstable and the critical delays are 0. The useful figures are "
            f"the energy growth per contact and the delay up to which the CoR stays within "
            f"{cor_limit:g}.",
            "",
        ]
    if model_lines:
        L += ["## The modelled rig", "", "```", *model_lines, "```", ""]
    if point is not None:
        L += point_markdown(point)
    if table1 is not None:
        p0 = next(iter(table1.params.values()))
        L += [
            f"## The paper's Table 1 point (T = {p0.sensor_delay_s * 1e3:g} ms, table "
            f"{p0.table_response_hz:g} Hz, zeta {p0.table_damping_ratio:g}, contact "
            f"{p0.contact_frequency_hz:g} Hz, k = {p0.contact_stiffness_n_per_m:g} N/m)",
            "",
            "The paper's parameters (undamped contact), whatever the sweep's contact; "
            "the simulated CoR is the continuous-time (or sampled) nonlinear loop's.",
            "",
            "| compensator | predicted CoR | exact-delay CoR | Pade error | simulated CoR | "
            "paper | energy growth | damping ratio | PM [deg] | crossover [Hz] | "
            "eff. delay [ms] | crit. delay [ms] | crit. table [Hz] |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        from hybridtable.studies.paper import load_tables

        paper = load_tables()["table1_simulation"]["cor"]
        for c in table1.params:
            m = table1.margins[c]
            e = table1.exact.get(c) or {}
            L.append(
                f"| {c} | {_fmt(m['predicted_cor'])} | {_fmt(e.get('predicted_cor'))} | "
                f"{_fmt(e.get('pade_cor_error'), '.1e')} | {_fmt(table1.cor_sim.get(c))} | "
                f"{_fmt(paper.get(c), '.4f')} | {_fmt(m['energy_growth_per_contact'], '.4f')} | "
                f"{_fmt(m['damping_ratio'], '.5f')} | {_fmt(m['phase_margin_deg'], '.3f')} | "
                f"{_fmt(m['crossover_rad_per_s'] / (2 * math.pi), '.4f')} | "
                f"{_fmt(m['effective_delay_s'] * 1e3, '.3f')} | "
                f"{_fmt(table1.critical_delay_s[c] * 1e3, '.3f')} | "
                f"{_fmt(table1.critical_table_hz[c], '.1f')} |"
            )
        L.append("")
    L += [
        f"## Grid: {result.sensor_delay_s.size} delays "
        f"({result.sensor_delay_s.min() * 1e3:g}-{result.sensor_delay_s.max() * 1e3:g} ms) x "
        f"{result.table_response_hz.size} table frequencies "
        f"({result.table_response_hz.min():g}-{result.table_response_hz.max():g} Hz), "
        f"{result.wall_time_s:.1f} s",
        "",
    ]
    if result.verification_error is not None:
        L += [
            f"Block-assembled model against Drake's Linearize of the full diagram: largest "
            f"relative difference {result.verification_error:.1e}.",
            "",
        ]
    limits = grid_cor_limits(result, cor_limit)
    dmax = float(result.sensor_delay_s.max()) * 1e3
    head = ["compensator", "CoR min", "CoR max", "max energy growth [1]"]
    head.append(f"CoR <= {cor_limit:g} up to [ms] (range over the tables)")
    if not undamped:
        head += ["stable points", "crit. delay range [ms]"]
    L += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c, cs in result.compensators.items():
        cor = cs.predicted_cor[np.isfinite(cs.predicted_cor)]
        lim = limits[c]["cor_limited_delay_s"] * 1e3
        row = [
            c,
            _fmt(float(cor.min()) if cor.size else None),
            _fmt(float(cor.max()) if cor.size else None),
            _fmt(float(np.nanmax(cs.energy_growth_per_contact)), ".4f"),
            "-".join(
                f"> {dmax:g}" if math.isinf(x) else f"{x:.3f}"
                for x in sorted({float(np.nanmin(lim)), float(np.nanmax(lim))})
            ),
        ]
        if not undamped:
            cd = cs.critical_delay_s[~np.isnan(cs.critical_delay_s)] * 1e3
            row += [
                f"{int(cs.stable.sum())}/{cs.stable.size}",
                f"{_fmt(float(cd.min()) if cd.size else None, '.3f')}-"
                f"{_fmt(float(cd.max()) if cd.size else None, '.3f')}",
            ]
        L.append("| " + " | ".join(row) + " |")
    L.append("")
    L += _figures(result, table1, cor_limit, undamped)
    if result.validation:
        ok = [v for v in result.validation if v.abs_error is not None]
        failed = [v for v in result.validation if v.abs_error is None]
        worst = max(ok, key=lambda v: v.abs_error) if ok else None
        npts = len({(v.i, v.j) for v in result.validation})
        L += [
            f"## Validation: {len(result.validation)} simulations at {npts} grid points",
            "",
        ]
        if worst is not None:
            L += [
                f"Largest |CoR_linear - CoR_sim| = {worst.abs_error:.5f} ({worst.compensator}, "
                f"T = {worst.sensor_delay_s * 1e3:.3g} ms, table {worst.table_response_hz:.4g} Hz); "
                f"median {float(np.median([v.abs_error for v in ok])):.2e}.",
                "",
            ]
        big = [v for v in ok if v.abs_error > EXPLAIN_ABOVE]
        if big:
            L += [
                f"Points above {EXPLAIN_ABOVE}: the linear loop run from the simulated onset "
                "state over the table's contact (CoR_transient) splits the error into a "
                "*transient* part (CoR_linear - CoR_transient: the onset state is off the contact "
                "mode, and the contact lasts while the table penetrates, which lags the "
                "MDC-compensated virtual contact at p_des by 2 zeta / w_table) and a *gating and "
                "separation* part (CoR_transient - CoR_sim: the compensator waits for the delayed "
                "measured force, the contact is unilateral, the delayed force acts after "
                "separation)."
                + (
                    " With a damped contact the unilateral contact also separates early, "
                    "when k p + c v reaches zero (the damper cannot pull), so the simulated "
                    "CoR is above the linear one even for a perfect rig."
                    if b.contact_damping_n_s_per_m > 0
                    else ""
                ),
                "",
                "| compensator | delay [ms] | table [Hz] | CoR_linear | CoR_transient | CoR_sim | "
                "transient part | gating part | larger |",
                "|---|---|---|---|---|---|---|---|---|",
            ]
            for v in sorted(big, key=lambda v: -v.abs_error):
                tr = v.cor_linear_transient
                L.append(
                    f"| {v.compensator} | {v.sensor_delay_s * 1e3:.3g} | {v.table_response_hz:.4g} | "
                    f"{_fmt(v.cor_linear)} | {_fmt(tr)} | {_fmt(v.cor_sim)} | "
                    f"{_fmt(None if tr is None else v.cor_linear - tr, '+.5f')} | "
                    f"{_fmt(None if tr is None else tr - v.cor_sim, '+.5f')} | {v.cause or '-'} |"
                )
            L.append("")
        if failed:
            L += [f"{len(failed)} simulations failed:", ""]
            L += [
                f"- {v.compensator}, T = {v.sensor_delay_s * 1e3:.3g} ms, table "
                f"{v.table_response_hz:.4g} Hz: {v.error}"
                for v in failed
            ]
            L.append("")
        exact = [v for v in ok if v.cor_exact_delay is not None]
        if exact:
            perr = max(abs(v.cor_linear - v.cor_exact_delay) for v in exact)
            L += [f"Largest Pade - exact-delay CoR difference at these points: {perr:.1e}.", ""]
    for note in result.notes:
        L += [f"Note: {note}.", ""]
    L += [
        "Not in the linear model: the compensator's gating (f_mea <= dead band => 0) and "
        "clamp, the unilateral contact (contact onset and separation), the force dead band.",
        "",
    ]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(L))
    return path


def write_report(
    result: SweepResult,
    directory: str | Path,
    table1: OperatingPoint | None = None,
    model_lines: list[str] | None = None,
    point: PointMargins | None = None,
    cor_limit: float = DEFAULT_COR_LIMIT,
    verdict: str | None = None,
) -> list[Path]:
    """Write :data:`REPORT_FILES` into ``directory`` (created if needed).

    ``table1``: figures at the paper's Table 1 point (computed, without
    simulations, if not given); ``model_lines``, ``point``, ``verdict``: see
    :func:`write_summary`; ``cor_limit``: the CoR limit of the critical figure.
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    comps = list(result.compensators)
    if table1 is None:
        table1 = operating_point(
            {c: table1_point(result.base.with_(compensator=c)) for c in comps},
            result.pade_order or 3,
        )
    files = [
        plot_cor_heatmaps(result, d / "cor_heatmaps.png"),
        plot_critical(result, d / "critical.png", cor_limit),
        plot_energy_growth(result, d / "energy_growth.png"),
        plot_bode(table1.params, d / "bode_table1.png", result.pade_order or 3),
        write_summary(result, table1, d / "report.md", model_lines, point, cor_limit, verdict),
    ]
    from hybridtable.reports.html import write_html_report

    files.append(write_html_report(files[-1]))  # report.html: the same text, figures embedded
    return files
