"""The runs of a campaign (:class:`SweepSpec`): which inputs run ``i`` gets.

The runs are every point x every sample x every grid cell (the last grid axis,
then ``compensators``, varying fastest). Each Monte Carlo sample is drawn once
and run at every point and cell, so compensators are compared on the same
draws. Run ``i``'s draws come from the seed and the sample's index, its own
seed (noise) from the seed and ``i``: no result depends on the worker, the
number of workers or the order of completion. :mod:`.spec` reads a spec file
into a :class:`SweepSpec`.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hybridtable.sweeps.distributions import Distribution
from hybridtable.sweeps.metrics import DEFAULT_METRICS, MARGINS, METRICS, SIMULATION

__all__ = ["SPEC_FORMAT", "ENGINES", "MAX_RUNS", "RunInputs", "SweepSpec", "input_for"]

#: The format name a spec may state (``format = "hybridtable-sweep/1"``).
SPEC_FORMAT = "hybridtable-sweep/1"

#: How a run is simulated: ``diagram`` (the Drake diagram, the model of
#: record), ``fast`` (the exact discrete update, :mod:`hybridtable.loop.fast`,
#: refused per run where it does not apply), ``auto`` (fast where it applies).
ENGINES: tuple[str, ...] = ("auto", "diagram", "fast")

#: The most runs one spec may hold.
MAX_RUNS = 10_000_000


def input_for(name: str, loop: str | None):
    """The :class:`~.inputs.Input` called ``name`` in ``loop``: the 1-D loop's
    (:func:`~.inputs.input_of`), the 6-DoF loop's
    (:func:`~.docking.docking_inputs`), or for ``loop=None`` either, the 1-D
    loop's first (a column's label). None if there is none."""
    from hybridtable.sweeps.inputs import INPUTS, input_of

    if loop == "six_dof" or (loop is None and name not in INPUTS and "." not in name):
        from hybridtable.sweeps.docking import docking_inputs

        return docking_inputs().get(name)
    return input_of(name)


@dataclass(frozen=True)
class RunInputs:
    """The inputs of run ``index``.

    Attributes
    ----------
    index : int
        The run's position in the campaign (0-based).
    point, sample : int
        Its explicit point and Monte Carlo sample.
    seed : int
        Its own seed (noise), from the spec's seed and ``index``.
    values : dict
        Every input the spec gives it (base, point, grid cell, draws).
    """

    index: int
    point: int
    sample: int
    seed: int
    values: dict[str, Any]


@dataclass(frozen=True)
class SweepSpec:
    """A parsed and checked spec (see the module docstring).

    Attributes
    ----------
    name, description : str
    seed : int
    engine : str
        One of :data:`ENGINES`.
    metrics : tuple of str
        Names in :data:`~hybridtable.sweeps.metrics.METRICS`.
    base : tuple of (name, value)
    grid : tuple of (name, tuple of values)
        The axes, slowest first.
    points : tuple of tuple of (name, value)
    samples : int
        Monte Carlo samples (1: none).
    draws : tuple of (name, Distribution)
    model : dict or None
        The model file's JSON (``hybridtable-model/1``), carried to the workers.
    model_path : str or None
        Where it was read from (for reports).
    pade_order : int
        Pade order of the continuous linear model (margin metrics).
    scenario : dict or None
        A 6-DoF scenario's TOML (``scenario = "FILE.toml"``): the campaign runs
        the docking loop (:mod:`.docking`) with it as every run's base.
    scenario_path : str or None
        Where it was read from (for reports).
    source : str
        The spec file, for messages.
    """

    name: str
    seed: int = 0
    engine: str = "auto"
    metrics: tuple[str, ...] = DEFAULT_METRICS
    base: tuple[tuple[str, Any], ...] = ()
    grid: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    points: tuple[tuple[tuple[str, Any], ...], ...] = ((),)
    samples: int = 1
    draws: tuple[tuple[str, Distribution], ...] = ()
    model: dict[str, Any] | None = None
    model_path: str | None = None
    pade_order: int = 3
    description: str = ""
    scenario: dict[str, Any] | None = None
    scenario_path: str | None = None
    source: str = field(default="<spec>", compare=False)

    @property
    def loop(self) -> str:
        """The loop the runs simulate (:data:`~.metrics.LOOPS`): ``six_dof``
        with a scenario, else ``1d``."""
        return "1d" if self.scenario is None else "six_dof"

    def input(self, name: str):
        """The :class:`~.inputs.Input` called ``name`` in this spec's loop
        (None: the loop has none)."""
        return input_for(name, self.loop)

    # -- the runs ----------------------------------------------------------
    @property
    def cells(self) -> int:
        """Grid cells (1 without a grid)."""
        return math.prod(len(v) for _, v in self.grid)

    @property
    def n_runs(self) -> int:
        """Runs in the campaign."""
        return len(self.points) * self.samples * self.cells

    @property
    def swept(self) -> tuple[str, ...]:
        """The inputs that vary between runs, in column order: the points'
        keys, the grid axes, the drawn inputs."""
        names = [k for k, _ in self.points[0]]
        names += [k for k, _ in self.grid]
        names += [k for k, _ in self.draws]
        return tuple(names)

    @property
    def needs_simulation(self) -> bool:
        return any(METRICS[m].source == SIMULATION for m in self.metrics)

    @property
    def needs_margins(self) -> bool:
        return any(METRICS[m].source == MARGINS for m in self.metrics)

    def run_inputs(self, index: int) -> RunInputs:
        """The inputs of run ``index`` (0 <= index < :attr:`n_runs`)."""
        if not 0 <= index < self.n_runs:
            raise IndexError(f"run {index} is not in 0..{self.n_runs - 1}")
        rest, cell = divmod(index, self.cells)
        point, sample = divmod(rest, self.samples)
        values: dict[str, Any] = dict(self.base)
        values.update(self.points[point])
        for name, axis in reversed(self.grid):
            cell, i = divmod(cell, len(axis))
            values[name] = axis[i]
        if self.draws:
            rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(0, sample)))
            for name, dist in self.draws:
                values[name] = dist.draw(rng)
        seed = int(np.random.SeedSequence(self.seed, spawn_key=(1, index)).generate_state(1)[0])
        return RunInputs(index, point, sample, seed, values)

    # -- identity ----------------------------------------------------------
    def to_json(self) -> dict[str, Any]:
        """The spec as JSON (what the Parquet file's metadata holds)."""
        out = {
            "format": SPEC_FORMAT,
            "name": self.name,
            "description": self.description,
            "seed": self.seed,
            "engine": self.engine,
            "metrics": list(self.metrics),
            "base": {k: _json_value(v) for k, v in self.base},
            "grid": {k: [_json_value(x) for x in v] for k, v in self.grid},
            "points": [{k: _json_value(v) for k, v in p} for p in self.points],
            "samples": self.samples,
            "draws": {k: d.to_json() for k, d in self.draws},
            "model": self.model,
            "model_path": self.model_path,
            "pade_order": self.pade_order,
            "n_runs": self.n_runs,
        }
        if self.scenario is not None:  # a 1-D spec's JSON (and fingerprint) as before
            out["scenario"] = self.scenario
            out["scenario_path"] = self.scenario_path
        return out

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of what decides the results (the
        runs, the metrics, the engine, the model), not of the file's text."""
        d = self.to_json()
        for key in ("name", "description", "model_path", "scenario_path"):
            d.pop(key, None)
        text = json.dumps(d, sort_keys=True, allow_nan=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def _json_value(v: Any) -> Any:
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    return v
