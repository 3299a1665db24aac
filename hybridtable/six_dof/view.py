"""Seeing a 6-DoF docking run: a Meshcat recording, motion magnified, the contact force as an arrow.

The scene is drawn in the target frame W (``docs/six_dof.md``), +z (the
docking axis) up: the passive device (the target plate, fixed, its face the
plane z = 0) above the active device that the table pushes up into it:

- the active device at the table's actual pose (``log["table_state"]``): the
  ring of spherical pads on a disc, on a column standing on the top plate
  of a 3-3 Stewart platform (``run.params.stewart.geometry`` for a Stewart
  run, else :class:`~hybridtable.stewart.geometry.StewartGeometry`'s
  defaults), ``device_length_m`` below the port's face, its base fixed under
  the docked pose; the legs come from
  :meth:`~hybridtable.stewart.geometry.StewartGeometry.leg_vectors` of the
  drawn plate pose, so the mechanism stays whole;
- the spacecraft model (``log["body_state"]``): a translucent box around its
  centre of mass and a boom out to its port (the gap between its port and
  the device is the table's tracking error);
- the contact force on the chaser (``log["contact_wrench"]``): a red arrow
  whose tip presses on the centre of pressure (where the force's line of
  action crosses the port's face plane, :func:`centre_of_pressure_m`), its
  length the force divided by ``force_scale_n_per_m``.

Each pose's displacement from the docked pose (port on the plate's face,
aligned: ``q = 0``) is drawn times ``magnify``, translation and rotation
angle alike (:func:`drawn_pose`); only the drawing is scaled. The recording
plays in real time at :data:`~hybridtable.stewart.view.FRAMES_PER_SECOND`,
each frame the log sample nearest its time, but the frame nearest the force
peak shows the peak; it holds the last frame :data:`HOLD_S` before it loops.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from pydrake.geometry import Box, Cylinder, Meshcat, MeshcatCone, Rgba, Sphere
from pydrake.math import RigidTransform, RotationMatrix

from hybridtable._validation import check_positive
from hybridtable.errors import ParameterError
from hybridtable.six_dof.drogue import drogue_mesh
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.six_dof.simulation import DockingRun
from hybridtable.stewart.geometry import StewartGeometry, rpy_from_rotation
from hybridtable.stewart.view import (
    FRAMES_PER_SECOND,
    auto_force_scale_n_per_m,
    auto_magnify,
    open_meshcat,
)

__all__ = [
    "ROOT",
    "HOLD_S",
    "DockingScene",
    "centre_of_pressure_m",
    "drawn_pose",
    "peak_displacement_m",
    "write_docking_html",
]

#: Meshcat path of the scene (Drake prefixes relative paths with /drake).
ROOT = "docking"
#: Time the recording holds the last frame before it loops, s.
HOLD_S = 1.0

_SHAFT_RADIUS_M = 0.012
_HEAD_LENGTH_M = 0.06
_HEAD_RADIUS_M = 0.03
_LEG_RADIUS_M = 0.018
_PLATE_THICKNESS_M = 0.03
_TARGET_THICKNESS_M = 0.08
_COLOURS = {
    "target": (0.55, 0.6, 0.7, 0.55),
    "pad": (0.95, 0.55, 0.1, 1.0),
    "device": (0.35, 0.35, 0.38, 1.0),
    "plate": (0.75, 0.75, 0.78, 1.0),
    "leg": (0.5, 0.52, 0.55, 1.0),
    "base": (0.3, 0.3, 0.32, 1.0),
    "spacecraft": (0.2, 0.45, 0.9, 0.22),
    "boom": (0.2, 0.45, 0.9, 0.6),
    "arrow": (0.85, 0.1, 0.1, 1.0),
}


def centre_of_pressure_m(
    wrench: np.ndarray, port_position_m: np.ndarray, port_rotation: np.ndarray
) -> np.ndarray | None:
    """Where the force's line of action crosses the port's face plane (W, m).

    Parameters
    ----------
    wrench : array (6,)
        ``[moment about the port origin (N m); force (N)]`` in W.
    port_position_m, port_rotation : array (3,), (3, 3)
        The port's origin in W and its orientation (its face plane is
        normal to the rotation's third column).

    Returns
    -------
    array (3,) or None
        The point ``r`` with ``(r - p) x f = moment`` in the face plane (the
        point of the wrench's axis nearest the port if the force lies in the
        plane); None without force.
    """
    tau, f = np.asarray(wrench[:3], float), np.asarray(wrench[3:6], float)
    ff = float(f @ f)
    if ff == 0.0:
        return None
    r0 = np.cross(f, tau) / ff  # the line's point nearest the port origin
    n = np.asarray(port_rotation)[:, 2]
    fn = float(f @ n)
    if abs(fn) > 1e-9 * math.sqrt(ff):
        r0 = r0 - (r0 @ n) / fn * f
    return np.asarray(port_position_m, float) + r0


def drawn_pose(q: np.ndarray, magnify: float) -> tuple[np.ndarray, np.ndarray]:
    """The drawn position (m) and rotation of a port pose ``q = [p; theta]``:
    its displacement from the docked pose ``q = 0`` times ``magnify``."""
    return magnify * np.asarray(q[:3], float), rotation_exp(magnify * np.asarray(q[3:6], float))


def _body_port_poses(run: DockingRun) -> np.ndarray:
    """The spacecraft's port pose ``[p_P; theta]`` (N, 6) from its body state."""
    r_p = run.params.spacecraft.port_position_m
    out = []
    for x in run.log["body_state"]:
        R = x[6:15].reshape(3, 3)
        out.append(np.concatenate([x[:3] + R @ r_p, rotation_log(R)]))
    return np.array(out).reshape(-1, 6)


