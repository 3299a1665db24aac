"""Figures of a margins sweep (matplotlib, Agg backend), drawn by
:func:`hybridtable.reports.margins.write_report`.

- :func:`plot_cor_heatmaps` (``cor_heatmaps.png``): predicted CoR over (table
  frequency, sensor delay) per compensator, the CoR = 1 contour, the paper's
  operating points (Tables 1-2, :func:`paper_points`) and the validated points;
- :func:`plot_critical` (``critical.png``): the sensor delay the loop takes per
  table frequency and the table frequency it needs per sensor delay, per
  compensator: the stability boundary (damped contact) and where the predicted
  CoR reaches a limit (read off the grid);
- :func:`plot_energy_growth` (``energy_growth.png``): energy growth per contact
  ``CoR^2 - 1`` against delay (at 25 Hz) and table frequency (at 5 ms), the
  useful figure for an undamped contact;
- :func:`plot_bode` (``bode_table1.png``): the loop ``L = -G`` at one point, Pade
  model and exact delay (and the sampled model when the point is sampled).
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import TwoSlopeNorm  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from hybridtable.analysis.blockwise import ContactLoopLinearizer  # noqa: E402
from hybridtable.analysis.exact_delay import exact_open_loop  # noqa: E402
from hybridtable.analysis.margins import loop_margins  # noqa: E402
from hybridtable.analysis.robustness import (  # noqa: E402
    DEFAULT_COR_LIMIT,
    grid_cor_limits,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer  # noqa: E402
from hybridtable.analysis.sweep import SweepResult  # noqa: E402
from hybridtable.loop.params import HybridLoopParams  # noqa: E402

__all__ = [
    "paper_points",
    "plot_cor_heatmaps",
    "plot_critical",
    "plot_energy_growth",
    "plot_bode",
]


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
        fig.colorbar(mesh, ax=ax, label="predicted CoR [1]")
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
    a1.set_title(f"table {result.table_response_hz[j]:.4g} Hz")
    a2.set_xlabel("table response frequency [Hz]")
    a2.set_title(f"sensor delay {result.sensor_delay_s[i] * 1e3:.4g} ms")
    for ax in (a1, a2):
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_ylabel("energy growth per contact CoR^2 - 1 [1]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, Path(path))


def _linear_base(result: SweepResult) -> HybridLoopParams:
    return result.base if result.transform is None else result.transform(result.base)


def _clip(y: np.ndarray, bottom: float, top: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``y`` with ``inf`` at ``top`` and 0 at ``bottom``, and where each was."""
    y = np.asarray(y, dtype=float)
    inf, zero = np.isinf(y), y == 0.0
    return np.where(inf, top, np.where(zero, bottom, y)), inf, zero


def plot_critical(
    result: SweepResult, path: str | Path, cor_limit: float = DEFAULT_COR_LIMIT
) -> Path:
    """How much sensor delay the loop takes (per table frequency) and how fast
    the table must be (per sensor delay), per compensator: stability (solid,
    the critical delay / table frequency; drawn for a damped contact only, an
    undamped one being marginal at best) and the predicted CoR within
    ``cor_limit`` (dashed, read off the grid). Triangles up: beyond the search
    (solid, drawn at the top edge) or the grid (dashed, drawn at the grid's
    largest delay or table frequency): left, stable / within the limit at
    every delay; right, no table fast enough. Triangles down (right): every
    table frequency will do (drawn at the search's or the grid's lowest)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    f = result.table_response_hz
    d_ms = result.sensor_delay_s * 1e3
    damped = _linear_base(result).contact_damping_n_s_per_m > 0.0
    limits = grid_cor_limits(result, cor_limit)
    cols = {c: f"C{k}" for k, c in enumerate(result.compensators)}
    delays, tables = [], []
    for c, cs in result.compensators.items():
        lim = limits[c]
        pairs = [(lim["cor_limited_delay_s"], lim["cor_limited_table_hz"], "--")]
        if damped:
            pairs.insert(0, (cs.critical_delay_s, cs.critical_table_hz, "-"))
        for delay_s, table_hz, style in pairs:
            delays.append((c, style, np.asarray(delay_s, dtype=float) * 1e3))
            tables.append((c, style, np.asarray(table_hz, dtype=float)))
    # the edges: the grid's range, or the finite values beyond it
    fin = np.concatenate([d_ms, *(y[np.isfinite(y)] for _, _, y in delays)])
    top_d = 1.06 * float(fin.max()) if fin.max() > 0 else 1.0
    ff = f[np.isfinite(f) & (f > 0)]
    fin = np.concatenate([ff, *(y[np.isfinite(y) & (y > 0)] for _, _, y in tables)])
    top_f = 1.25 * float(fin.max()) if fin.size else 1.0
    bottom_f = float(fin.min()) / 1.25 if fin.size else 0.1
    # inf / 0 of a curve read off the grid sit at the grid's edges, the searches' at the axes'
    grid_d = float(d_ms.max())
    grid_f = (float(ff.min()), float(ff.max())) if ff.size else (bottom_f, top_f)
    drawn = set()  # (compensator, style) of every curve with a point on the axes
    for c, style, y in delays:
        y, inf, _ = _clip(y, 0.0, grid_d if style == "--" else top_d)
        a1.plot(f, y, style, color=cols[c])
        a1.plot(f[inf], y[inf], "^", color=cols[c], ms=5)
        if np.isfinite(y).any():
            drawn.add((c, style))
    for c, style, y in tables:
        y, inf, zero = _clip(y, *(grid_f if style == "--" else (bottom_f, top_f)))
        a2.plot(d_ms, y, style, color=cols[c])
        a2.plot(d_ms[inf], y[inf], "^", color=cols[c], ms=5)
        a2.plot(d_ms[zero], y[zero], "v", color=cols[c], ms=5)
        if np.isfinite(y).any():
            drawn.add((c, style))
    a1.set_ylim(-0.03 * top_d, 1.04 * top_d)
    a2.set_ylim(bottom_f / 1.1, top_f * 1.1)
    a1.set_xlabel("table response frequency [Hz]")
    a1.set_ylabel("sensor delay [ms]")
    a1.set_title("Sensor delay the loop takes")
    a2.set_xlabel("sensor delay [ms]")
    a2.set_ylabel("table response frequency [Hz]")
    a2.set_yscale("log")
    a2.set_title("Table frequency the loop needs")
    # The legend names only what is drawn: a compensator or a kind of curve
    # with no finite point (never stable, no grid point within the limit) is left out.
    styles = {style for _, style in drawn}
    handles = [
        Line2D([], [], color=cols[c], label=c)
        for c in result.compensators
        if any((c, style) in drawn for style in ("-", "--"))
    ]
    if damped and "-" in styles:
        handles.append(Line2D([], [], color="0.3", ls="-", label="stability boundary"))
    elif not damped:
        handles.append(Line2D([], [], ls="none", label="undamped: no stability boundary"))
    if "--" in styles:
        handles.append(Line2D([], [], color="0.3", ls="--", label=f"CoR = {cor_limit:g}"))
    for ax in (a1, a2):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(handles=handles, fontsize=8)
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
    am.set_ylabel("|L| [1]")
    ap.set_ylabel("phase of L [deg]")
    az.set_ylabel("phase of L + 180 [deg]")
    az.set_xlabel("frequency [Hz]")
    ap.set_xlabel("frequency [Hz]")
    am.set_xlabel("frequency [Hz]")
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
