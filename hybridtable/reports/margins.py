"""Figures and Markdown summary of a margins sweep (matplotlib, Agg backend).

- ``cor_heatmaps.png``: predicted CoR over (table frequency, sensor delay) per
  compensator, the CoR = 1 contour, the paper's operating points (Tables 1-2)
  and the validated points;
- ``critical.png``: critical sensor delay against table frequency and critical
  table frequency against sensor delay, per compensator;
- ``energy_growth.png``: energy growth per contact ``CoR^2 - 1`` against
  delay (at 25 Hz) and table frequency (at 5 ms), the useful figure for an
  undamped contact;
- ``bode_table1.png``: the loop ``L = -G`` at the paper's Table 1 point, Pade
  model and exact delay (and the sampled model when the sweep is sampled);
- ``summary.md``: what the numbers mean, the Table 1 point, the grid, the
  validation.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import TwoSlopeNorm  # noqa: E402

from hybridtable.analysis.exact_delay import exact_margins, exact_open_loop  # noqa: E402
from hybridtable.analysis.linearize import ContactLoopLinearizer  # noqa: E402
from hybridtable.analysis.margins import (
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    loop_margins,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer  # noqa: E402
from hybridtable.analysis.sweep import SweepResult  # noqa: E402
from hybridtable.analysis.validation import EXPLAIN_ABOVE  # noqa: E402
from hybridtable.loop.params import HybridLoopParams  # noqa: E402

__all__ = [
    "REPORT_FILES",
    "OperatingPoint",
    "paper_points",
    "table1_point",
    "operating_point",
    "plot_cor_heatmaps",
    "plot_critical",
    "plot_energy_growth",
    "plot_bode",
    "write_summary",
    "write_report",
]

#: Files :func:`write_report` writes into its directory.
REPORT_FILES: tuple[str, ...] = (
    "cor_heatmaps.png",
    "critical.png",
    "energy_growth.png",
    "bode_table1.png",
    "summary.md",
)


def paper_points() -> list[tuple[str, float, float]]:
    """The paper's simulated operating points ``(label, delay_s, table_hz)``
    (Table 1 and the distinct delay/table pairs of Table 2)."""
    from hybridtable.studies.paper import load_tables, table2_rows

    t1 = load_tables()["table1_simulation"]["parameters"]
    pts = [("Table 1", t1["sensor_delay_s"], t1["table_response_hz"])]
    seen = {(pts[0][1], pts[0][2])}
    for row in table2_rows():
        key = (row["sensor_delay_ms"] * 1e-3, float(row["table_response_hz"]))
        if key not in seen:
            seen.add(key)
            pts.append(("Table 2", *key))
    return pts


def table1_point(base: HybridLoopParams) -> HybridLoopParams:
    """The paper's Table 1 point (contact, table, delay, lead = delay) with
    the sample rate of ``base``; a sampled point rounds the delay to whole
    samples."""
    from hybridtable.studies.paper import table1_params

    p = table1_params(base.compensator)
    if base.sample_rate_hz is not None:
        h = 1.0 / base.sample_rate_hz
        p = p.with_(
            sample_rate_hz=base.sample_rate_hz, sensor_delay_s=round(p.sensor_delay_s / h) * h
        )
    return p


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


def _save(fig, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _edges(x: np.ndarray) -> np.ndarray:
    if x.size == 1:
        return np.array([x[0] - 0.5, x[0] + 0.5]) if x[0] != 0 else np.array([-0.5, 0.5])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]])


def plot_cor_heatmaps(result: SweepResult, path: str | Path) -> Path:
    """Predicted CoR heatmaps with the CoR = 1 contour and the paper's points
    (one colour scale per compensator, white at CoR = 1)."""
    comps = list(result.compensators)
    finite = np.isfinite(result.table_response_hz)
    f = result.table_response_hz[finite]
    d_ms = result.sensor_delay_s * 1e3
    ncol = 2 if len(comps) > 1 else 1
    nrow = math.ceil(len(comps) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.2 * ncol, 4.6 * nrow), squeeze=False)
    pts = paper_points()
    for k, c in enumerate(comps):
        ax = axes[k // ncol][k % ncol]
        cor = result.compensators[c].predicted_cor[:, finite]
        if f.size == 0:
            ax.set_axis_off()
            continue
        fin = cor[np.isfinite(cor)]
        vmin = min(float(fin.min()) if fin.size else 0.99, 1.0 - 1e-4)
        vmax = max(float(fin.max()) if fin.size else 1.01, 1.0 + 1e-4)
        norm = TwoSlopeNorm(vcenter=1.0, vmin=vmin, vmax=vmax)
        mesh = ax.pcolormesh(_edges(f), _edges(d_ms), cor, cmap="RdBu_r", norm=norm, shading="flat")
        # The CoR = 1 contour only where the field crosses 1 (a marginal row at
        # exactly 1, e.g. MDC at zero delay, would give round-off squiggles).
        crosses = (fin < 1.0 - 1e-9).any() and (fin > 1.0 + 1e-9).any()
        if f.size > 1 and d_ms.size > 1 and crosses:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                cs = ax.contour(f, d_ms, cor, levels=[1.0], colors="k", linewidths=1.5)
            if cs.allsegs and any(len(s) for s in cs.allsegs[0]):
                ax.clabel(cs, fmt={1.0: "CoR = 1"}, fontsize=8)
        for label, T, fr in pts:
            if f.min() <= fr <= f.max() and d_ms.min() <= T * 1e3 <= d_ms.max():
                star = label == "Table 1"
                ax.plot(
                    fr, T * 1e3, "*" if star else "o", mfc="gold", mec="k", ms=12 if star else 6
                )
        for v in result.validation:
            if v.compensator == c and math.isfinite(v.table_response_hz):
                ax.plot(v.table_response_hz, v.sensor_delay_s * 1e3, "x", color="0.2", ms=5)
        ax.set_title(f"{c}: predicted CoR")
        ax.set_xlabel("table response frequency [Hz]")
        ax.set_ylabel("sensor delay [ms]")
        fig.colorbar(mesh, ax=ax)
    for k in range(len(comps), nrow * ncol):
        axes[k // ncol][k % ncol].set_axis_off()
    fig.suptitle(
        "Predicted CoR, white = 1 (black line: CoR = 1; star: Table 1, dots: Table 2, "
        "x: validated), "
        + ("sampled model" if result.sampled else f"Pade order {result.pade_order}"),
        fontsize=10,
    )
    return _save(fig, Path(path))


def _nearest(x: np.ndarray, target: float) -> int:
    return int(np.argmin(np.abs(np.asarray(x, dtype=float) - target)))


def plot_energy_growth(result: SweepResult, path: str | Path) -> Path:
    """Energy growth per contact (``CoR^2 - 1``) against sensor delay at the
    grid's table frequency nearest the paper's 25 Hz, and against table
    frequency at the delay nearest 5 ms."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    j = _nearest(result.table_response_hz, 25.0)
    i = _nearest(result.sensor_delay_s, 0.005)
    for c, cs in result.compensators.items():
        a1.plot(result.sensor_delay_s * 1e3, cs.energy_growth_per_contact[:, j], label=c)
        a2.plot(result.table_response_hz, cs.energy_growth_per_contact[i, :], label=c)
    a1.set_xlabel("sensor delay [ms]")
    a1.set_title(f"table {result.table_response_hz[j]:g} Hz")
    a2.set_xlabel("table response frequency [Hz]")
    a2.set_title(f"sensor delay {result.sensor_delay_s[i] * 1e3:g} ms")
    for ax in (a1, a2):
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_ylabel("energy growth per contact, CoR^2 - 1")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, Path(path))


