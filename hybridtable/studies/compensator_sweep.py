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

The runs are a campaign of :mod:`hybridtable.sweeps` (the command builds its
specs): :func:`sweep_runs` gives every run as the inputs of a sweep (plain
dicts, by the names of :mod:`hybridtable.sweeps.inputs`) beside what the
post-processing needs, and :func:`sweep_result` turns the rows the campaign
returns into a :class:`SweepResult`. This module runs nothing itself.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.studies.run_json import run_json

__all__ = [
    "SCENARIOS",
    "STIFFNESS_FREE",
    "SweepSettings",
    "SweepResult",
    "RUN_METRICS",
    "sweep_points",
    "reference_inputs",
    "case_inputs",
    "sweep_runs",
    "sweep_result",
    "summarize",
    "checks",
    "ONLINE_COR_TOLERANCE",
    "PASSIVITY_MAX_COR",
]


SCENARIOS: tuple[str, ...] = ("mismatch", "noise", "damped")


#: Compensators whose force does not depend on the believed stiffness.
STIFFNESS_FREE: frozenset[str] = frozenset({"none", "SDC", "polynomial"})


#: Largest |CoR error| that ``sdmdc-online`` should show at any believed stiffness.
ONLINE_COR_TOLERANCE = 0.01

#: Largest CoR that any run with the passivity guard should end with.
PASSIVITY_MAX_COR = 1.005


