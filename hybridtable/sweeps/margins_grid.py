"""The margins grid as a campaign: sensor delay x table frequency x
compensator, the margin metrics of each point's linear model.

``hybridtable margins`` runs its grid here: a spec (:func:`margins_spec`) whose
runs are the grid's points, run by the engine (in this process by default: a
point takes milliseconds, less than a cluster takes to start; on Dask with
``workers`` or ``scheduler``), and the rows turned into the per-compensator
arrays, critical curves and verification of
:func:`hybridtable.analysis.sweep.margins_from_rows`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

from hybridtable.analysis.sweep import GRID_FIELDS, SweepResult, margins_from_rows
from hybridtable.loop.params import HybridLoopParams
from hybridtable.sweeps.plan import SweepSpec

__all__ = ["MARGIN_METRICS", "margins_spec", "sweep_margins"]

#: The metrics of a grid point.
MARGIN_METRICS: tuple[str, ...] = ("stable", *GRID_FIELDS)

_AXES = ("sensor_delay_s", "table_response_hz", "compensator")


def margins_spec(
    base: HybridLoopParams,
    sensor_delay_s: Sequence[float],
    table_response_hz: Sequence[float],
    compensators: Sequence[str],
    pade_order: int = 3,
    model: dict[str, Any] | None = None,
) -> SweepSpec:
    """The campaign of a margins grid: ``base``'s parameters fixed, the axes
    swept (delay slowest, compensator fastest), :data:`MARGIN_METRICS`.

    Parameters
    ----------
    base : HybridLoopParams
    sensor_delay_s, table_response_hz : sequence of float
        The axes [s], [Hz] (``inf``: an ideal table).
    compensators : sequence of str
    pade_order : int
    model : dict, optional
        A model file's JSON: each point's linear model with its physics.
    """
    from hybridtable.sweeps.spec import parse_spec

    fixed = {k: v for k, v in base.quantities().items() if k not in _AXES and v is not None}
    raw: dict[str, Any] = {
        "name": "margins",
        "engine": "diagram",
        "metrics": list(MARGIN_METRICS),
        "pade_order": int(pade_order),
        "base": fixed,
        "grid": {
            "sensor_delay_s": [float(x) for x in sensor_delay_s],
            "table_response_hz": [float(x) for x in table_response_hz],
        },
        "compensators": list(compensators),
    }
    spec = parse_spec(raw, source="the margins grid")
    if model is not None:
        from dataclasses import replace

        spec = replace(spec, model=model, model_path="--model")
    return spec


def sweep_margins(
    base: HybridLoopParams,
    sensor_delay_s: Sequence[float],
    table_response_hz: Sequence[float],
    compensators: Sequence[str] = ("none", "SDC", "MDC", "SDMDC"),
    pade_order: int = 3,
    critical: bool = True,
    verify: bool = True,
    progress: bool = False,
    model=None,
    transform: Callable[[HybridLoopParams], HybridLoopParams] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
) -> SweepResult:
    """Margins of every compensator over the (delay, table frequency) grid.

    Parameters
    ----------
    base : HybridLoopParams
        Every other parameter. ``lead_time_s=None`` makes the lead follow the delay.
    sensor_delay_s, table_response_hz : sequence of float
        Grid axes [s], [Hz] (``inf`` allowed for an ideal table).
    compensators : sequence of str
        The paper's compensators.
    pade_order : int
        Pade order of the continuous model (ignored when sampled).
    critical, verify : bool
        As :func:`~hybridtable.analysis.sweep.margins_from_rows`.
    progress : bool
        A progress bar on stderr.
    model : RigModel, optional
        A rig model: each point's linear model has its physics
        (:func:`~hybridtable.studies.model_compensators.model_transform`).
    transform : callable, optional
        ``params -> params`` for the critical searches and the verification;
        default: the model's transform (or none).
    workers, scheduler : optional
        Run the points on Dask (a local cluster of ``workers`` processes, or
        the scheduler at ``scheduler``) instead of in this process.

    Raises
    ------
    ParameterError
        A compensator or parameter the linear models do not hold, or a point
        whose linear model could not be made.
    """
    from hybridtable.analysis.sweep import check_supported
    from hybridtable.sweeps.engine import run_campaign

    t0 = time.perf_counter()
    check_supported(base, compensators)
    if model is not None and transform is None:
        from hybridtable.studies.model_compensators import model_transform

        transform = model_transform(model)
    spec = margins_spec(
        base,
        sensor_delay_s,
        table_response_hz,
        compensators,
        pade_order,
        None if model is None else model.to_json(),
    )
    in_process = workers is None and scheduler is None
    campaign = run_campaign(
        spec,
        None,
        scheduler=scheduler,
        workers=workers,
        progress=progress,
        in_process=in_process,
    )
    return margins_from_rows(
        base,
        sensor_delay_s,
        table_response_hz,
        compensators,
        campaign.rows,
        pade_order=pade_order,
        critical=critical,
        verify=verify,
        transform=transform,
        wall_time_s=time.perf_counter() - t0,
    )
