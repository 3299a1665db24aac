"""Seeing a Stewart run in Meshcat: the platform's motion, magnified, and the contact force.

The table moves a few millimetres to a few centimetres on a platform of a
metre: at true scale the motion is invisible. A run logs the plate's pose
and the contact force at every step (:class:`StewartMotion`, filled by
:func:`~hybridtable.stewart.run.simulate_stewart`); :class:`MotionView` draws
them with the plate's displacement from its home pose (translation and
rotation) scaled by ``magnify`` and the legs placed by the inverse kinematics
of the drawn pose, so the mechanism stays whole. Only the drawing is scaled:
the physics, the metrics and the JSON are the run's.

The contact force is an arrow (red, along -z: the push of the spacecraft's
device on the table's) from the contact point, its length the force divided
by ``force_scale_n_per_m`` (e.g. 1 m per 5000 N). The arrow is a unit shaft
and a cone whose ``scale`` and position are animated, at Meshcat path
``/drake/contact_force`` (:data:`ARROW_PATH`).

- :meth:`MotionView.record`: a Meshcat recording (an animation) of the run,
  written as a self-contained HTML file by :meth:`MotionView.html`;
- :meth:`MotionView.play`: the run streamed to a live Meshcat server at a
  real-time rate (:func:`open_meshcat` starts one on localhost).
"""

from __future__ import annotations

