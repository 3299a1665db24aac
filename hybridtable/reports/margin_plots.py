"""Figures of a margins sweep (matplotlib, Agg backend), drawn by
:func:`hybridtable.reports.margins.write_report`.

- :func:`plot_cor_heatmaps` (``cor_heatmaps.png``): predicted CoR over (table
  frequency, sensor delay) per compensator, the CoR = 1 contour, the paper's
  operating points (Tables 1-2, :func:`paper_points`) and the validated points;
- :func:`plot_critical` (``critical.png``): critical sensor delay against table
  frequency and critical table frequency against sensor delay, per compensator;
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

from hybridtable.analysis.blockwise import ContactLoopLinearizer  # noqa: E402
from hybridtable.analysis.exact_delay import exact_open_loop  # noqa: E402
from hybridtable.analysis.margins import loop_margins  # noqa: E402
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
