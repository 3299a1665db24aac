"""Record runs of a modelled rig: ``hybridtable-run/1`` files made by the model.

:func:`record_run` runs the closed loop of a rig (the rig computer exactly as
the run format defines it, the physical part of a
:class:`~hybridtable.measurement.rig.RigPhysics`, i.e. the nominal model or the
model with hidden effects) with measurement noise the computer reads
(:class:`~hybridtable.systems.noise.MeasurementNoiseParams`, white or AR(1)),
and returns the :class:`~hybridtable.measurement.run_format.Run` a data logger
would have written: the readings with their noise, the compensated force the
computer computed from them, the command it sent. The run's JSON holds the
nominal parameters only: what was hidden is the caller's to keep
(``simulate --record`` writes it to ``truth.json``).

:func:`write_run` writes a run as its CSV and JSON pair (every float in its
shortest exact form, so a run read back is bit-identical).

Users rehearse ``diagnose`` on such runs; the tests of ``diagnose`` use an
independent generator instead (``tests/generators/``), so that the method is
never checked against its own model's code.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from hybridtable._files import write_text_atomic
from hybridtable.errors import CommandError, ParameterError, SimulationError
from hybridtable.measurement.phases import record_cor
from hybridtable.measurement.rig import RigPhysics, simulate_rig
from hybridtable.measurement.run_format import FORMAT, RUN_COLUMNS, RUN_KEYS, Run, RunInfo
from hybridtable.systems.noise import MeasurementNoiseParams, noise_series

__all__ = [
    "FORMAT_COMPENSATORS",
    "default_duration_s",
    "record_run",
    "write_run",
    "run_files",
]

#: The compensators the run format's rig computer knows.
FORMAT_COMPENSATORS: tuple[str, ...] = ("none", "SDC", "MDC", "SDMDC")


def default_duration_s(info: RunInfo) -> float:
    """Approach, one undamped contact and two more contact durations of free
    flight (s): ``gap / v + 3 pi sqrt(m / k)``, at least 50 ticks."""
    contact = math.pi * math.sqrt(info.spacecraft_mass_kg / info.contact_stiffness_n_per_m)
    approach = info.initial_gap_m / info.initial_velocity_m_per_s
    return max(approach + 3.0 * contact, 50.0 * info.sample_period_s)


def record_run(
    info: RunInfo,
    physics: RigPhysics | None = None,
    noise: MeasurementNoiseParams | None = None,
    duration_s: float | None = None,
) -> tuple[Run, dict]:
    """Simulate one run of the rig of ``info`` and return it as recorded.

    Parameters
    ----------
    info : RunInfo
        The nominal parameters (the run's JSON); the compensator is one of
        :data:`FORMAT_COMPENSATORS`.
    physics : RigPhysics, optional
        The rig's physics (default: nominal): the hidden effects.
    noise : MeasurementNoiseParams, optional
        Noise of the force and position readings (default: none).
    duration_s : float, optional
        Length of the record (default: :func:`default_duration_s`).

    Returns
    -------
    run : Run
        The record (rows at ticks ``0 .. n - 1``).
    truth : dict
        What the record does not show: the noise-free contact force's CoR
        (``cor``), ``peak_force_n`` of the actual contact force, ``ticks``.

    Raises
    ------
    ParameterError
        For a compensator the format does not know, or a duration that does
        not hold the contact.
    SimulationError
        If the model diverges, never touches, or is still in contact at the
        end of the record.
    """
    if info.compensator not in FORMAT_COMPENSATORS:
        raise ParameterError(
            f"compensator {info.compensator!r}: a recorded run's computer is one of "
            f"{', '.join(FORMAT_COMPENSATORS)} (the run format's)"
        )
    duration = default_duration_s(info) if duration_s is None else float(duration_s)
    if not (math.isfinite(duration) and duration > 0.0):
        raise ParameterError(f"duration_s must be > 0 (got {duration_s})")
    h = info.sample_period_s
    n = int(math.floor(duration / h + 1e-9)) + 1
    if n < 3:
        raise ParameterError(f"duration_s {duration} s holds fewer than 3 ticks of {h} s")
    time_s = h * np.arange(n)
    empty = np.zeros(n)
    frame = Run(info, time_s, empty, empty, empty, empty, empty)
    result = simulate_rig(frame, physics, noise=noise)
    f_mea = np.array(result.f_mea_n, dtype=float)
    p_act = np.array(result.p_act_m, dtype=float)
    if noise is not None:
        f_mea = f_mea + noise_series(noise, "force", n)
        p_act = p_act + noise_series(noise, "position", n)
    run = Run(
        info=info,
        time_s=time_s,
        p_des_m=np.array(result.p_des_m, dtype=float),
        p_act_m=p_act,
        f_mea_n=f_mea,
        f_comp_n=np.array(result.f_comp_n, dtype=float),
        v_des_m_per_s=np.array(result.v_des_m_per_s, dtype=float),
    )
    f_act = np.asarray(result.f_act_n, dtype=float)
    if not np.any(f_act > 0.0):
        raise SimulationError(f"run {info.run_id}: no contact within {duration:.4g} s")
    if f_act[-1] > 0.0:
        raise SimulationError(
            f"run {info.run_id}: still in contact at the end of the record "
            f"({duration:.4g} s); give a longer duration"
        )
    try:
        cor = record_cor(run)[0]
    except ValueError as err:
        raise SimulationError(f"run {info.run_id}: {err}") from None
    return run, {"cor": cor, "peak_force_n": float(f_act.max()), "ticks": n}


def run_files(folder: str | Path, stem: str) -> tuple[Path, Path]:
    """The CSV and JSON paths of run ``stem`` in ``folder``."""
    folder = Path(folder)
    return folder / f"{stem}.csv", folder / f"{stem}.json"


def write_run(run: Run, folder: str | Path, stem: str, force: bool = False) -> Run:
    """Write ``run`` as ``folder/stem.csv`` and ``folder/stem.json``
    (``hybridtable-run/1``); return it with its paths set.

    Raises
    ------
    CommandError
        If a file exists and ``force`` is false (nothing is written then).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    csv_path, json_path = run_files(folder, stem)
    if not force:
        for path in (csv_path, json_path):
            if path.exists():
                raise CommandError(f"{path} exists; not replacing it without --force")
    columns = run.columns()
    lines = [",".join(RUN_COLUMNS)]
    for row in zip(*(columns[c] for c in RUN_COLUMNS), strict=True):
        lines.append(",".join(repr(float(x)) for x in row))
    info = run.info.to_dict()
    info["format"] = FORMAT
    assert set(info) == set(RUN_KEYS)
    write_text_atomic(csv_path, "\n".join(lines) + "\n")
    write_text_atomic(json_path, json.dumps(info, indent=2) + "\n")
    return replace(run, csv_path=csv_path, json_path=json_path)
