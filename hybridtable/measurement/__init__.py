"""Recorded runs and the model against them.

- :mod:`~hybridtable.measurement.run_format`: the ``hybridtable-run/1`` format
  (:class:`Run`, :class:`RunInfo`);
- :mod:`~hybridtable.measurement.run_reader`: read and validate runs in that
  format (:func:`read_runs`);
- :mod:`~hybridtable.measurement.rig`: the rig model of a run (:class:`RigPhysics`);
- :mod:`~hybridtable.measurement.recorder`: runs recorded from a modelled rig
  (``simulate --record``);
- :mod:`~hybridtable.measurement.replay`: the physical part driven by the recorded command;
- :mod:`~hybridtable.measurement.comparison`: replay and closed loop against the
  record (:func:`compare_run`), built from
  :mod:`~hybridtable.measurement.phases` (contact phases, CoR, loop energy),
  :mod:`~hybridtable.measurement.stats` (errors, noise floor, whiteness) and
  :mod:`~hybridtable.measurement.noise_model` (AR(1) noise models, prewhitening).
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "comparison": (
            "RunComparison",
            "check_comparable",
            "compare_run",
        ),
        "noise_model": (
            "NoiseModel",
            "estimate_noise",
            "whiten",
        ),
        "recorder": (
            "record_run",
            "write_run",
        ),
        "replay": (
            "ReplayResult",
            "replay",
        ),
        "rig": (
            "RigPhysics",
            "rig_params",
            "simulate_rig",
        ),
        "run_format": (
            "Run",
            "RunInfo",
        ),
        "run_reader": (
            "read_run",
            "read_runs",
        ),
    },
)