@dataclass(frozen=True)
class SweepSettings:
    """What the sweep runs (:func:`sweep_runs`).

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
        The campaign's seed: each run's noise seed derives from it and the
        run's index (:mod:`hybridtable.sweeps`).
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
        from hybridtable.compensators.registry import compensator_names

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
                raise ParameterError(
                    f"scenarios must each be one of {', '.join(SCENARIOS)} (got {s!r})"
                )
        object.__setattr__(self, "scenarios", tuple(self.scenarios))
        object.__setattr__(self, "passivity", tuple(bool(p) for p in self.passivity))
        if self.sample_rate_hz is not None:
            object.__setattr__(
                self, "sample_rate_hz", check_positive("sample_rate_hz", self.sample_rate_hz)
            )


@dataclass
class SweepResult:
    """Runs of a sweep (:func:`sweep_result`; dicts, JSON-ready) and the settings."""

    settings: SweepSettings
    points: list[dict[str, float]]
    runs: list[dict[str, Any]]
    references: list[dict[str, Any]]
    wall_time_s: float = 0.0
    figures: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        settings = asdict(self.settings)
        if settings.get("sample_rate_hz") is None:
            settings["note"] = "sample_rate_hz null: a continuous rig computer, as the paper's"
        return {
            "settings": settings,
            "points": self.points,
            "references": [run_json(r) for r in self.references],
            "runs": [run_json(r) for r in self.runs],
            "summary": summarize(self),
            "checks": checks(self),
            "figures": self.figures,
            "wall_time_s": self.wall_time_s,
        }


def sweep_points(tables: dict[str, Any] | None = None, quick: bool = False) -> list[dict]:
    """The distinct rows of Table 2 (paper units, without the CoR column);
    ``quick``: the Table 1 point only."""
    from hybridtable.studies.paper import load_tables, table2_rows

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


#: What every run of the campaign measures (metric names of :mod:`hybridtable.sweeps`).
RUN_METRICS = ("cor", "peak_force_n", "v_in_m_per_s", "v_out_m_per_s", "energy_created")

#: What tells the runs apart in the results, beside their sweep inputs.
_LABELS: tuple[str, ...] = ("point", "scenario", "compensator", "prior_ratio", "passivity")


def _point_inputs(row: dict[str, float]) -> dict[str, float]:
    """The sweep inputs of a Table 2 row (paper units) in SI units, converted as
    :func:`~hybridtable.studies.paper.table2_params` converts them."""
    return {
        "sensor_delay_s": row["sensor_delay_ms"] * 1e-3,
        "table_response_hz": row["table_response_hz"],
        "contact_frequency_hz": row["contact_frequency_hz"],
        "contact_stiffness_n_per_m": row["contact_stiffness_n_per_mm"] * 1e3,
        "initial_velocity_m_per_s": row["initial_velocity_mm_per_s"] * 1e-3,
    }


def _noise_levels(row: dict[str, float]) -> tuple[float, float]:
    """Undamped peak force v0 sqrt(k m) [N] and peak deflection v0 / omega [m]
    of a Table 2 row."""
    from hybridtable.studies.paper import table2_params

    params = table2_params(row)
    k, m = params.contact_stiffness_n_per_m, params.spacecraft_mass_kg
    v0 = params.initial_velocity_m_per_s
    return v0 * math.sqrt(k * m), v0 / math.sqrt(k / m)


def reference_inputs(row: dict[str, float], damped: bool, settings: SweepSettings) -> dict:
    """The sweep inputs of the reference run of a grid point: the same contact
    (damped: damping ratio ``settings.contact_damping_ratio``) through an ideal
    loop (continuous rig computer, no delay, ideal table, no compensation)."""
    return {
        **_point_inputs(row),
        "sensor_delay_s": 0.0,
        "table_response_hz": math.inf,
        "compensator": "none",
        "contact_damping_ratio": settings.contact_damping_ratio if damped else 0.0,
    }


def case_inputs(
    row: dict[str, float],
    scenario: str,
    compensator: str,
    prior_ratio: float,
    passivity: bool,
    settings: SweepSettings,
    noise_levels: tuple[float, float] | None = None,
) -> dict:
    """The sweep inputs of one run: a grid point (a Table 2 row, paper units),
    its scenario, the compensator, the believed / true stiffness and the guard.

    The noise scenario's deviations are in N and m (``force_noise_ratio`` of
    the undamped peak force, ``position_noise_ratio`` of the peak deflection:
    ``noise_levels`` [N, m], computed when not given), its force deadband
    ``deadband_sigmas`` force deviations. Every run has the same keys
    (``sample_rate_hz`` when the settings have one).
    """
    force_n = position_m = deadband_n = 0.0
    if scenario == "noise":
        f0, x0 = noise_levels if noise_levels is not None else _noise_levels(row)
        force_n = settings.force_noise_ratio * f0
        position_m = settings.position_noise_ratio * x0
        deadband_n = settings.deadband_sigmas * force_n
    inputs = {
        **_point_inputs(row),
        "compensator": compensator,
        "compensator_stiffness_ratio": prior_ratio,
        "compensator_damping_n_s_per_m": 0.0,
        "contact_damping_ratio": settings.contact_damping_ratio if scenario == "damped" else 0.0,
        "force_noise_n": force_n,
        "position_noise_m": position_m,
        "force_deadband_n": deadband_n,
        "passivity": passivity,
    }
    if settings.sample_rate_hz is not None:
        inputs["sample_rate_hz"] = settings.sample_rate_hz
    return inputs


def sweep_runs(
    settings: SweepSettings, points: Sequence[dict[str, float]]
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The campaign's runs: the references and the cases, in run order.

    Each run is a dict of ``point``, ``scenario``, ``compensator``
    (``"ideal"`` for a reference), ``prior_ratio``, ``passivity`` and
    ``inputs``: its sweep inputs (:func:`reference_inputs`,
    :func:`case_inputs`). The references (one per point, and one more with the
    damped contact when the ``damped`` scenario runs) need a continuous loop,
    the cases may be sampled: they are two campaigns.
    """
    damped = (False, True) if "damped" in settings.scenarios else (False,)
    references = [
        _labelled(
            (i, "damped" if d else "mismatch", "ideal", 1.0, False),
            reference_inputs(row, d, settings),
        )
        for i, row in enumerate(points)
        for d in damped
    ]
    ratios = {
        "mismatch": settings.prior_ratios,
        "noise": settings.noise_prior_ratios,
        "damped": settings.damped_prior_ratios,
    }
    cases = []
    for i, row in enumerate(points):
        levels = _noise_levels(row) if "noise" in settings.scenarios else None
        for scenario in settings.scenarios:
            for comp in settings.compensators:
                for ratio in (1.0,) if comp in STIFFNESS_FREE else ratios[scenario]:
                    for guard in settings.passivity:
                        labels = (i, scenario, comp, ratio, guard)
                        inputs = case_inputs(row, scenario, comp, ratio, guard, settings, levels)
                        cases.append(_labelled(labels, inputs))
    return references, cases


def _labelled(labels: tuple, inputs: dict[str, Any]) -> dict[str, Any]:
    return {**dict(zip(_LABELS, labels, strict=True)), "inputs": inputs}


