"""The 6-DoF run format (``hybridtable-run6/1``, ``docs/run6-format.md``):
a recorded run of a six-axis docking rig, read with every check, and written
from a :class:`~hybridtable.six_dof.simulation.DockingRun`.

A run is a CSV of the rig computer's ticks (:data:`RUN6_COLUMNS`: the
commanded and the measured port pose, the model port's twist, the measured
and the compensated wrench) and a JSON of the scenario it ran with (a
``simulate6`` scenario file's sections). The CSV is read by the 1-D format's
reader (:func:`~hybridtable.measurement.run_reader.read_series`, with this
format's columns), so its defects are worded the same way; the 6-DoF checks
(unit quaternions of one sign, the rates' units against the poses' changes,
a contact in the record) are this module's.

Row ``k`` is tick ``k`` as the format defines it: what the computer read and
computed at the tick, and the model after its update. The diagram logs each
tick before its update (the table's pose and the sensor's reading the
computer reads, the compensated wrench it applies), so the model after tick
``k`` is the diagram's row ``k + 1``: :func:`run6_of_docking` takes the
commanded state one row later, as the 1-D loop's
:func:`~hybridtable.loop.simulation.collect_result` does.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hybridtable._files import read_user_json, regular_file_problem
from hybridtable.errors import MeasurementError, ParameterError
from hybridtable.measurement.channels import noise_level_of_differences
from hybridtable.measurement.log_layout import LogLayout
from hybridtable.measurement.run_files import find_run_files
from hybridtable.measurement.run_reader import check_time, check_unique_ids, read_series
from hybridtable.six_dof.metrics import DockingMetrics, docking_metrics
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.pose import (
    quaternion_product,
    quaternions_of_rotation_vectors,
    rotation_exp,
    rotation_vectors_of_quaternions,
)
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.six_dof.simulation import DockingRun, peak_force_n
from hybridtable.six_dof.touch import force_from_rest, touching

__all__ = [
    "FORMAT6",
    "BLOCKS",
    "RUN6_COLUMNS",
    "Run6",
    "run6_of_docking",
    "run6_csv_text",
    "run6_json",
    "read_run6",
    "read_runs6",
    "is_run6",
    "noise_levels",
]

#: Value of the JSON ``format`` key.
FORMAT6 = "hybridtable-run6/1"

#: The CSV's blocks: name -> (columns, SI unit, what it is, for messages).
BLOCKS: dict[str, tuple[tuple[str, ...], str, str]] = {
    "p_des": (("px_des_m", "py_des_m", "pz_des_m"), "m", "commanded port position"),
    "q_des": (("qw_des", "qx_des", "qy_des", "qz_des"), "1", "commanded port attitude"),
    "v_des": (
        ("vx_des_m_per_s", "vy_des_m_per_s", "vz_des_m_per_s"),
        "m/s",
        "model port's velocity",
    ),
    "w_des": (
        ("wx_des_rad_per_s", "wy_des_rad_per_s", "wz_des_rad_per_s"),
        "rad/s",
        "model port's angular velocity",
    ),
    "p_act": (("px_act_m", "py_act_m", "pz_act_m"), "m", "measured port position"),
    "q_act": (("qw_act", "qx_act", "qy_act", "qz_act"), "1", "measured port attitude"),
    "f_mea": (("fx_mea_n", "fy_mea_n", "fz_mea_n"), "N", "measured force"),
    "m_mea": (("mx_mea_n_m", "my_mea_n_m", "mz_mea_n_m"), "N m", "measured moment"),
    "f_comp": (("fx_comp_n", "fy_comp_n", "fz_comp_n"), "N", "compensated force"),
    "m_comp": (("mx_comp_n_m", "my_comp_n_m", "mz_comp_n_m"), "N m", "compensated moment"),
}

#: CSV columns of the format, in the format's order, with their SI units.
RUN6_COLUMNS: dict[str, str] = {
    "time_s": "s",
    **{c: unit for cols, unit, _ in BLOCKS.values() for c in cols},
}

#: Plausible magnitude of a column by its unit (the quaternions have their own check).
_RANGES: dict[str, float] = {"m": 100.0, "m/s": 1000.0, "rad/s": 100.0, "N": 1e9, "N m": 1e9}

#: How far a quaternion's norm may be off 1 (a logger's rounding is far below).
QUATERNION_NORM_TOLERANCE = 1e-3

#: The largest attitude from the target frame a docking's pose may have (deg): a
#: quaternion read in another column order is about 180 deg off.
MAX_ATTITUDE_DEG = 60.0

#: The format's own CSV.
LAYOUT6 = LogLayout(source="the 6-DoF format", format_columns=RUN6_COLUMNS)


@dataclass
class Run6:
    """One recorded 6-DoF run (SI units; row ``k`` is tick ``k``).

    Attributes
    ----------
    run_id : str
    params : DockingLoopParams
        The scenario the rig computer ran with.
    scenario : dict
        The scenario as the JSON holds it (a scenario file's sections).
    time_s : ndarray (N,)
    blocks : dict of ndarray
        :data:`BLOCKS` by name, each (N, 3) or (N, 4).
    """

    run_id: str
    params: DockingLoopParams
    scenario: dict
    time_s: np.ndarray
    blocks: dict[str, np.ndarray]
    csv_path: Path | None = None
    json_path: Path | None = None
    skipped_columns: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.time_s)

    def pose(self, which: str) -> np.ndarray:
        """``[p; theta]`` (N, 6; m, rad) of ``"des"`` or ``"act"``: the loop's
        pose coordinates (the rotation vector of the attitude)."""
        q = self.blocks[f"q_{which}"]
        return np.hstack([self.blocks[f"p_{which}"], rotation_vectors_of_quaternions(q)])

    @functools.cached_property
    def contact_ticks(self) -> np.ndarray:
        """The ticks the devices touch at the measured pose, found once
        (:func:`~hybridtable.six_dof.touch.touching`; read only)."""
        mask = touching(self.params.contact, self.pose("act")[:, :3], self.rotations("act"))
        mask.flags.writeable = False
        return mask

    def rotations(self, which: str) -> np.ndarray:
        """The attitudes of ``"des"`` or ``"act"`` as rotation matrices (N, 3, 3;
        port frame to W)."""
        return np.array([rotation_exp(t) for t in self.pose(which)[:, 3:]])

    def wrench(self, which: str) -> np.ndarray:
        """``[moment; force]`` (N, 6; N m, N) of ``"mea"`` or ``"comp"``: the
        loop's wrench layout."""
        return np.hstack([self.blocks[f"m_{which}"], self.blocks[f"f_{which}"]])

    def metrics(self) -> DockingMetrics:
        """The 6-DoF metrics of the record (:func:`docking_metrics`): the CoR
        along the normal from the model port's velocity, the energy of the
        model's body (its centre of mass's velocity and body rate from the
        port's twist and attitude), the contact as the sensor read it."""
        body = self.params.spacecraft
        R = self.rotations("des")
        omega = self.blocks["w_des"]
        arm = R @ body.port_position_m
        v_com = self.blocks["v_des"] - np.cross(omega, arm)
        omega_b = np.einsum("nji,nj->ni", R, omega)
        rot = 0.5 * np.einsum("ni,ij,nj->n", omega_b, body.inertia, omega_b)
        kin = 0.5 * body.mass_kg * np.einsum("ni,ni->n", v_com, v_com) + rot
        return docking_metrics(
            self.time_s,
            self.blocks["v_des"],
            kin,
            rot,
            self.wrench("mea"),
            self.wrench("comp"),
            self.blocks["p_des"],
        )


# -- writing ---------------------------------------------------------------------
def run6_of_docking(run: DockingRun, run_id: str, scenario: Mapping[str, Any]) -> Run6:
    """The 6-DoF run a data logger would have written of a simulated run: the
    format's rows of the diagram's log (see the module), the readings as the
    rig computer read them (the F/T sensor's and the encoders' noise, the
    scenario's ``[rig]``, inside the loop). ``scenario`` is what the JSON
    holds: what the rig computer was told, which may differ from the physics
    ``run`` simulated (the run's :attr:`Run6.params` are the scenario's, as a
    reader finds them)."""
    log = run.log
    n = len(run.time_s) - 1
    if n < 3:
        raise ParameterError("the record is too short to write (fewer than 3 ticks)")
    command = log["commanded_state"][1:]
    table = log["measured_table_state"][:n]
    blocks = {
        "p_des": command[:, 0:3],
        "q_des": quaternions_of_rotation_vectors(command[:, 3:6]),
        "v_des": command[:, 6:9],
        "w_des": command[:, 9:12],
        "p_act": table[:, 0:3],
        "q_act": quaternions_of_rotation_vectors(table[:, 3:6]),
        "f_mea": log["measured_wrench"][:n, 3:6],
        "m_mea": log["measured_wrench"][:n, 0:3],
        "f_comp": log["compensated_wrench"][:n, 3:6],
        "m_comp": log["compensated_wrench"][:n, 0:3],
    }
    return Run6(
        run_id,
        parse_scenario(scenario, f"the scenario of run {run_id}"),
        copy.deepcopy(dict(scenario)),
        run.time_s[:n].copy(),
        {k: np.ascontiguousarray(v, dtype=float) for k, v in blocks.items()},
    )


def run6_csv_text(run: Run6) -> str:
    """The CSV of a run (every float in its shortest exact form)."""
    columns = [run.time_s] + [
        run.blocks[name][:, j] for name, (cols, _, _) in BLOCKS.items() for j in range(len(cols))
    ]
    lines = [",".join(RUN6_COLUMNS)]
    lines += [",".join(map(repr, map(float, row))) for row in zip(*columns, strict=True)]
    return "\n".join(lines) + "\n"


def run6_json(run: Run6) -> dict:
    """The JSON document of a run."""
    return {"format": FORMAT6, "run_id": run.run_id, "scenario": run.scenario}


# -- reading ---------------------------------------------------------------------
def is_run6(paths: Sequence[str | Path]) -> bool:
    """True if the first run ``paths`` name is a 6-DoF run: its JSON's format
    is a ``hybridtable-run6`` one (another version too, which the reader then
    refuses by name), or it holds a ``scenario`` and no 1-D ``format``."""
    try:
        pairs = find_run_files(paths, formats=(FORMAT6,))
    except MeasurementError:
        return False
    for _, json_path in pairs[:1]:
        try:
            raw = read_user_json(json_path)
        except (OSError, ValueError):
            return False
        if not isinstance(raw, dict):
            return False
        kind = raw.get("format")
        if isinstance(kind, str) and kind.startswith(FORMAT6.split("/")[0] + "/"):
            return True
        return "scenario" in raw and kind is None
    return False


def _read_json(path: Path) -> tuple[str, DockingLoopParams, dict]:
    try:
        raw = read_user_json(path)
    except ValueError as err:
        raise MeasurementError(f"{path}: {err}") from None
    if not isinstance(raw, dict):
        raise MeasurementError(f"{path}: must hold a JSON object (got {type(raw).__name__})")
    missing = [k for k in ("format", "run_id", "scenario") if k not in raw]
    if missing:
        raise MeasurementError(f"{path}: missing key(s) {', '.join(missing)}")
    if raw["format"] != FORMAT6:
        raise MeasurementError(
            f"{path}: format is {raw['format']!r}; this reader reads {FORMAT6!r}"
        )
    if not isinstance(raw["run_id"], str) or not raw["run_id"].strip():
        raise MeasurementError(f"{path}: run_id must be a non-empty string")
    if not isinstance(raw["scenario"], dict):
        raise MeasurementError(f"{path}: scenario must be an object (a scenario file's sections)")
    try:
        params = parse_scenario(raw["scenario"], f"{path}: scenario")
    except ParameterError as err:
        raise MeasurementError(str(err)) from None
    return raw["run_id"], params, raw["scenario"]


def read_run6(
    csv_path: str | Path, json_path: str | Path | None = None, layout: LogLayout | None = None
) -> Run6:
    """Read and check one 6-DoF run (every check of ``docs/run6-format.md``
    but the set's unique run ids); ``layout`` says how a rig's own log maps to
    the format (:func:`~hybridtable.measurement.log_layout.log_layout` with
    :data:`RUN6_COLUMNS`; default: the format's own CSV).

    Raises
    ------
    MeasurementError
        For any defect, in one line naming the file and the line or key.
    """
    csv_path = Path(csv_path)
    json_path = Path(json_path) if json_path is not None else csv_path.with_suffix(".json")
    for p in (csv_path, json_path):
        problem = regular_file_problem(p)
        if problem:
            raise MeasurementError(f"{p}: {problem}")
    run_id, params, scenario = _read_json(json_path)
    layout = LAYOUT6 if layout is None else layout
    if layout.format_columns is not RUN6_COLUMNS:
        raise ValueError("read_run6: the layout must map to RUN6_COLUMNS")
    cols, lines, skipped = read_series(csv_path, layout)
    check_time(csv_path, json_path, cols["time_s"], lines, params, layout)
    blocks = {name: np.column_stack([cols[c] for c in spec[0]]) for name, spec in BLOCKS.items()}
    run = Run6(run_id, params, scenario, cols["time_s"], blocks, csv_path, json_path, skipped)
    _check_ranges(run, lines)
    for which in ("des", "act"):
        _check_quaternions(run, which, lines)
    _check_rates(run, layout)
    _check_contact(run)
    return run


def read_runs6(paths: Sequence[str | Path], layout: LogLayout | None = None) -> list[Run6]:
    """Read and check every 6-DoF run ``paths`` name (files or folders,
    through ``layout``: see :func:`read_run6`); all are read before any is
    returned, and their run ids must differ.

    Raises
    ------
    MeasurementError
        For any defect (:func:`read_run6`, and the pairs' own).
    """
    runs = [read_run6(c, j, layout) for c, j in find_run_files(paths, formats=(FORMAT6,))]
    check_unique_ids(runs)
    return runs


# -- the checks ------------------------------------------------------------------
def _check_ranges(run: Run6, lines: Sequence[int]) -> None:
    for name, (cols, unit, what) in BLOCKS.items():
        if unit == "1":
            continue
        bound = _RANGES[unit]
        values = run.blocks[name]
        bad = np.argwhere(np.abs(values) > bound)
        if bad.size:
            i, j = (int(x) for x in bad[0])
            raise MeasurementError(
                f"{run.csv_path} line {lines[i]}: {cols[j]} = {values[i, j]:.6g} {unit} at "
                f"t = {run.time_s[i]:.6g} s is outside the plausible range (+-{bound:g} {unit}; "
                f"the {what})"
            )


def _check_quaternions(run: Run6, which: str, lines: Sequence[int]) -> None:
    q = run.blocks[f"q_{which}"]
    name = f"q_{which}"
    norm = np.linalg.norm(q, axis=1)
    off = np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE)
    if off.size:
        i = int(off[0])
        raise MeasurementError(
            f"{run.csv_path} line {lines[i]}: {name} (the {BLOCKS[name][2]}) is not a unit "
            f"quaternion (norm {norm[i]:.6g} at t = {run.time_s[i]:.6g} s), so not a rotation: "
            "the format's attitude is a unit quaternion (qw, qx, qy, qz)"
        )
    angle = np.degrees(2.0 * np.arccos(np.clip(np.abs(q[:, 0]), 0.0, 1.0)))
    far = np.flatnonzero(angle > MAX_ATTITUDE_DEG)
    if far.size:
        i = int(far[0])
        raise MeasurementError(
            f"{run.csv_path} line {lines[i]}: {name} (the {BLOCKS[name][2]}) is {angle[i]:.0f} deg "
            f"from the target frame at t = {run.time_s[i]:.6g} s, where a docking stays within "
            f"{MAX_ATTITUDE_DEG:g} deg of it: are the quaternion's columns in another order, "
            "(x, y, z, w)? map them with --column-map"
        )
    if q[0, 0] < 0.0:
        raise MeasurementError(
            f"{run.csv_path} line {lines[0]}: {name} starts with qw < 0; the format's first "
            "quaternion has qw >= 0 (q and -q are one rotation: write -q)"
        )
    dots = np.einsum("ij,ij->i", q[1:], q[:-1])
    flip = np.flatnonzero(dots < 0.0)
    if flip.size:
        i = int(flip[0]) + 1
        raise MeasurementError(
            f"{run.csv_path} line {lines[i]}: {name} changes sign from the row before "
            f"(q . q_prev = {dots[i - 1]:.4g} at t = {run.time_s[i]:.6g} s): q and -q are one "
            "rotation, but the format keeps each row on the side of the row before (a logger "
            "that writes qw >= 0 keeps it)"
        )


