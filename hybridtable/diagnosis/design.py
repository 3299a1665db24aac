"""Runs that would separate look-alike effects: simulate candidate experiments
and pick the one where the models differ most.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from hybridtable.diagnosis.evaluate import Evaluator
from hybridtable.diagnosis.settings import BIC_THRESHOLD, CHANNELS
from hybridtable.effects.selection import most_separating, scaled_runs
from hybridtable.effects.spec import ModelSpec
from hybridtable.errors import MeasurementError, SimulationError
from hybridtable.measurement.replay import replay_command
from hybridtable.measurement.rig import rig_params, simulate_rig
from hybridtable.measurement.run_format import Run

__all__ = [
    "separating_run",
]


# -- separating runs -----------------------------------------------------------
#: Candidate runs of :func:`separating_run`: (label, changes of the run's JSON),
#: the effect core's :data:`~hybridtable.effects.selection.SCALED_RUNS`.
DESIGNS: tuple[tuple[str, Callable[[Run], dict]], ...] = scaled_runs(
    lambda run, name: getattr(run.info, name)
)


def _design_run(run: Run, changes: dict) -> Run:
    info = replace(run.info, run_id=f"{run.run_id}-design", **changes)
    v = info.initial_velocity_m_per_s
    m, k = info.spacecraft_mass_kg, info.contact_stiffness_n_per_m
    duration = info.initial_gap_m / v + 1.6 * math.pi * math.sqrt(m / k) + 0.1
    h = info.sample_period_s
    n = int(math.ceil(duration / h)) + 1
    z = np.zeros(n)
    return Run(info, h * np.arange(n), z, z, z, z, z)


def separating_run(
    ev: Evaluator,
    spec_a: ModelSpec,
    spec_b: ModelSpec,
) -> dict | None:
    """The candidate run (:data:`DESIGNS`) on which two fitted models differ most.

    Each design is the first run with changed JSON values; model A's closed
    loop gives its command, which both models replay. The difference of the
    predictions in noise units, ``sqrt(sum (dy / sigma)^2)`` over ``f_mea``
    and ``p_act``, is compared with the same distance on the recorded runs.
    Returns the best design (label, changes, distances, ``separates``: the
    squared distance of one such run exceeds :data:`BIC_THRESHOLD`, and
    ``runs_needed``: how many such runs would), or None if no design could
    be simulated.
    """
    runs = [d.run for d in ev.data]
    sig = {c: float(np.mean([d.noise[c].sigma for d in ev.data])) for c in CHANNELS}

    def distance(pa, pb) -> float:
        return math.sqrt(sum(float(np.sum(((pa[c] - pb[c]) / sig[c]) ** 2)) for c in CHANNELS))

    recorded = 0.0
    for i in range(len(ev.data)):
        a = ev.evaluate(spec_a, i).prediction
        b = ev.evaluate(spec_b, i).prediction
        if np.isnan(a["f_mea_n"]).any() or np.isnan(b["f_mea_n"]).any():
            continue
        recorded += distance(a, b) ** 2
    recorded = math.sqrt(recorded)

    def predicted(design) -> float | None:
        label, changes = design
        try:
            run = _design_run(runs[0], changes)
            cl = simulate_rig(spec_a.closed_loop_run(run), spec_a.physics(), accuracy=ev.accuracy)
            params = rig_params(run.info)
            preds = []
            for spec in (spec_a, spec_b):
                rep = replay_command(
                    params, cl.p_des_m, cl.v_des_m_per_s, spec.physics(), accuracy=ev.accuracy
                )
                preds.append({"f_mea_n": rep.f_mea_n, "p_act_m": rep.p_act_m})
        except (SimulationError, MeasurementError, ValueError):
            return None
        ev.simulations += 3
        return distance(*preds)

    best = most_separating(
        [(label, changes_of(runs)) for label, changes_of in DESIGNS], predicted, BIC_THRESHOLD
    )
    if best is None:
        return None
    return best.to_dict(recorded)