def _run_of(run: dict[str, Any], row: dict[str, Any]) -> dict[str, Any]:
    """A run's labels, ``error`` (None when it finished) and metrics, from its
    row of the campaign (NaN metrics when it did not finish)."""
    out = {k: run[k] for k in _LABELS}
    out["error"] = None if row["status"] == "ok" else (row["message"] or row["status"])
    for name in RUN_METRICS:
        value = row.get(name)
        out[name] = math.nan if value is None or out["error"] else float(value)
    return out


def sweep_result(
    settings: SweepSettings,
    points: Sequence[dict[str, float]],
    references: Sequence[dict[str, Any]],
    cases: Sequence[dict[str, Any]],
    reference_rows: Sequence[dict[str, Any]],
    case_rows: Sequence[dict[str, Any]],
    wall_time_s: float = 0.0,
) -> SweepResult:
    """The :class:`SweepResult` of the campaign's rows.

    Parameters
    ----------
    settings, points
        What :func:`sweep_runs` was given.
    references, cases
        What it returned.
    reference_rows, case_rows
        The campaigns' rows (``run`` = the index in ``references`` and
        ``cases``; ``status``, ``message`` and the :data:`RUN_METRICS`).
    wall_time_s : float
        The campaign's wall time [s].

    Raises
    ------
    ValueError
        If a run has no row (a campaign stopped before its end).
    """
    refs = _matched(references, reference_rows)
    runs = _matched(cases, case_rows)
    ref_by = {(r["point"], r["scenario"] == "damped"): r for r in refs}
    for r in runs:
        ref = ref_by[(r["point"], r["scenario"] == "damped")]
        r["cor_reference"] = ref["cor"]
        r["cor_error"] = r["cor"] - ref["cor"]
        r["peak_force_error"] = r["peak_force_n"] / ref["peak_force_n"] - 1.0
        r["energy_drift"] = r["cor"] ** 2 - ref["cor"] ** 2
    return SweepResult(settings, list(points), runs, refs, wall_time_s=wall_time_s)


def _matched(runs: Sequence[dict[str, Any]], rows: Sequence[dict[str, Any]]) -> list[dict]:
    by_run = {int(row["run"]): row for row in rows}
    missing = [i for i in range(len(runs)) if i not in by_run]
    if missing:
        raise ValueError(
            f"{len(missing)} of {len(runs)} runs have no result (first: run {missing[0]})"
        )
    return [_run_of(run, by_run[i]) for i, run in enumerate(runs)]


def _key(r: dict[str, Any]) -> str:
    return r["compensator"] + (" +passivity" if r["passivity"] else "")


def _max_abs(values: list[float]) -> float:
    arr = np.asarray(values, dtype=float)
    return math.nan if not arr.size else math.inf if np.isnan(arr).any() else np.abs(arr).max()


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
            if scen[name]["failed"] or not nominal:
                scen[name]["note"] = "inf: a run failed; nan: no run at the true stiffness"
        out[key] = scen
    return out


def checks(result: SweepResult) -> dict[str, Any]:
    """What the sweep shows of the online identification, the passivity guard
    and fixed-k SDMDC with a wrong stiffness.

    - ``sdmdc_online``: every unguarded ``sdmdc-online`` run of the
      ``mismatch`` scenario within :data:`ONLINE_COR_TOLERANCE` of the
      reference CoR (``passed``);
    - ``passivity``: no guarded run ends with CoR above
      :data:`PASSIVITY_MAX_COR` (a failed guarded run breaks it);
    - ``fixed_k_sdmdc_at_half_k``: fixed-k SDMDC's CoR error at prior ratio
      0.5 (shown, nothing to hold).
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
            **({} if online else {"note": "no sdmdc-online run in this sweep"}),
        },
        "passivity": {
            "runs": len(guarded),
            "max_cor": None if worst is None else worst["cor"],
            "worst_case": None
            if worst is None
            else {k: worst[k] for k in ("point", "scenario", "compensator", "prior_ratio")},
            "limit": PASSIVITY_MAX_COR,
            "passed": bool(guarded) and guarded_ok,
            **({} if guarded else {"note": "no run with the passivity guard in this sweep"}),
        },
        "fixed_k_sdmdc_at_half_k": half,
        "sdmdc_online_at_half_k": online_half,
    }
    return out