def _slope(measured: np.ndarray, reference: np.ndarray) -> float:
    """Least-squares factor ``s`` of ``measured ~ s reference`` (rows of vectors)."""
    return float(np.sum(measured * reference) / np.sum(reference * reference))


#: An attitude turning slower than this (rad/s, RMS) cannot tell rad/s from deg/s.
_TURNING_RAD_PER_S = 1e-6


def _check_rates(run: Run6, layout: LogLayout = LAYOUT6) -> None:
    """The model's twist against the commanded pose's change from tick to
    tick, axis by axis: the attitude's change is ``exp(h w_des[k]) R[k-1]``
    exactly (the rig computer's step), the position's ``h v_des[k]`` but for
    the turn of the port's lever arm."""
    h = run.params.sample_period_s
    q = run.blocks["q_des"]
    conj = q[:-1] * np.array([1.0, -1.0, -1.0, -1.0])
    turn = rotation_vectors_of_quaternions(quaternion_product(q[1:], conj)) / h
    w = run.blocks["w_des"][1:]
    columns = BLOCKS["w_des"][0]
    for j in range(3):
        if math.sqrt(float(np.mean(turn[:, j] ** 2))) <= _TURNING_RAD_PER_S:
            continue  # this axis does not turn measurably
        s = _slope(w[:, j], turn[:, j])
        if abs(s / math.degrees(1.0) - 1.0) < 0.1:
            raise MeasurementError(
                f"{run.csv_path}: {columns[j]} is {s:.4g} times the commanded attitude's rate "
                "of turn: logged in degrees per second where radians per second are due; "
                f"{layout.unit_advice({c: 'deg/s' for c in columns})}"
            )
        if not 0.8 < s < 1.25:
            raise MeasurementError(
                f"{run.csv_path}: {columns[j]} does not follow the commanded attitude's change "
                f"from tick to tick (slope {s:.4g}, expected 1): a sign-flipped or mislabelled "
                "angular velocity column"
            )
    step = np.diff(run.blocks["p_des"], axis=0) / h
    v = run.blocks["v_des"]
    speed = math.sqrt(float(np.mean(np.sum(v * v, axis=1))))
    columns = BLOCKS["v_des"][0]
    for j in range(3):
        if math.sqrt(float(np.mean(step[:, j] ** 2))) <= 1e-6 * speed:
            continue  # no motion along this axis to compare (the command has no noise)
        s = _slope(v[1:, j], step[:, j])
        if not 0.8 < s < 1.25:
            raise MeasurementError(
                f"{run.csv_path}: {columns[j]} does not follow the commanded position's change "
                f"from tick to tick (slope {s:.4g}, expected 1): a sign-flipped or mislabelled "
                "velocity column"
            )
    # p_des[k] - p_des[k-1] = h v_des[k]: a command logged a row off is closer
    # to its neighbour's velocity (seen while the model accelerates)
    errors = {
        d: float(np.sqrt(np.mean((step[1:-1] - v[2 + d : len(v) - 1 + d]) ** 2)))
        for d in (-1, 0, 1)
    }
    best = min(errors, key=errors.__getitem__)
    if best != 0 and errors[best] < 0.3 * errors[0] and errors[0] > 1e-6 * speed:
        side = "late" if best == -1 else "early"
        raise MeasurementError(
            f"{run.csv_path}: the commanded position steps by h v_des of the row "
            f"{'before' if best == -1 else 'after'} (RMS {errors[best]:.3g} m/s against "
            f"{errors[0]:.3g} m/s for its own row): p_des is logged a row {side} against v_des; "
            "the format logs both after the tick's update"
        )