def _finite_or_clip(y: np.ndarray, top: float) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(y, dtype=float)
    inf = np.isinf(y)
    out = np.where(inf, top, y)
    return out, inf


def plot_critical(result: SweepResult, path: str | Path) -> Path:
    """Critical sensor delay vs table frequency and critical table frequency
    vs sensor delay (``inf`` drawn at the top edge with a triangle, a table
    frequency of 0, stable over the whole search, at the bottom edge)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    f = result.table_response_hz
    d_ms = result.sensor_delay_s * 1e3
    top_d = 0.25 / result.base.contact_frequency_hz * 1e3
    top_f = 1000.0 * result.base.contact_frequency_hz
    bottom_f = 0.5 * result.base.contact_frequency_hz
    for c, cs in result.compensators.items():
        y, inf = _finite_or_clip(cs.critical_delay_s * 1e3, top_d)
        (line,) = a1.plot(f, y, "-", label=c)
        a1.plot(f[inf], y[inf], "^", color=line.get_color())
        y, inf = _finite_or_clip(cs.critical_table_hz, top_f)
        zero = y == 0.0
        y = np.where(zero, bottom_f, y)
        (line,) = a2.plot(d_ms, y, "-", label=c)
        a2.plot(d_ms[inf], y[inf], "^", color=line.get_color())
        a2.plot(d_ms[zero], y[zero], "v", color=line.get_color())
    a1.set_xlabel("table response frequency [Hz]")
    a1.set_ylabel("critical sensor delay [ms]")
    a1.set_title("loop unstable above the curve (triangle: stable up to the search limit)")
    a2.set_xlabel("sensor delay [ms]")
    a2.set_ylabel("critical table frequency [Hz]")
    a2.set_yscale("log")
    a2.set_title("unstable below the curve (^: no table fast enough, v: stable down to f_con/2)")
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    if result.base.contact_damping_n_s_per_m == 0.0:
        fig.suptitle(
            "Undamped contact: the loop is at best marginally stable, see the energy growth per "
            "contact (summary.md)",
            fontsize=10,
        )
    return _save(fig, Path(path))


def _phase_deg(L: np.ndarray) -> np.ndarray:
    """Unwrapped phase in degrees, starting within 180 deg of -180 (the
    double integrator of the spacecraft)."""
    ph = np.degrees(np.unwrap(np.angle(L)))
    return ph - 360.0 * np.round((ph[0] + 180.0) / 360.0)


def plot_bode(point: dict[str, HybridLoopParams], path: str | Path, pade_order: int = 3) -> Path:
    """Bode plot of ``L = -G`` per compensator at one point: Pade model (solid),
    exact delay (dashed), sampled model (dotted, when sampled); the third
    panel zooms on the phase margin at the contact crossover."""
    lin = ContactLoopLinearizer(pade_order)
    sampled = SampledLoopLinearizer(lin)
    fig, (am, ap, az) = plt.subplots(
        3, 1, figsize=(8, 9.5), gridspec_kw={"height_ratios": [3, 2, 2]}
    )
    any_p = next(iter(point.values()))
    w0 = math.sqrt(any_p.contact_stiffness_n_per_m / any_p.spacecraft_mass_kg)
    w = w0 * np.geomspace(0.1, 300.0, 800)
    wz = w0 * np.geomspace(0.5, 2.0, 400)
    hz, hzz = w / (2 * math.pi), wz / (2 * math.pi)
    for c, p in point.items():
        pc = p.with_(sample_rate_hz=None)
        model = lin.open_loop(pc)
        exact = exact_open_loop(lin, pc)
        L_pade, L_exact = -model.transfer(1j * w), -exact(1j * w)
        (line,) = am.loglog(hz, np.abs(L_pade), "-", label=f"{c}")
        col = line.get_color()
        am.loglog(hz, np.abs(L_exact), "--", color=col, lw=1)
        ap.semilogx(hz, _phase_deg(L_pade), "-", color=col)
        ap.semilogx(hz, _phase_deg(L_exact), "--", color=col, lw=1)
        az.semilogx(hzz, _phase_deg(-model.transfer(1j * wz)) + 180.0, "-", color=col)
        az.semilogx(hzz, _phase_deg(-exact(1j * wz)) + 180.0, "--", color=col, lw=1)
        if p.sample_rate_hz is not None:
            ms = sampled.open_loop(p)
            ok = w < math.pi * p.sample_rate_hz
            Ls = -ms.transfer(np.exp(1j * w[ok] / p.sample_rate_hz))
            am.loglog(hz[ok], np.abs(Ls), ":", color=col)
            ap.semilogx(hz[ok], _phase_deg(Ls), ":", color=col)
            Lz = -ms.transfer(np.exp(1j * wz / p.sample_rate_hz))
            az.semilogx(hzz, _phase_deg(Lz) + 180.0, ":", color=col)
        m = loop_margins(model, "python-control")
        if math.isfinite(m.crossover_rad_per_s):
            az.plot(m.crossover_rad_per_s / (2 * math.pi), m.phase_margin_deg, "o", color=col)
    am.axhline(1.0, color="0.5", lw=0.8)
    ap.axhline(-180.0, color="0.5", lw=0.8)
    az.axhline(0.0, color="0.5", lw=0.8)
    am.set_ylabel("|L|")
    ap.set_ylabel("phase of L [deg]")
    az.set_ylabel("phase of L + 180 [deg]")
    az.set_xlabel("frequency [Hz]")
    ap.set_xlabel("frequency [Hz]")
    az.set_title("near the contact crossover (dots: phase margin at the crossover)", fontsize=9)
    am.legend(fontsize=8)
    p = any_p
    am.set_title(
        f"Loop L = -G at T = {p.sensor_delay_s * 1e3:g} ms, table {p.table_response_hz:g} Hz "
        f"(solid: Pade {pade_order}, dashed: exact e^-sT"
        + (f", dotted: sampled {p.sample_rate_hz:g} Hz" if p.sample_rate_hz else "")
        + ")",
        fontsize=9,
    )
    for ax in (am, ap, az):
        ax.grid(True, which="both", alpha=0.3)
    return _save(fig, Path(path))


def _fmt(x, spec: str = ".5f") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec)


def write_summary(result: SweepResult, table1: OperatingPoint | None, path: str | Path) -> Path:
    """The Markdown summary of a sweep (see :func:`write_report`)."""
    b = result.base
    undamped = b.contact_damping_n_s_per_m == 0.0
    L: list[str] = ["# Stability margins of the hybrid loop", ""]
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
            "net delay makes it unstable and the critical delays are 0. The useful figure is "
            "the energy growth per contact.",
            "",
        ]
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
    L += [
        "| compensator | CoR min | CoR max | stable points | max energy growth | "
        "crit. delay range [ms] |",
        "|---|---|---|---|---|---|",
    ]
    for c, cs in result.compensators.items():
        cor = cs.predicted_cor[np.isfinite(cs.predicted_cor)]
        cd = cs.critical_delay_s[~np.isnan(cs.critical_delay_s)] * 1e3
        L.append(
            f"| {c} | {_fmt(float(cor.min()) if cor.size else None)} | "
            f"{_fmt(float(cor.max()) if cor.size else None)} | "
            f"{int(cs.stable.sum())}/{cs.stable.size} | "
            f"{_fmt(float(np.nanmax(cs.energy_growth_per_contact)), '.4f')} | "
            f"{_fmt(float(cd.min()) if cd.size else None, '.3f')}-"
            f"{_fmt(float(cd.max()) if cd.size else None, '.3f')} |"
        )
    L.append("")
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
) -> list[Path]:
    """Write :data:`REPORT_FILES` into ``directory`` (created if needed).

    ``table1``: figures at the paper's Table 1 point (computed, without
    simulations, if not given).
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
        plot_critical(result, d / "critical.png"),
        plot_energy_growth(result, d / "energy_growth.png"),
        plot_bode(table1.params, d / "bode_table1.png", result.pade_order or 3),
        write_summary(result, table1, d / "summary.md"),
    ]
    return files
