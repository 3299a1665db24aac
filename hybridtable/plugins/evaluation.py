"""Every compensator over the paper's Table 2 grid, under stiffness mismatch,
sensor noise and a damped contact (``hybridtable compensators``).

Scenarios (each with and without the passivity guard):

- ``mismatch``: the undamped contact of each grid point; the compensators
  that use a stiffness believe ``prior_ratio * k`` (ratio 1: nominal);
- ``noise``: white noise on the measured force (``force_noise_ratio`` of the
  undamped peak force ``v0 sqrt(k m)``) and on the table position
  (``position_noise_ratio`` of the peak deflection ``v0 / omega``), a new
  sample every computer period, with a force deadband of
  ``deadband_sigmas`` standard deviations;
- ``damped``: a contact with damping ratio ``contact_damping_ratio``
  (``c = 2 zeta sqrt(k m)``) that the compensators do not know (prior
  damping 0).

Metrics of a run, against the reference run of the same contact with an ideal
loop (no delay, ideal table, no compensation):

- ``cor_error``: CoR minus the reference CoR (1 for an undamped contact);
- ``peak_force_error``: relative error of the peak actual contact force;
- ``energy_drift``: spacecraft kinetic energy after the contact minus the
  reference's, relative to the energy before the contact;
- ``energy_created``: the largest excess of the spacecraft's kinetic energy
  over its value before the contact, relative to it (> 0: the loop created
  energy at some instant; a passive contact never does).

Compensators that use no stiffness (``none``, ``SDC``, ``polynomial``) are run
at ratio 1 only: their results hold for every ratio.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hybridtable._validation import ParameterError, check_nonnegative, check_positive

__all__ = [
    "SCENARIOS",
    "STIFFNESS_FREE",
    "SweepSettings",
    "SweepCase",
    "SweepResult",
    "sweep_points",
    "sweep_cases",
    "case_params",
    "run_case",
    "run_sweep",
    "summarize",
    "acceptance",
    "format_summary",
    "write_report",
    "default_jobs",
]

SCENARIOS: tuple[str, ...] = ("mismatch", "noise", "damped")

#: Compensators whose force does not depend on the believed stiffness.
STIFFNESS_FREE: frozenset[str] = frozenset({"none", "SDC", "polynomial"})

#: Acceptance thresholds of the issue.
ONLINE_COR_TOLERANCE = 0.01
PASSIVITY_MAX_COR = 1.005


@dataclass(frozen=True)
class SweepSettings:
    """What :func:`run_sweep` runs.

    Parameters
    ----------
    compensators : tuple of str
        Registered compensator names (default: all).
    prior_ratios : tuple of float
        Believed / true stiffness in the ``mismatch`` scenario (> 0).
    noise_prior_ratios, damped_prior_ratios : tuple of float
        The same for the ``noise`` and ``damped`` scenarios.
    force_noise_ratio : float
        Force noise standard deviation / undamped peak force.
    position_noise_ratio : float
        Position noise standard deviation / undamped peak deflection.
    deadband_sigmas : float
        Force deadband of the noise scenario, in force-noise deviations.
    contact_damping_ratio : float
        Damping ratio of the ``damped`` scenario's contact.
    passivity : tuple of bool
        Guard settings to run.
    scenarios : tuple of str
        Subset of :data:`SCENARIOS`.
    sample_rate_hz : float or None
        Sampled rig computer (None: continuous loop, as the paper).
    seed : int
        Base seed of the noise (each grid point adds its index).
    """

    compensators: tuple[str, ...] = ()
    prior_ratios: tuple[float, ...] = (0.5, 0.75, 1.0, 1.5, 2.0)
    noise_prior_ratios: tuple[float, ...] = (0.5, 1.0)
    damped_prior_ratios: tuple[float, ...] = (0.5, 1.0)
    force_noise_ratio: float = 1e-3
    position_noise_ratio: float = 1e-4
    deadband_sigmas: float = 5.0
    contact_damping_ratio: float = 0.1
    passivity: tuple[bool, ...] = (False, True)
    scenarios: tuple[str, ...] = SCENARIOS
    sample_rate_hz: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        from hybridtable.compensator import compensator_names

        names = compensator_names()
        comps = tuple(self.compensators) or names
        for c in comps:
            if c not in names:
                raise ParameterError(f"compensator must be one of {', '.join(names)} (got {c!r})")
        object.__setattr__(self, "compensators", comps)
        for name in ("prior_ratios", "noise_prior_ratios", "damped_prior_ratios"):
            values = tuple(check_positive(name, r) for r in getattr(self, name))
            if not values:
                raise ParameterError(f"{name} must not be empty")
            object.__setattr__(self, name, values)
        for name in (
            "force_noise_ratio",
            "position_noise_ratio",
            "deadband_sigmas",
            "contact_damping_ratio",
        ):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))
        if self.contact_damping_ratio >= 1.0:
            raise ParameterError("contact_damping_ratio must be < 1")
        for s in self.scenarios:
            if s not in SCENARIOS:
                raise ParameterError(f"scenario must be one of {', '.join(SCENARIOS)} (got {s!r})")
        object.__setattr__(self, "scenarios", tuple(self.scenarios))
        object.__setattr__(self, "passivity", tuple(bool(p) for p in self.passivity))
        if self.sample_rate_hz is not None:
            object.__setattr__(
                self, "sample_rate_hz", check_positive("sample_rate_hz", self.sample_rate_hz)
            )


@dataclass(frozen=True)
class SweepCase:
    """One run of the sweep (picklable: plain values only)."""

    point: int
    row: tuple[tuple[str, float], ...]
    scenario: str
    compensator: str
    prior_ratio: float
    passivity: bool

    @property
    def row_dict(self) -> dict[str, float]:
        return dict(self.row)

    @property
    def is_reference(self) -> bool:
        return self.compensator == "ideal"


@dataclass
class SweepResult:
    """Runs of :func:`run_sweep` (dicts, JSON-ready) and the settings."""

    settings: SweepSettings
    points: list[dict[str, float]]
    runs: list[dict[str, Any]]
    references: list[dict[str, Any]]
    wall_time_s: float = 0.0
    figures: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "settings": asdict(self.settings),
            "points": self.points,
            "references": self.references,
            "runs": self.runs,
            "summary": summarize(self),
            "acceptance": acceptance(self),
            "figures": self.figures,
            "wall_time_s": self.wall_time_s,
        }


def sweep_points(tables: dict[str, Any] | None = None, quick: bool = False) -> list[dict]:
    """The distinct rows of Table 2 (paper units, without the CoR column);
    ``quick``: the Table 1 point only."""
    from hybridtable.paper import load_tables, table2_rows

    tables = tables or load_tables()
    points: list[dict[str, float]] = []
    for row in table2_rows(tables):
        row = {k: float(v) for k, v in row.items() if k != "cor_sdmdc"}
        if row not in points:
            points.append(row)
    if quick:
        t1 = tables["table1_simulation"]["parameters"]
        point = {
            "sensor_delay_ms": t1["sensor_delay_s"] * 1e3,
            "table_response_hz": t1["table_response_hz"],
            "contact_frequency_hz": t1["contact_frequency_hz"],
            "contact_stiffness_n_per_mm": t1["contact_stiffness_n_per_m"] * 1e-3,
            "initial_velocity_mm_per_s": t1["initial_velocity_m_per_s"] * 1e3,
        }
        points = [{k: float(v) for k, v in point.items()}]
    return points


def sweep_cases(settings: SweepSettings, points: Sequence[dict[str, float]]) -> list[SweepCase]:
    """Every run of the sweep, references excluded."""
    ratios = {
        "mismatch": settings.prior_ratios,
        "noise": settings.noise_prior_ratios,
        "damped": settings.damped_prior_ratios,
    }
    cases = []
    for i, row in enumerate(points):
        frozen = tuple(sorted(row.items()))
        for scenario in settings.scenarios:
            for comp in settings.compensators:
                rs = (1.0,) if comp in STIFFNESS_FREE else ratios[scenario]
                for ratio in rs:
                    for guard in settings.passivity:
                        cases.append(SweepCase(i, frozen, scenario, comp, ratio, guard))
    return cases


def _reference_cases(settings: SweepSettings, points) -> list[SweepCase]:
    damped = [False, True] if "damped" in settings.scenarios else [False]
    return [
        SweepCase(i, tuple(sorted(row.items())), "damped" if d else "mismatch", "ideal", 1.0, False)
        for i, row in enumerate(points)
        for d in damped
    ]


def _noise_levels(params) -> tuple[float, float]:
    """Undamped peak force v0 sqrt(k m) and peak deflection v0 / omega."""
    k, m = params.contact_stiffness_n_per_m, params.spacecraft_mass_kg
    v0 = params.initial_velocity_m_per_s
    return v0 * math.sqrt(k * m), v0 / math.sqrt(k / m)


def case_params(case: SweepCase, settings: SweepSettings):
    """The :class:`~hybridtable.loop.HybridLoopParams` of a case, and the
    noise it reads (a :class:`~hybridtable.plugins.noise.MeasurementNoiseParams`
    or None)."""
    from hybridtable.paper import table2_params
    from hybridtable.plugins.noise import MeasurementNoiseParams

    base = table2_params(case.row_dict, sample_rate_hz=settings.sample_rate_hz)
    k, m = base.contact_stiffness_n_per_m, base.spacecraft_mass_kg
    c = 2.0 * settings.contact_damping_ratio * math.sqrt(k * m)
    damping = c if case.scenario == "damped" else 0.0
    if case.is_reference:
        return (
            base.with_(
                compensator="none",
                sensor_delay_s=0.0,
                table_response_hz=math.inf,
                contact_damping_n_s_per_m=damping,
                sample_rate_hz=None,
            ),
            None,
        )
    params = base.with_(
        compensator=case.compensator,
        compensator_stiffness_n_per_m=case.prior_ratio * k,
        compensator_damping_n_s_per_m=0.0,
        contact_damping_n_s_per_m=damping,
        passivity=case.passivity,
    )
    noise = None
    if case.scenario == "noise":
        f0, x0 = _noise_levels(params)
        sigma_f = settings.force_noise_ratio * f0
        noise = MeasurementNoiseParams(
            sigma_f, settings.position_noise_ratio * x0, settings.seed + case.point
        )
        params = params.with_(force_deadband_n=settings.deadband_sigmas * sigma_f)
    return params, noise


def run_case(case: SweepCase, settings: SweepSettings) -> dict[str, Any]:
    """Run one case; a failed run (divergence, capture) is recorded with its
    error and NaN metrics, never dropped."""
    from hybridtable.compensator import make_compensator
    from hybridtable.loop import build_hybrid_loop
    from hybridtable.plugins.noise import with_measurement_noise
    from hybridtable.simulation import SimulationError, run_loop

    params, noise = case_params(case, settings)
    out: dict[str, Any] = {
        "point": case.point,
        "scenario": case.scenario,
        "compensator": case.compensator,
        "prior_ratio": case.prior_ratio,
        "passivity": case.passivity,
        "error": None,
    }
    try:
        compensator = None
        if noise is not None:
            period = build_hybrid_loop(params, log=False).computer_period_s
            inner = make_compensator(params.with_(passivity=False), period)
            compensator = with_measurement_noise(inner, noise, period)
        result = run_loop(build_hybrid_loop(params, compensator=compensator))
    except SimulationError as err:
        out.update(cor=math.nan, peak_force_n=math.nan, energy_created=math.nan, error=str(err))
        return out
    m = result.metrics
    v = result.v_des_m_per_s
    ke_in = 0.5 * m.v_in_m_per_s**2
    ke_max = float(np.max(0.5 * v**2))
    out.update(
        cor=m.cor,
        peak_force_n=m.peak_force_n,
        v_in_m_per_s=m.v_in_m_per_s,
        v_out_m_per_s=m.v_out_m_per_s,
        energy_created=max(0.0, ke_max - ke_in) / ke_in,
        steps=result.steps,
    )
    return out


def _run_indexed(item):
    index, case, settings = item
    return index, run_case(case, settings)


def run_sweep(
    settings: SweepSettings,
    points: Sequence[dict[str, float]],
    progress: bool = True,
    jobs: int = 1,
) -> SweepResult:
    """Run the references and every case (``jobs`` worker processes)."""
    import time

    from tqdm import tqdm

    t0 = time.perf_counter()
    refs = _reference_cases(settings, points)
    cases = sweep_cases(settings, points)
    work = list(enumerate(refs + cases))
    results: list[dict[str, Any] | None] = [None] * len(work)
    bar = tqdm(total=len(work), desc="compensators", unit="run", disable=not progress)
    items = [(i, c, settings) for i, c in work]
    if jobs <= 1:
        for item in items:
            i, r = _run_indexed(item)
            results[i] = r
            bar.update(1)
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # fork where available (no main-module guard needed in scripts).
        methods = multiprocessing.get_all_start_methods()
        ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            for i, r in pool.map(_run_indexed, items, chunksize=4):
                results[i] = r
                bar.update(1)
    bar.close()
    ref_runs = results[: len(refs)]
    runs = results[len(refs) :]
    ref_by = {(r["point"], r["scenario"] == "damped"): r for r in ref_runs}
    for r in runs:
        ref = ref_by[(r["point"], r["scenario"] == "damped")]
        r["cor_reference"] = ref["cor"]
        r["cor_error"] = r["cor"] - ref["cor"]
        r["peak_force_error"] = r["peak_force_n"] / ref["peak_force_n"] - 1.0
        r["energy_drift"] = r["cor"] ** 2 - ref["cor"] ** 2
    return SweepResult(settings, list(points), runs, ref_runs, wall_time_s=time.perf_counter() - t0)


def _key(r: dict[str, Any]) -> str:
    return r["compensator"] + (" +passivity" if r["passivity"] else "")


def _max_abs(values: list[float]) -> float:
    if not values:
        return math.nan
    arr = np.asarray(values, dtype=float)
    return math.inf if np.isnan(arr).any() else float(np.max(np.abs(arr)))


def summarize(result: SweepResult) -> dict[str, dict[str, Any]]:
    """Per compensator (and guard) and scenario: worst |CoR error|, largest
    CoR, worst |peak-force error|, worst |energy drift|, largest energy
    created, number of runs and of failed runs."""
    out: dict[str, dict[str, Any]] = {}
    for r in result.runs:
        entry = out.setdefault(_key(r), {}).setdefault(r["scenario"], {"runs": []})
        entry["runs"].append(r)
    for key, scen in out.items():
        for name, entry in scen.items():
            rs = entry.pop("runs")
            nominal = [r for r in rs if r["prior_ratio"] == 1.0]
            scen[name] = {
                "runs": len(rs),
                "failed": sum(r["error"] is not None for r in rs),
                "max_abs_cor_error": _max_abs([r["cor_error"] for r in rs]),
                "max_abs_cor_error_nominal_k": _max_abs([r["cor_error"] for r in nominal]),
                "max_cor": float(np.nanmax([r["cor"] for r in rs]))
                if any(r["error"] is None for r in rs)
                else math.nan,
                "max_abs_peak_force_error": _max_abs([r["peak_force_error"] for r in rs]),
                "max_abs_energy_drift": _max_abs([r["energy_drift"] for r in rs]),
                "max_energy_created": _max_abs([r["energy_created"] for r in rs]),
            }
        out[key] = scen
    return out


def acceptance(result: SweepResult) -> dict[str, Any]:
    """The issue's acceptance checks on this sweep.

    - ``sdmdc_online``: every unguarded ``sdmdc-online`` run of the
      ``mismatch`` scenario within 0.01 of the reference CoR;
    - ``passivity``: no guarded run ends with CoR above 1.005 (a failed
      guarded run fails the check);
    - ``fixed_k_sdmdc_at_half_k``: fixed-k SDMDC's CoR error at prior ratio
      0.5 (shown, not a pass/fail point).
    """
    online = [
        r
        for r in result.runs
        if r["compensator"] == "sdmdc-online" and not r["passivity"] and r["scenario"] == "mismatch"
    ]
    online_err = _max_abs([r["cor_error"] for r in online])
    guarded = [r for r in result.runs if r["passivity"]]
    worst = max(guarded, key=lambda r: -math.inf if r["error"] else r["cor"], default=None)
    guarded_ok = all(r["error"] is None and r["cor"] <= PASSIVITY_MAX_COR for r in guarded)
    half = [
        {"point": r["point"], "cor": r["cor"], "cor_error": r["cor_error"]}
        for r in result.runs
        if r["compensator"] == "SDMDC"
        and not r["passivity"]
        and r["scenario"] == "mismatch"
        and r["prior_ratio"] == 0.5
    ]
    online_half = [
        {"point": r["point"], "cor": r["cor"], "cor_error": r["cor_error"]}
        for r in online
        if r["prior_ratio"] == 0.5
    ]
    out: dict[str, Any] = {
        "sdmdc_online": {
            "runs": len(online),
            "max_abs_cor_error": online_err,
            "tolerance": ONLINE_COR_TOLERANCE,
            "passed": bool(online) and online_err <= ONLINE_COR_TOLERANCE,
        },
        "passivity": {
            "runs": len(guarded),
            "max_cor": None if worst is None else worst["cor"],
            "worst_case": None
            if worst is None
            else {k: worst[k] for k in ("point", "scenario", "compensator", "prior_ratio")},
            "limit": PASSIVITY_MAX_COR,
            "passed": bool(guarded) and guarded_ok,
        },
        "fixed_k_sdmdc_at_half_k": half,
        "sdmdc_online_at_half_k": online_half,
    }
    return out


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

    from hybridtable.loop import add_hybrid_loop

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

    from hybridtable.compensator import compensator_names
    from hybridtable.loop import LOG_ROWS
    from hybridtable.simulation import simulate

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


def default_jobs() -> int:
    """Worker processes: the CPUs available, at most 4."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        n = os.cpu_count() or 1
    return max(1, min(4, n))