def peak_displacement_m(run: DockingRun) -> float:
    """Largest distance of a pad centre (or the probe head's centre) of the
    device (at the table's pose) or of the spacecraft's port from its place
    at the docked pose (m)."""
    c = run.params.contact
    pads = c.probe_centre_m[None, :] if c.is_cone else c.pad_centres_m
    peak = 0.0
    for poses in (run.log["table_state"][:, :6], _body_port_poses(run)):
        for q in poses:
            moved = q[:3] + pads @ (rotation_exp(q[3:6]) - np.eye(3)).T
            peak = max(peak, float(np.max(np.linalg.norm(moved, axis=1))))
    return peak


class DockingScene:
    """A 6-DoF run drawn in a Meshcat (see the module docstring).

    Parameters
    ----------
    meshcat : pydrake.geometry.Meshcat
    run : DockingRun
    magnify : float, optional
        Factor on the displacement from the docked pose, > 0; default
        :func:`~hybridtable.stewart.view.auto_magnify` of
        :func:`peak_displacement_m` on the ring's radius.
    force_scale_n_per_m : float, optional
        Force per metre of arrow (N/m), > 0; default
        :func:`~hybridtable.stewart.view.auto_force_scale_n_per_m` of the peak.
    """

    def __init__(
        self,
        meshcat: Meshcat,
        run: DockingRun,
        magnify: float | None = None,
        force_scale_n_per_m: float | None = None,
    ) -> None:
        if len(run.time_s) == 0:
            raise ParameterError("the run logged no sample to draw")
        p = run.params
        self.meshcat, self.run = meshcat, run
        self.geometry = p.stewart.geometry if p.stewart is not None else StewartGeometry()
        force = np.linalg.norm(run.log["contact_wrench"][:, 3:6], axis=1)
        self.peak_index = int(np.argmax(force))
        self.peak_force_n = float(force[self.peak_index])
        self.peak_displacement_m = peak_displacement_m(run)
        if magnify is None:
            magnify = auto_magnify(self.peak_displacement_m, p.contact.moment_arm_m)
        if force_scale_n_per_m is None:
            force_scale_n_per_m = auto_force_scale_n_per_m(self.peak_force_n)
        self.magnify = check_positive("magnify", magnify)
        self.force_scale_n_per_m = check_positive("force_scale_n_per_m", force_scale_n_per_m)
        self._body_ports = _body_port_poses(run)
        g = self.geometry
        self._base_origin = np.array([0.0, 0.0, -(g.home_height_m + g.device_length_m)])
        self._add_objects()

    # -- frames -----------------------------------------------------------
    @property
    def duration_s(self) -> float:
        return float(self.run.time_s[-1] - self.run.time_s[0])

    def frame_indices(self) -> np.ndarray:
        """The log sample drawn by each frame (frame j at ``j / fps`` s)."""
        t = self.run.time_s - self.run.time_s[0]
        n = int(math.floor(self.duration_s * FRAMES_PER_SECOND + 1e-9)) + 1
        frames = np.arange(n) / FRAMES_PER_SECOND
        right = np.minimum(np.searchsorted(t, frames), len(t) - 1)
        left = np.maximum(right - 1, 0)
        idx = np.where(frames - t[left] <= t[right] - frames, left, right)
        if self.peak_force_n > 0.0:
            idx[np.argmin(np.abs(frames - t[self.peak_index]))] = self.peak_index
        return idx

    # -- what each frame shows ---------------------------------------------
    def device_pose(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Drawn position (m) and rotation of the active device's port."""
        return drawn_pose(self.run.log["table_state"][index, :6], self.magnify)

    def spacecraft_pose(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Drawn position of the centre of mass (m) and attitude of the spacecraft."""
        p, R = drawn_pose(self._body_ports[index], self.magnify)
        return p - R @ self.run.params.spacecraft.port_position_m, R

    def legs(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Base joints (6, 3) and leg vectors (6, 3) in W of the drawn plate pose (m)."""
        p, R = self.device_pose(index)
        plate = p - R[:, 2] * self.geometry.device_length_m
        pose = np.concatenate([plate - self._base_origin, rpy_from_rotation(R)])
        return self.geometry.base_points_m + self._base_origin, self.geometry.leg_vectors(pose)

    def arrow(self, index: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The drawn force arrow: its tip at the centre of pressure on the
        drawn port face, its vector force / scale (W, m); None without force."""
        w = self.run.log["contact_wrench"][index]
        q = self.run.log["table_state"][index, :6]
        R_act = rotation_exp(q[3:6])
        cop = centre_of_pressure_m(w, q[:3], R_act)
        if cop is None:
            return None
        p, R = self.device_pose(index)
        return p + R @ (R_act.T @ (cop - q[:3])), w[3:6] / self.force_scale_n_per_m

    # -- drawing --------------------------------------------------------------
    def _set(self, path: str, shape, colour: str, X: RigidTransform | None = None) -> None:
        self.meshcat.SetObject(f"{ROOT}/{path}", shape, Rgba(*_COLOURS[colour]))
        if X is not None:
            self.meshcat.SetTransform(f"{ROOT}/{path}", X)

    def _add_objects(self) -> None:
        c, g, m = self.run.params.contact, self.geometry, self.meshcat
        b = self.run.params.spacecraft
        m.Delete(ROOT)
        m.SetProperty("/Grid", "visible", False)
        m.SetProperty("/Axes", "visible", False)
        a, r, t, top = c.ring_radius_m, c.pad_radius_m, _PLATE_THICKNESS_M, _TARGET_THICKNESS_M
        if c.is_cone:  # the probe's head on a disc of its size; the drogue, the target
            a, r = c.probe_radius_m, c.probe_radius_m
            self._set("target", drogue_mesh(c), "target")
            self._set("device/probe", Sphere(r), "pad", RigidTransform(c.probe_centre_m))
        else:
            self._set("target", Cylinder(1.4 * a, top), "target", RigidTransform([0, 0, top / 2]))
            for i, centre in enumerate(c.pad_centres_m):
                self._set(f"device/pad{i}", Sphere(r), "pad", RigidTransform(centre))
        disc = max(2.0 * r, 0.02)
        column = max(g.device_length_m - r - disc, 1e-3)
        for path, shape, colour, z in (
            ("device/disc", Cylinder(a + 1.5 * r, disc), "device", -r - disc / 2),
            ("device/column", Cylinder(0.2 * a, column), "device", column / 2 - g.device_length_m),
            (
                "device/plate",
                Cylinder(g.top_radius_m + 0.03, t),
                "plate",
                -g.device_length_m - t / 2,
            ),
            ("base", Cylinder(g.base_radius_m + 0.05, t), "base", self._base_origin[2] - t / 2),
        ):
            self._set(path, shape, colour, RigidTransform([0.0, 0.0, z]))
        for i in range(6):
            self._set(f"legs/{i}", Cylinder(_LEG_RADIUS_M, 1.0), "leg")
        # The box ends below the table's base where it can (it is virtual, but
        # the rig reads better uncluttered).
        below = b.port_distance_m - g.home_height_m - g.device_length_m - 0.05
        height = max(0.5 * b.port_distance_m, min(b.port_distance_m, 2.0 * below))
        side = 2.6 * (c.mouth_radius_m if c.is_cone else a)
        self._set("spacecraft/box", Box(side, side, height), "spacecraft")
        self._set("spacecraft/centre_of_mass", Sphere(0.04), "boom")
        arm = b.port_position_m
        self._set(
            "spacecraft/boom",
            Cylinder(0.025, float(np.linalg.norm(arm))),
            "boom",
            RigidTransform(RotationMatrix.MakeFromOneVector(arm, 2), arm / 2),
        )
        self._set("force/shaft", Cylinder(_SHAFT_RADIUS_M, 1.0), "arrow")
        flip = RotationMatrix.MakeXRotation(math.pi)
        m.SetObject(
            f"{ROOT}/force/head/cone",
            MeshcatCone(_HEAD_LENGTH_M, _HEAD_RADIUS_M, _HEAD_RADIUS_M),
            Rgba(*_COLOURS["arrow"]),
        )
        m.SetTransform(f"{ROOT}/force/head/cone", RigidTransform(flip, [0.0, 0.0, 0.0]))
        m.SetCameraPose([1.5, -1.9, 0.1], [0.0, 0.0, -0.6])

    def draw(self, index: int, time_in_recording: float | None = None) -> None:
        """Draw log sample ``index``: live, or into the current recording at
        ``time_in_recording`` (s)."""
        m, when = self.meshcat, time_in_recording
        p, R = self.device_pose(index)
        m.SetTransform(f"{ROOT}/device", RigidTransform(RotationMatrix(R), p), when)
        p_s, R_s = self.spacecraft_pose(index)
        m.SetTransform(f"{ROOT}/spacecraft", RigidTransform(RotationMatrix(R_s), p_s), when)
        base, legs = self.legs(index)
        for i, (b, leg) in enumerate(zip(base, legs, strict=True)):
            length = float(np.linalg.norm(leg))
            X = RigidTransform(RotationMatrix.MakeFromOneVector(leg, 2), b + leg / 2)
            m.SetTransform(f"{ROOT}/legs/{i}", X, when)
            m.SetProperty(f"{ROOT}/legs/{i}", "scale", [1.0, 1.0, length], when)
        arrow = self.arrow(index)
        m.SetProperty(f"{ROOT}/force", "visible", arrow is not None, when)
        if arrow is None:
            return
        tip, vector = arrow
        length = float(np.linalg.norm(vector))
        head = min(1.0, length / _HEAD_LENGTH_M)
        shaft = max(length - head * _HEAD_LENGTH_M, 1e-6)
        X = RigidTransform(RotationMatrix.MakeFromOneVector(vector, 2), tip - vector)
        m.SetTransform(f"{ROOT}/force", X, when)
        m.SetTransform(f"{ROOT}/force/shaft", RigidTransform([0.0, 0.0, shaft / 2]), when)
        m.SetProperty(f"{ROOT}/force/shaft", "scale", [1.0, 1.0, shaft], when)
        # The cone's point (the head's origin) is the arrow's tip.
        m.SetTransform(f"{ROOT}/force/head", RigidTransform([0.0, 0.0, length]), when)
        m.SetProperty(f"{ROOT}/force/head", "scale", [head, head, head], when)

    def record(self) -> int:
        """Record the run in real time (frame j: :meth:`frame_indices`
        ``[j]`` at ``j / fps`` s), hold the last frame :data:`HOLD_S`, and
        publish the recording; returns the number of frames of the run."""
        indices = self.frame_indices()
        self.draw(int(indices[0]))  # the scene before the animation plays
        self.meshcat.StartRecording(
            frames_per_second=FRAMES_PER_SECOND, set_visualizations_while_recording=False
        )
        for j, index in enumerate(indices):
            self.draw(int(index), j / FRAMES_PER_SECOND)
        self.draw(int(indices[-1]), (len(indices) - 1) / FRAMES_PER_SECOND + HOLD_S)
        self.meshcat.StopRecording()
        self.meshcat.get_mutable_recording().set_repetitions(1000)
        self.meshcat.PublishRecording()
        return len(indices)


def write_docking_html(
    run: DockingRun,
    path: str | Path,
    magnify: float | None = None,
    force_scale_n_per_m: float | None = None,
    overwrite: bool = False,
) -> dict:
    """Record a 6-DoF run (:class:`DockingScene`) and write it as a
    self-contained HTML page (Meshcat's static HTML, about 2 MB).

    Parameters
    ----------
    run : DockingRun
    path : path
        The HTML file; an existing file is refused (FileExistsError) unless
        ``overwrite`` (then it is replaced atomically).
    magnify, force_scale_n_per_m : float, optional
        See :class:`DockingScene`.

    Returns
    -------
    dict
        ``path``, ``magnify`` (1), ``force_scale_n_per_m`` (N/m),
        ``peak_force_n`` (N) and ``peak_arrow_m`` (m), ``peak_displacement_m``
        (m, true), ``frames`` and ``frames_per_second`` (1/s) of the run,
        ``duration_s`` (s, simulated and played), ``bytes`` of the file.
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"refusing to overwrite {path}")
    meshcat = open_meshcat()
    scene = DockingScene(meshcat, run, magnify, force_scale_n_per_m)
    frames = scene.record()
    html = meshcat.StaticHtml()
    from hybridtable._files import write_text_atomic

    write_text_atomic(path, html, replace=overwrite)  # complete, and no other's replaced
    return {
        "path": str(path),
        "magnify": scene.magnify,
        "force_scale_n_per_m": scene.force_scale_n_per_m,
        "peak_force_n": scene.peak_force_n,
        "peak_arrow_m": scene.peak_force_n / scene.force_scale_n_per_m,
        "peak_displacement_m": scene.peak_displacement_m,
        "frames": frames,
        "frames_per_second": FRAMES_PER_SECOND,
        "duration_s": scene.duration_s,
        "bytes": len(html.encode("utf-8")),
    }
