"""The run that would tell two models of a six-axis rig apart: ``diagnose``'s
separating run for 6-DoF runs (the 1-D one is
:func:`~hybridtable.diagnosis.design.separating_run`; both pick by the effect
core's :func:`~hybridtable.effects.selection.most_separating`).

Two models that fit the recorded runs equally well (look-alikes: a series
compliance and a softer spring, a table's damping and its response) may
still predict another run differently. Each candidate run (:data:`DESIGNS`)
is the first recorded run's scenario with one thing an operator can change:
the approach speed, the spacecraft's mass (a number in the rig computer), the
approach's pitch, or the compensator switched off. Model A's closed loop
(:func:`~hybridtable.six_dof.simulation.simulate6` through its physical part,
without noise) gives the run's commands, which both models replay
(:func:`~hybridtable.six_dof.compare6.replay_residuals`), as ``diagnose``
would replay a run recorded on a rig that is A. Their distance is
``sqrt(sum (dy / sigma)^2)`` over every component of every tick, ``sigma``
each component's noise level on the recorded runs (their mean); on a rig
whose noise is that, the information criterion prefers the right model by
about that distance squared, so a run separates them when it exceeds
:data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`, and independent runs
add their squares (``runs_needed``). Two models that are one law on this rig
(a compliance in series with a linear spring and the softer spring) are no
distance apart on any run, and the answer says that none separates them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from hybridtable.diagnosis.settings import BIC_THRESHOLD
from hybridtable.effects.selection import most_separating, scaled_runs
from hybridtable.errors import DivergenceError, ParameterError, SimulationError
from hybridtable.six_dof.compare6 import noise_levels_of, replay_residuals
from hybridtable.six_dof.fit6 import Fit6
from hybridtable.six_dof.run6 import Run6, run6_of_docking
from hybridtable.six_dof.simulation import expected_end_s, simulate6

__all__ = [
    "DESIGNS",
    "PITCH_STEP_RAD",
    "candidate_runs",
    "design_distance",
    "mean_levels",
    "separating_run6",
    "separation",
    "try_distance",
]

#: The pitch a candidate run adds to the approach's (2 degrees).
PITCH_STEP_RAD = math.radians(2.0)


def _pitched(runs: Sequence[Run6]) -> dict:
    roll, pitch = runs[0].params.approach.misalignment_rad
    return {"misalignment_rad": (roll, pitch + PITCH_STEP_RAD)}


def _unchanged_compensator(runs: Sequence[Run6]) -> bool:
    return runs[0].params.compensator == "none"


#: Candidate runs: (words, the recorded runs -> changes of the first run's
#: scenario by flat name, :attr:`~hybridtable.six_dof.params.DockingLoopParams.FIELDS`,
#: or None where the run is no change).
DESIGNS: tuple[tuple[str, Callable[[Sequence[Run6]], dict | None]], ...] = (
    # the 1-D diagnose's (the effect core's), then pitch and the compensator
    *scaled_runs(lambda run, name: getattr(run.params, name)),
    ("2 degrees more pitch in the approach", _pitched),
    (
        "the compensator off",
        lambda r: None if _unchanged_compensator(r) else {"compensator": "none"},
    ),
)


def candidate_runs(runs: Sequence[Run6]) -> list[tuple[str, dict]]:
    """The candidate runs of :data:`DESIGNS` for ``runs``: (words, changes)."""
    return [(words, changes) for words, of in DESIGNS if (changes := of(runs)) is not None]


def design_distance(
    runs: Sequence[Run6], a: Fit6, b: Fit6, changes: dict, levels: dict | None = None
) -> float:
    """The distance (noise levels, see the module) between models ``a`` and
    ``b`` on the first run's scenario with ``changes`` (flat names), the
    run's commands from ``a``'s closed loop; ``levels``: each measured
    block's noise levels (default: the mean of the runs').

    Raises
    ------
    SimulationError, ParameterError
        If the run cannot be made or replayed on this rig.
    """
    levels = mean_levels(runs) if levels is None else levels
    first = runs[0]
    params = first.params.without_noise(**changes, duration_s=None)
    try:
        loop = simulate6(params, physics=a.physics)
    except DivergenceError:
        raise
    except SimulationError:  # a contact that does not end by itself (a reading held
        # above the dead band by a bias): the run as long as one is expected to be
        params = params.with_(duration_s=expected_end_s(params))
        loop = simulate6(params, physics=a.physics)
    design = replace(run6_of_docking(loop, f"{first.run_id}-design", first.scenario), params=params)
    da = replay_residuals(design, a.physics, levels)
    db = replay_residuals(design, b.physics, levels)
    return float(np.linalg.norm(db - da))


def mean_levels(runs: Sequence[Run6]) -> dict[str, np.ndarray]:
    """Each measured block's noise levels, the mean over ``runs``."""
    each = [noise_levels_of(r) for r in runs]
    return {k: np.mean([e[k] for e in each], axis=0) for k in each[0]}


def try_distance(
    runs: Sequence[Run6], a: Fit6, b: Fit6, changes: dict, levels: dict
) -> float | None:
    """:func:`design_distance`, or None where the run cannot be made or
    replayed on this rig (a candidate passed over)."""
    try:
        return design_distance(runs, a, b, changes, levels)
    except (SimulationError, ParameterError, ValueError):
        return None


def separating_run6(runs: Sequence[Run6], a: Fit6, b: Fit6) -> dict | None:
    """Of :data:`DESIGNS`, the run on which the fitted models ``a`` and ``b``
    differ most (see the module), or None if none could be simulated
    (:func:`separation` of each candidate's :func:`try_distance`)."""
    levels = mean_levels(runs)
    designs = candidate_runs(runs)
    distances = {words: try_distance(runs, a, b, changes, levels) for words, changes in designs}
    return separation(a, b, designs, distances)


def separation(
    a: Fit6, b: Fit6, designs: Sequence[tuple[str, dict]], distances: dict[str, float | None]
) -> dict | None:
    """The separating run of models ``a`` and ``b`` from each candidate's
    distance (words -> noise levels; None: passed over), or None if no
    candidate ran. Returns ``run`` (words), ``changes`` (flat names),
    ``distance`` and ``recorded_distance`` (the two models' replays of the
    recorded runs apart, noise levels), ``separates`` (one such run's squared
    distance exceeds :data:`~hybridtable.diagnosis.settings.BIC_THRESHOLD`)
    and ``runs_needed`` (how many such runs would; None: the models agree)."""
    best = most_separating(designs, lambda d: distances[d[0]], BIC_THRESHOLD)
    if best is None:
        return None
    out = best.to_dict(float(np.linalg.norm(b.residuals - a.residuals)))
    out["changes"] = {k: list(v) if isinstance(v, tuple) else v for k, v in out["changes"].items()}
    return out
