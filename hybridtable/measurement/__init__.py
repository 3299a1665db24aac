"""Recorded runs and the model against them.

- :mod:`~hybridtable.measurement.run_format`: the ``hybridtable-run/1`` format
  (:class:`Run`, :class:`RunInfo`);
- :mod:`~hybridtable.measurement.run_reader`: read and validate runs in that
  format (:func:`read_runs`);
- :mod:`~hybridtable.measurement.rig`: the rig model of a run (:class:`RigPhysics`);
- :mod:`~hybridtable.measurement.replay`: the physical part driven by the recorded command;
- :mod:`~hybridtable.measurement.comparison`: replay and closed loop against the
  record (:func:`compare_run`), built from
  :mod:`~hybridtable.measurement.phases` (contact phases, CoR, loop energy),
  :mod:`~hybridtable.measurement.stats` (errors, noise floor, whiteness) and
  :mod:`~hybridtable.measurement.noise_model` (AR(1) noise models, prewhitening).
"""

from hybridtable.measurement.comparison import RunComparison, check_comparable, compare_run
from hybridtable.measurement.noise_model import NoiseModel, estimate_noise, whiten
from hybridtable.measurement.replay import ReplayResult, replay
from hybridtable.measurement.rig import RigPhysics, rig_params, simulate_rig
from hybridtable.measurement.run_format import Run, RunInfo
from hybridtable.measurement.run_reader import read_run, read_runs

__all__ = [
    "NoiseModel",
    "ReplayResult",
    "RigPhysics",
    "Run",
    "RunComparison",
    "RunInfo",
    "check_comparable",
    "compare_run",
    "estimate_noise",
    "read_run",
    "read_runs",
    "replay",
    "rig_params",
    "simulate_rig",
    "whiten",
]
