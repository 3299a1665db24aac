"""Seeing a Stewart run: magnified drawing, force arrow, recording, live view, progress."""

from __future__ import annotations

import base64
import io
import math
import re
import urllib.request

import numpy as np
import pytest

from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.progress import SimulatedTimeProgress
from hybridtable.stewart.view import (
    ARROW_PATH,
    DRAWN_FRACTION_OF_RADIUS,
    MotionView,
    StewartMotion,
    auto_force_scale_n_per_m,
    auto_magnify,
    open_meshcat,
    show_live,
)

HOME = np.array([0.0, 0.0, StewartParams().geometry.home_height_m])


def html_commands(html: str) -> bytes:
    """The msgpack'd Meshcat commands a static HTML page embeds (base64)."""
    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return b"".join(base64.b64decode(b) for b in blobs)


def motion(peak_m: float = 0.01, tilt_rad: float = 0.002, peak_force_n: float = 1500.0):
    """A plate that heaves by ``peak_m`` and tilts about x by ``tilt_rad`` over
    0.5 s (half a sine), pushed by a force following the heave."""
    t = np.linspace(0.0, 0.5, 501)
    s = np.sin(np.pi * t / 0.5)
    q = np.column_stack([np.cos(tilt_rad * s / 2), np.sin(tilt_rad * s / 2), 0 * s, 0 * s])
    position = HOME + np.outer(peak_m * s, [0.0, 0.0, 1.0])
    return StewartMotion(t, q, position, peak_force_n * s, HOME.copy())


@pytest.fixture(scope="module")
def meshcat():
    return open_meshcat()


def test_automatic_factors_are_round_and_draw_the_peak_at_a_tenth_of_the_radius():
    radius = StewartParams().geometry.top_radius_m
    # The default run: 17.1 mm peak on a 0.35 m radius -> x5 (86 mm <= 105 mm).
    assert auto_magnify(0.0171, radius) == 5.0
    for peak in (1e-4, 3e-3, 0.0171, 0.02):
        m = auto_magnify(peak, radius)
        assert m * peak <= DRAWN_FRACTION_OF_RADIUS * radius * (1 + 1e-12)
        assert m * peak > 0.4 * DRAWN_FRACTION_OF_RADIUS * radius  # next round step is too big
        assert m / 10 ** math.floor(math.log10(m)) in (1.0, 2.0, 5.0)
    assert auto_magnify(0.2, radius) == 1.0  # never shrinks
    assert auto_magnify(0.0, radius) == 1.0
    assert auto_force_scale_n_per_m(1709.0) == 5000.0  # 0.34 m of arrow
    assert auto_force_scale_n_per_m(900.0) == 2000.0  # 0.45 m
    assert 1709.0 / auto_force_scale_n_per_m(1709.0) <= 0.5


def test_drawn_pose_magnifies_displacement_and_keeps_the_mechanism_whole(meshcat):
    view = MotionView(meshcat, StewartParams(), motion(), magnify=3.0, force_scale_n_per_m=2000.0)
    position, rotation = view.drawn_pose(0.25)  # the peak
    assert position == pytest.approx(HOME + [0.0, 0.0, 0.03], abs=1e-12)
    assert rotation.ToAngleAxis().angle() == pytest.approx(0.006, rel=1e-9)
    assert view.arrow_length_m(0.25) == pytest.approx(1500.0 / 2000.0)
    assert view.arrow_length_m(0.0) == 0.0
    # The legs come from the inverse kinematics of the drawn pose: each piston's
    # end (the top joint) sits on the plate's joint point.
    handles = view._handles
    plant, context = handles.plant, view._plant_context
    handles.set_drawn_pose(context, position, rotation)
    X_plate = plant.EvalBodyPoseInWorld(context, handles.plate)
    top = handles.geometry.top_points_m
    for i, joint in enumerate(handles.leg_joints):
        X_piston = plant.EvalBodyPoseInWorld(context, joint.child_body())
        assert np.linalg.norm(X_piston.translation() - X_plate @ top[i]) < 1e-9


def test_recording_holds_the_magnified_motion_and_the_force_arrow(meshcat):
    view = MotionView(meshcat, StewartParams(), motion(), magnify=2.0)
    view.record(realtime_rate=0.5)
    commands = html_commands(view.html())
    assert f"/drake/{ARROW_PATH}/shaft".encode() in commands
    assert f"/drake/{ARROW_PATH}/head".encode() in commands
    assert b"set_animation" in commands
    assert b".scale" in commands and b".visible" in commands  # the arrow's tracks
    assert meshcat.HasPath(f"/drake/{ARROW_PATH}/shaft")
    # 0.5 s simulated at 64 frames per second.
    assert len(view.frame_times_s()) == 33


def test_live_view_answers_on_localhost_and_plays_at_the_realtime_rate(meshcat):
    url = meshcat.web_url()
    assert url.startswith("http://localhost:")
    with urllib.request.urlopen(url, timeout=10) as reply:
        assert reply.status == 200
    view = MotionView(meshcat, StewartParams(), motion())
    now = [0.0]
    slept = []

    def sleep(s):
        slept.append(s)
        now[0] += s

    wall = view.play(realtime_rate=0.25, clock=lambda: now[0], sleep=sleep)
    assert wall == pytest.approx(0.5 / 0.25, abs=1.0 / 64 / 0.25)
    # Not from a terminal: one play, no wait for Enter.
    plays = []
    view.play = lambda rate, **kw: plays.append(rate)
    assert show_live(view, 2.0, interactive=False) == 1 and plays == [2.0]


def test_interactive_live_view_closes_on_enter(meshcat):
    view = MotionView(meshcat, StewartParams(), motion())
    said = []
    plays = show_live(view, 50.0, interactive=True, stdin=io.StringIO("\n"), say=said.append)
    assert plays <= 2 and "Enter" in said[0]


def test_progress_bar_follows_simulated_time_and_changes_nothing():
    from hybridtable.stewart.identify import drive_table

    params = StewartParams()
    command = np.full(300, -2e-3)
    quiet, _ = drive_table(params, command, -2e-3)
    stream = io.StringIO()
    with SimulatedTimeProgress(file=stream, disable=False) as progress:
        shown, _ = drive_table(params, command, -2e-3, label="test drive")
    assert progress.stages == ["test drive"]
    assert "s simulated" in stream.getvalue() and "test drive" in stream.getvalue()
    np.testing.assert_array_equal(quiet, shown)


def test_motion_interpolates_pose_and_force():
    m = motion()
    position, q, force = m.at(0.25)
    assert position[2] - HOME[2] == pytest.approx(0.01, rel=1e-6)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    assert force == pytest.approx(1500.0, rel=1e-6)
    assert m.peak_displacement_m == pytest.approx(0.01, rel=1e-6)