def noise_levels(values: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """Robust white-noise std of each column (N, k): the 1-D channels'
    :func:`~hybridtable.measurement.channels.noise_level` of its second
    differences, over the second differences centred on ``rows`` (a mask of
    the N rows; default all)."""
    values = np.asarray(values, dtype=float)
    d2 = np.diff(values, n=2, axis=0)
    if rows is not None:
        d2 = d2[rows[:-2] & rows[1:-1] & rows[2:]]
    return np.array([noise_level_of_differences(c) for c in d2.T])


def _check_contact(run: Run6) -> None:
    """The record starts apart (by the measured pose) and holds a contact (a
    force from its level at rest above five noise levels and the dead band)."""
    touch = run.contact_ticks
    if touch[0]:
        raise MeasurementError(
            f"{run.csv_path}: the record starts in contact (the measured pose presses the "
            "devices together at t = 0); the format's record starts with the devices apart"
        )
    force = force_from_rest(run.blocks["f_mea"], touch)
    # five noise levels (over every tick, at least 1e-3 of the head-on peak) and the dead band
    noise = float(np.linalg.norm(noise_levels(run.blocks["f_mea"])))
    level = 5.0 * max(noise, 1e-3 * peak_force_n(run.params)) + run.params.force_deadband_n
    above = np.flatnonzero(force > level)
    if above.size == 0:
        raise MeasurementError(
            f"{run.csv_path}: no contact in the record: the measured force stays within "
            f"{level:.4g} N (five noise levels and the dead band)"
        )
    if above[0] < 3:
        raise MeasurementError(
            f"{run.csv_path}: the record starts in contact (measured force {force[0]:.4g} N "
            "from its level at rest at t = 0); the format's record starts with the devices apart"
        )
