"""Margins over a grid of sensor delays and table response frequencies.

For each compensator, every grid point ``(sensor_delay_s[i],
table_response_hz[j])`` gets the figures of :mod:`hybridtable.analysis.margins` from the
Drake-linearized model (continuous with a Pade delay, or sampled when the base
parameters have a sample rate): the points are the runs of a campaign
(:mod:`hybridtable.sweeps.margins_grid`), whose rows :func:`margins_from_rows`
turns into per-compensator arrays; every table frequency gets its critical
sensor delay and every delay its critical table frequency.
:mod:`hybridtable.analysis.validation` compares the predictions with the nonlinear
simulation.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.linearize import LinearLoop, linearization_notes
from hybridtable.analysis.margins import (
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.errors import ParameterError
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "GRID_FIELDS",
    "CompensatorSweep",
    "SweepResult",
    "ValidationPoint",
    "check_supported",
    "margins_from_rows",
    "model_function",
]

#: Per-grid-point arrays of a :class:`CompensatorSweep`.
GRID_FIELDS: tuple[str, ...] = (
    "predicted_cor",
    "phase_margin_deg",
    "damping_ratio",
    "effective_delay_s",
    "energy_growth_per_contact",
    "growth_rate_per_s",
    "crossover_rad_per_s",
)


@dataclass
class CompensatorSweep:
    """Grid results of one compensator; ``[i][j]`` at ``sensor_delay_s[i]``,
    ``table_response_hz[j]``.

    ``critical_delay_s[j]``: smallest unstable sensor delay at
    ``table_response_hz[j]`` (0: unstable at zero delay, inf: stable over the
    search). ``critical_table_hz[i]``: table frequency above which the loop is
    stable at ``sensor_delay_s[i]`` (inf: no table is fast enough, 0: stable
    over the search).
    """

    compensator: str
    predicted_cor: np.ndarray
    phase_margin_deg: np.ndarray
    damping_ratio: np.ndarray
    effective_delay_s: np.ndarray
    energy_growth_per_contact: np.ndarray
    growth_rate_per_s: np.ndarray
    crossover_rad_per_s: np.ndarray
    stable: np.ndarray
    critical_delay_s: np.ndarray
    critical_table_hz: np.ndarray

    def to_dict(self) -> dict:
        d = {name: getattr(self, name).tolist() for name in GRID_FIELDS}
        d["stable"] = self.stable.tolist()
        d["critical_delay_s"] = self.critical_delay_s.tolist()
        d["critical_table_hz"] = self.critical_table_hz.tolist()
        return d


@dataclass
class SweepResult:
    """Everything :func:`sweep_margins` computed."""

    base: HybridLoopParams
    sensor_delay_s: np.ndarray
    table_response_hz: np.ndarray
    pade_order: int | None
    compensators: dict[str, CompensatorSweep]
    verification_error: float | None = None
    wall_time_s: float = 0.0
    #: Filled by :func:`hybridtable.analysis.validation.validate_sweep`.
    validation: list[ValidationPoint] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: The ``transform`` of :func:`sweep_margins` (None: the grid's parameters
    #: as they are); :func:`hybridtable.analysis.validation.validate_sweep`
    #: applies it too. Not in the JSON document.
    transform: Callable[[HybridLoopParams], HybridLoopParams] | None = field(
        default=None, repr=False, compare=False
    )

    @property
    def sampled(self) -> bool:
        return self.base.sample_rate_hz is not None

    def max_validation_error(self) -> float | None:
        errs = [v.abs_error for v in self.validation if v.abs_error is not None]
        return max(errs) if errs else None

    def to_json_dict(self) -> dict:
        """The ``hybridtable margins --json`` document."""
        b = self.base
        return {
            "grid": {
                "sensor_delay_s": self.sensor_delay_s.tolist(),
                "table_response_hz": self.table_response_hz.tolist(),
            },
            "model": {
                "kind": "sampled" if self.sampled else "continuous",
                "pade_order": self.pade_order,
                **(
                    {"note": "pade_order null: a sampled-data model holds the delay exactly"}
                    if self.pade_order is None
                    else {}
                ),
                "sample_rate_hz": b.sample_rate_hz,
                "spacecraft_mass_kg": b.spacecraft_mass_kg,
                "contact_stiffness_n_per_m": b.contact_stiffness_n_per_m,
                "contact_damping_n_s_per_m": b.contact_damping_n_s_per_m,
                "contact_frequency_hz": b.contact_frequency_hz,
                "table_damping_ratio": b.table_damping_ratio,
                "lead_time_s": b.lead_time_s if b.lead_time_s is not None else "sensor_delay_s",
                "verification_error": self.verification_error,
            },
            "compensators": {name: cs.to_dict() for name, cs in self.compensators.items()},
            "validation": [v.to_dict() for v in self.validation],
            "max_validation_abs_error": self.max_validation_error(),
            "notes": list(self.notes),
            "wall_time_s": self.wall_time_s,
        }


def model_function(
    base: HybridLoopParams, pade_order: int = 3, linearizer: ContactLoopLinearizer | None = None
) -> tuple[Callable[[HybridLoopParams], LinearLoop], ContactLoopLinearizer]:
    """``params -> LinearLoop``: the sampled model when ``base`` has a sample
    rate, else the continuous Pade model. Returns it with the continuous
    linearizer (shared)."""
    lin = linearizer or ContactLoopLinearizer(pade_order)
    if base.sample_rate_hz is None:
        return lin.open_loop, lin
    return SampledLoopLinearizer(lin).open_loop, lin


def check_supported(params: HybridLoopParams, compensators: Sequence[str]) -> None:
    """Raise ParameterError unless the linear models hold ``compensators`` and
    ``params`` (the paper's four compensators, no passivity guard)."""
    for c in compensators:
        if c not in COMPENSATORS:
            raise ParameterError(
                f"the margins analysis models the paper's compensators "
                f"({', '.join(COMPENSATORS)}), not {c!r}"
            )
    if getattr(params, "passivity", False):
        raise ParameterError("the margins analysis does not model the passivity guard")


def margins_from_rows(
    base: HybridLoopParams,
    sensor_delay_s: Sequence[float],
    table_response_hz: Sequence[float],
    compensators: Sequence[str],
    rows: Sequence[dict],
    pade_order: int = 3,
    critical: bool = True,
    verify: bool = True,
    transform: Callable[[HybridLoopParams], HybridLoopParams] | None = None,
    wall_time_s: float = 0.0,
) -> SweepResult:
    """The :class:`SweepResult` of a margins campaign's rows.

    The grid's points are runs of a campaign (:mod:`hybridtable.sweeps`; the
    margins command and :func:`hybridtable.sweeps.margins_grid.sweep_margins`
    build it): ``rows`` are its rows in run order, sensor delay slowest,
    compensator fastest, with the margin metrics of :data:`GRID_FIELDS` and
    ``stable``. Here they become the per-compensator arrays; every table
    frequency gets its critical sensor delay and every delay its critical
    table frequency (1-D searches on the same linear model), and the
    block-assembled model is checked against a direct ``Linearize`` of the
    whole diagram at two grid points per compensator (``verify``).

    Parameters
    ----------
    base : HybridLoopParams
        Every other parameter (contact, table damping ratio, lead time, sample
        rate, ...). ``lead_time_s=None`` makes the lead follow the delay.
    sensor_delay_s, table_response_hz : sequence of float
        Grid axes (``inf`` allowed for an ideal table).
    compensators : sequence of str
    rows : sequence of dict
        The campaign's rows.
    pade_order : int
        Pade order of the continuous model (ignored when sampled).
    critical : bool
        Compute the critical delay / table frequency curves.
    verify : bool
        Compare the block-assembled continuous model with a direct ``Linearize``.
    transform : callable, optional
        ``params -> params``: what the linear model is built from at each
        point (a rig model's physics as the linear models see it), as the
        campaign's rows had it. The grid axes stay the parameters before it.
    wall_time_s : float
        The campaign's time, added to the searches'.

    Raises
    ------
    ParameterError
        If a grid point's linear model could not be made (its row's message).
    """
    t0 = time.perf_counter()
    check_supported(base, compensators)
    delays = np.asarray(sensor_delay_s, dtype=float)
    tables = np.asarray(table_response_hz, dtype=float)
    if delays.ndim != 1 or tables.ndim != 1 or delays.size == 0 or tables.size == 0:
        raise ParameterError("the grid needs at least one delay and one table frequency")
    nd, nt, nc = delays.size, tables.size, len(compensators)
    if len(rows) != nd * nt * nc:
        raise ParameterError(f"{len(rows)} rows for a grid of {nd} x {nt} x {nc} points")
    for row in rows:
        if row["status"] != "ok":
            raise ParameterError(row["message"])
    model, lin = model_function(base, pade_order)
    if transform is not None:
        bare_model = model

        def model(p: HybridLoopParams) -> LinearLoop:
            return bare_model(transform(p))

    sampled_lin = SampledLoopLinearizer(lin) if base.sample_rate_hz is not None else None
    growth = growth_of(model)
    notes: set[str] = set()
    verification = None
    out: dict[str, CompensatorSweep] = {}
    for c, comp in enumerate(compensators):
        cbase = base.with_(compensator=comp)
        arrays = {name: np.full((nd, nt), np.nan) for name in GRID_FIELDS}
        stable = np.zeros((nd, nt), dtype=bool)
        for i, T in enumerate(delays):
            for j, f in enumerate(tables):
                row = rows[(i * nt + j) * nc + c]
                if (row["sensor_delay_s"], row["table_response_hz"], row["compensator"]) != (
                    float(T),
                    float(f),
                    comp,
                ):
                    raise ParameterError(f"row {row['run']} is not grid point ({i}, {j}, {comp})")
                for name in GRID_FIELDS:
                    arrays[name][i, j] = row[name]
                stable[i, j] = bool(row["stable"])
                p = cbase.with_(sensor_delay_s=float(T), table_response_hz=float(f))
                notes.update(linearization_notes(p if transform is None else transform(p)))
        if verify:
            for i, j in {(0, 0), (nd // 2, nt // 2)}:
                p = cbase.with_(sensor_delay_s=float(delays[i]), table_response_hz=float(tables[j]))
                p = p if transform is None else transform(p)
                err = lin.verify(p) if sampled_lin is None else sampled_lin.verify(p)
                verification = err if verification is None else max(verification, err)
        crit_d = np.full(nt, np.nan)
        crit_f = np.full(nd, np.nan)
        if critical:
            max_delay = max(0.25 / base.contact_frequency_hz, float(delays.max()))
            for j, f in enumerate(tables):
                crit_d[j] = critical_sensor_delay(
                    growth, cbase.with_(table_response_hz=float(f)), max_delay_s=max_delay
                )
            for i, T in enumerate(delays):
                crit_f[i] = critical_table_frequency(growth, cbase.with_(sensor_delay_s=float(T)))
        out[comp] = CompensatorSweep(
            comp, **arrays, stable=stable, critical_delay_s=crit_d, critical_table_hz=crit_f
        )
    return SweepResult(
        base=base,
        sensor_delay_s=delays,
        table_response_hz=tables,
        pade_order=None if base.sample_rate_hz is not None else lin.pade_order,
        compensators=out,
        verification_error=verification,
        wall_time_s=wall_time_s + time.perf_counter() - t0,
        notes=sorted(notes),
        transform=transform,
    )


@dataclass(frozen=True)
class ValidationPoint:
    """Predicted against simulated CoR at one grid point.

    Attributes
    ----------
    compensator : str
    i, j : int
        Grid indices (delay, table frequency).
    sensor_delay_s, table_response_hz : float
    cor_linear : float
        Predicted CoR of the linear model used by the sweep.
    cor_sim : float or None
        CoR of :func:`hybridtable.loop.simulation.simulate` (None if it failed).
    abs_error : float or None
        ``|cor_linear - cor_sim|``.
    cor_exact_delay : float or None
        Predicted CoR with the exact delay (continuous models).
    cor_linear_transient : float or None
        Linear loop from the simulated onset state over the table's contact
        (computed when ``abs_error`` exceeds the threshold).
    cause : str or None
        ``"transient"`` or ``"gating and separation"``, the larger part of the
        error (see the module doc), when explained.
    error : str or None
        Why the simulation failed.
    """

    compensator: str
    i: int
    j: int
    sensor_delay_s: float
    table_response_hz: float
    cor_linear: float
    cor_sim: float | None
    abs_error: float | None
    cor_exact_delay: float | None = None
    cor_linear_transient: float | None = None
    cause: str | None = None
    error: str | None = None

    def to_dict(self) -> dict:
        out = asdict(self)
        why = []
        if self.cor_sim is None:
            why.append(f"cor_sim and abs_error null: the simulation failed ({self.error})")
        else:
            out["error"] = ""
        if self.cor_exact_delay is None:
            why.append("cor_exact_delay null: computed for continuous models only")
        if self.cor_linear_transient is None or self.cause is None:
            why.append(
                "cor_linear_transient and cause null: the linear and simulated CoRs agree "
                "within the threshold, so the difference is not split into its causes"
            )
        if why:
            out["note"] = "; ".join(why)
        return out