import logging
import math
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TextIO

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis, Quaternion
from pydrake.geometry import (
    Cylinder,
    Meshcat,
    MeshcatCone,
    MeshcatParams,
    MeshcatVisualizer,
    MeshcatVisualizerParams,
    Rgba,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import DiagramBuilder, LeafSystem

from hybridtable.errors import ParameterError
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.plant import add_stewart_plant

__all__ = [
    "ARROW_PATH",
    "FRAMES_PER_SECOND",
    "DRAWN_FRACTION_OF_RADIUS",
    "MAX_ARROW_LENGTH_M",
    "StewartMotion",
    "PoseRecorder",
    "MotionView",
    "auto_magnify",
    "auto_force_scale_n_per_m",
    "open_meshcat",
    "show_live",
]

#: Meshcat path of the force arrow (Drake prefixes relative paths with /drake).
ARROW_PATH = "contact_force"
#: Frame rate of the drawing (recording and live), 1/s.
FRAMES_PER_SECOND = 64.0
#: The automatic magnification draws the peak plate displacement at about
#: this fraction of the platform's radius (the top joint circle).
DRAWN_FRACTION_OF_RADIUS = 0.3
#: The automatic force scale draws the peak force at most this long, m.
MAX_ARROW_LENGTH_M = 0.5

_ARROW_RGBA = (0.85, 0.1, 0.1, 1.0)
_SHAFT_RADIUS_M = 0.012
_HEAD_LENGTH_M = 0.06
_HEAD_RADIUS_M = 0.03
#: Time the recording holds the last frame before it loops, s (wall).
_HOLD_S = 1.0


def _nice_floor(x: float) -> float:
    """The largest 1, 2 or 5 times a power of ten that is <= ``x`` (> 0)."""
    e = math.floor(math.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**e <= x * (1.0 + 1e-12):
            return m * 10.0**e
    return 10.0 ** (e - 1) * 5.0


def _nice_ceil(x: float) -> float:
    """The smallest 1, 2 or 5 times a power of ten that is >= ``x`` (> 0)."""
    e = math.floor(math.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10.0**e >= x * (1.0 - 1e-12):
            return m * 10.0**e
    return 10.0 ** (e + 1)


def auto_magnify(peak_displacement_m: float, platform_radius_m: float) -> float:
    """A round factor (1, 2, 5 x 10^k, at least 1) that draws the peak plate
    displacement at about :data:`DRAWN_FRACTION_OF_RADIUS` of the platform's
    radius (at most that)."""
    if not peak_displacement_m > 0.0:
        return 1.0
    return max(1.0, _nice_floor(DRAWN_FRACTION_OF_RADIUS * platform_radius_m / peak_displacement_m))


def auto_force_scale_n_per_m(peak_force_n: float) -> float:
    """A round force per metre of arrow (1, 2, 5 x 10^k N/m) that draws the
    peak force at most :data:`MAX_ARROW_LENGTH_M` long."""
    if not peak_force_n > 0.0:
        return 1000.0
    return _nice_ceil(peak_force_n / MAX_ARROW_LENGTH_M)


@dataclass(frozen=True)
class StewartMotion:
    """What a Stewart run shows: the plate's pose and the contact force over time.

    Attributes
    ----------
    time_s : array (n,)
        Simulated times, s, increasing.
    plate_quaternion : array (n, 4)
        The plate's orientation in the world, ``[w, x, y, z]``.
    plate_position_m : array (n, 3)
        The plate frame's origin in the world, m.
    force_n : array (n,)
        Contact force read by the F/T sensor, N, compression positive.
    home_position_m : array (3,)
        The plate's home position, m (its home orientation is the identity).
    """

    time_s: np.ndarray
    plate_quaternion: np.ndarray
    plate_position_m: np.ndarray
    force_n: np.ndarray
    home_position_m: np.ndarray

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1])

    @property
    def peak_displacement_m(self) -> float:
        """Largest distance of the plate from home, m."""
        return float(np.max(np.linalg.norm(self.plate_position_m - self.home_position_m, axis=1)))

    @property
    def peak_force_n(self) -> float:
        return float(np.max(self.force_n))

    def at(self, time_s: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Plate position (m), quaternion ``[w, x, y, z]`` and force (N) at
        ``time_s``, interpolated linearly (the quaternion normalized)."""
        t = self.time_s
        position = np.array([np.interp(time_s, t, c) for c in self.plate_position_m.T])
        q = np.array([np.interp(time_s, t, c) for c in self.plate_quaternion.T])
        force = float(np.interp(time_s, t, self.force_n))
        return position, q / np.linalg.norm(q), force


class PoseRecorder(LeafSystem):
    """Records the plate's pose (``StewartTable``'s ``plate_pose``) at every
    simulator step: a per-step publish event, so no extra step and no state;
    the samples stay in the system (the simulation's context may be gone).

    Ports
    -----
    Input ``plate_pose`` (7: 1, m)
        Quaternion ``[w, x, y, z]`` and position of the plate.
    """

    def __init__(self) -> None:
        LeafSystem.__init__(self)
        self._input = self.DeclareVectorInputPort("plate_pose", 7)
        self._times: list[float] = []
        self._poses: list[np.ndarray] = []
        self.DeclarePerStepPublishEvent(self._record)

    def _record(self, context) -> None:
        t = context.get_time()
        pose = np.array(self._input.Eval(context), dtype=float)
        if self._times and t <= self._times[-1]:
            self._times[-1], self._poses[-1] = t, pose
        else:
            self._times.append(t)
            self._poses.append(pose)

    def samples(self) -> tuple[np.ndarray, np.ndarray]:
        """Times (n,), s, and poses (n, 7): quaternion ``[w, x, y, z]``, position m."""
        return np.array(self._times), np.array(self._poses).reshape(-1, 7)


def open_meshcat(port: int | None = None) -> Meshcat:
    """A Meshcat server on localhost (``port`` ``None``: the first free one
    from 7000), without Drake's "listening" log line (the caller prints the
    URL, :meth:`~pydrake.geometry.Meshcat.web_url`)."""
    log = logging.getLogger("drake")
    level = log.level
    log.setLevel(logging.WARNING)
    try:
        return Meshcat(MeshcatParams(host="localhost", port=port))
    finally:
        log.setLevel(level)


class MotionView:
    """Draws a :class:`StewartMotion` in a Meshcat, magnified about the home pose.

    Parameters
    ----------
    meshcat : pydrake.geometry.Meshcat
    stewart : StewartParams
        The platform run (its geometry is drawn).
    motion : StewartMotion
    magnify : float, optional
        Factor on the plate's displacement from home (translation and
        rotation angle), > 0; default :func:`auto_magnify`.
    force_scale_n_per_m : float, optional
        Force per metre of arrow, N/m, > 0; default :func:`auto_force_scale_n_per_m`.
    """

    def __init__(
        self,
        meshcat: Meshcat,
        stewart: StewartParams,
        motion: StewartMotion,
        magnify: float | None = None,
        force_scale_n_per_m: float | None = None,
    ) -> None:
        g = stewart.geometry
        if magnify is None:
            magnify = auto_magnify(motion.peak_displacement_m, g.top_radius_m)
        if force_scale_n_per_m is None:
            force_scale_n_per_m = auto_force_scale_n_per_m(motion.peak_force_n)
        for name, value in (("magnify", magnify), ("force_scale_n_per_m", force_scale_n_per_m)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} must be a finite number > 0 (got {value!r})")
        self.meshcat = meshcat
        self.motion = motion
        self.magnify = float(magnify)
        self.force_scale_n_per_m = float(force_scale_n_per_m)
        # The tip's top point in the plate frame (the contact point at home).
        self._tip_top = g.device_tip_center_m + np.array([0.0, 0.0, g.device_tip_radius_m])
        builder = DiagramBuilder()
        # Contact parameters do not matter for drawing.
        self._handles = add_stewart_plant(builder, stewart, 1.0)
        self._visualizer = MeshcatVisualizer.AddToBuilder(
            builder, self._handles.scene_graph, meshcat, MeshcatVisualizerParams()
        )
        self._diagram = builder.Build()
        self._context = self._diagram.CreateDefaultContext()
        self._plant_context = self._handles.plant.GetMyMutableContextFromRoot(self._context)
        self._visualizer_context = self._visualizer.GetMyContextFromRoot(self._context)
        rgba = Rgba(*_ARROW_RGBA)
        meshcat.SetObject(f"{ARROW_PATH}/shaft", Cylinder(_SHAFT_RADIUS_M, 1.0), rgba)
        meshcat.SetObject(
            f"{ARROW_PATH}/head", MeshcatCone(_HEAD_LENGTH_M, _HEAD_RADIUS_M, _HEAD_RADIUS_M), rgba
        )

    def frame_times_s(self) -> np.ndarray:
        """Simulated times of the frames, s (:data:`FRAMES_PER_SECOND`)."""
        n = int(math.floor(self.motion.duration_s * FRAMES_PER_SECOND + 1e-9)) + 1
        return np.arange(n) / FRAMES_PER_SECOND

    def drawn_pose(self, time_s: float):
        """The magnified plate pose drawn at ``time_s``: (position m, RotationMatrix)."""
        position, q, _ = self.motion.at(time_s)
        home = self.motion.home_position_m
        drawn_position = home + self.magnify * (position - home)
        angle_axis = RotationMatrix(Quaternion(q)).ToAngleAxis()
        drawn_rotation = RotationMatrix(
            AngleAxis(self.magnify * angle_axis.angle(), angle_axis.axis())
        )
        return drawn_position, drawn_rotation

    def arrow_length_m(self, time_s: float) -> float:
        """Length of the force arrow at ``time_s``, m (0 without contact)."""
        return max(self.motion.at(time_s)[2], 0.0) / self.force_scale_n_per_m

    def draw(self, time_s: float, time_in_recording: float | None = None) -> None:
        """Draw the frame at simulated ``time_s``: live, or into the current
        recording at ``time_in_recording`` (s of the recording)."""
        position, rotation = self.drawn_pose(time_s)
        self._handles.set_drawn_pose(self._plant_context, position, rotation)
        self._context.SetTime(time_s if time_in_recording is None else time_in_recording)
        self._visualizer.ForcedPublish(self._visualizer_context)
        m, when = self.meshcat, time_in_recording
        length = self.arrow_length_m(time_s)
        m.SetProperty(ARROW_PATH, "visible", length > 0.0, when)
        if length <= 0.0:
            return
        contact = position + rotation.matrix() @ self._tip_top
        # The shaft runs from the contact point (0) to the cone's base; the
        # cone's apex, at -length, is the arrow's tip.
        shaft = max(length - _HEAD_LENGTH_M, 1e-4)
        head = min(1.0, length / _HEAD_LENGTH_M)
        m.SetTransform(ARROW_PATH, RigidTransform(contact), when)
        m.SetTransform(f"{ARROW_PATH}/shaft", RigidTransform([0.0, 0.0, -shaft / 2]), when)
        m.SetProperty(f"{ARROW_PATH}/shaft", "scale", [1.0, 1.0, shaft], when)
        m.SetTransform(f"{ARROW_PATH}/head", RigidTransform([0.0, 0.0, -length]), when)
        m.SetProperty(f"{ARROW_PATH}/head", "scale", [head, head, head], when)

    def record(self, realtime_rate: float = 1.0, repetitions: int = 1000) -> None:
        """Record the run as a Meshcat animation played at ``realtime_rate``
        (recording time = simulated time / rate), holding the last frame
        for a second before it loops, and publish it."""
        rate = _check_rate(realtime_rate)
        self.meshcat.StartRecording(
            frames_per_second=FRAMES_PER_SECOND, set_visualizations_while_recording=False
        )
        times = self.frame_times_s()
        for t in times:
            self.draw(float(t), float(t) / rate)
        self.draw(float(times[-1]), float(times[-1]) / rate + _HOLD_S)
        self.meshcat.StopRecording()
        recording = self.meshcat.get_mutable_recording()
        recording.set_repetitions(repetitions)
        self.meshcat.PublishRecording()

    def html(self) -> str:
        """The scene and its recording as a self-contained HTML page."""
        return self.meshcat.StaticHtml()

    def play(
        self,
        realtime_rate: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        stop: Callable[[], bool] | None = None,
    ) -> float:
        """Stream the run to the live Meshcat at ``realtime_rate`` (wall
        time = simulated time / rate), until its end or ``stop()``; returns
        the wall time it took, s."""
        rate = _check_rate(realtime_rate)
        start = clock()
        for t in self.frame_times_s():
            if stop is not None and stop():
                break
            wait = start + float(t) / rate - clock()
            if wait > 0.0:
                sleep(wait)
            self.draw(float(t))
        return clock() - start


def _check_rate(realtime_rate: float) -> float:
    if not (math.isfinite(realtime_rate) and realtime_rate > 0.0):
        raise ParameterError(f"realtime_rate must be a finite number > 0 (got {realtime_rate!r})")
    return float(realtime_rate)


def show_live(
    view: MotionView,
    realtime_rate: float = 1.0,
    interactive: bool = False,
    stdin: TextIO | None = None,
    say: Callable[[str], None] = print,
) -> int:
    """Play a run in its live Meshcat.

    Not ``interactive`` (stdin is not a terminal): play it once and return.
    ``interactive``: play it in a loop (a second's pause between plays) until
    a line is read from ``stdin`` (Enter) or Ctrl-C. ``say`` prints the one
    line of instructions. Returns the number of plays.
    """
    if not interactive:
        view.play(realtime_rate)
        return 1
    stdin = sys.stdin if stdin is None else stdin
    done = threading.Event()

    def wait_for_enter() -> None:
        try:
            stdin.readline()
        finally:
            done.set()

    threading.Thread(target=wait_for_enter, name="meshcat-enter", daemon=True).start()
    say("Playing in a loop; press Enter or Ctrl-C to close the view.")
    plays = 0
    try:
        while not done.is_set():
            view.play(realtime_rate, sleep=done.wait, stop=done.is_set)
            plays += 1
            done.wait(_HOLD_S)
    except KeyboardInterrupt:
        pass
    return plays
