"""The Meshcat recording of a 6-DoF run: frames, the force arrow, the centre of
pressure, the magnified motion and the Stewart legs, read back from the HTML."""

from __future__ import annotations

import base64
import math
import re

import msgpack
import numpy as np
import pytest

from hybridtable.errors import ParameterError
from hybridtable.six_dof.pose import rotation_exp
from hybridtable.six_dof.simulation import DockingRun, simulate6
from hybridtable.six_dof.view import (
    HOLD_S,
    ROOT,
    DockingScene,
    centre_of_pressure_m,
    write_docking_html,
)
from hybridtable.stewart.geometry import StewartGeometry
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.view import FRAMES_PER_SECOND, open_meshcat
from tests.six_dof.conftest import docking_params

#: Two 0.2 s runs of the table model (25 Hz, 5 ms delay, SDMDC): on axis, and
#: pitched by 0.035 rad so that one side of the ring touches first.
PITCH_RAD = 0.035


def _run(pitch_rad: float) -> DockingRun:
    params = docking_params(
        pitch_deg=math.degrees(pitch_rad),
        duration_s=0.2,
        table_response_hz=25.0,
        sensor_delay_s=0.005,
        compensator="SDMDC",
    )
    return simulate6(params)


@pytest.fixture(scope="module")
def runs() -> dict[str, DockingRun]:
    return {"on_axis": _run(0.0), "tilted": _run(PITCH_RAD)}


@pytest.fixture(scope="module")
def pages(runs, tmp_path_factory):
    """name -> (HTML path, returned dict, animation tracks)."""
    folder = tmp_path_factory.mktemp("six_dof_view")
    out = {}
    for name, run in runs.items():
        path = folder / f"{name}.html"
        info = write_docking_html(run, path)
        out[name] = (path, info, _tracks(path.read_text()))
    return out


def _tracks(html: str) -> dict[tuple[str, str], list[tuple[int, object]]]:
    """``(path, track) -> [(frame, value)]`` of the Meshcat animation the page embeds."""
    tracks = {}
    for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        message = msgpack.unpackb(base64.b64decode(blob), raw=False, strict_map_key=False)
        if message.get("type") != "set_animation":
            continue
        for animation in message["animations"]:
            assert animation["clip"]["fps"] == FRAMES_PER_SECOND
            for track in animation["clip"]["tracks"]:
                keys = [(k["time"], k["value"]) for k in track["keys"]]
                tracks[(animation["path"], track["name"])] = keys
    return tracks


def _path(name: str) -> str:
    return f"/drake/{ROOT}/{name}"


def _peak(run: DockingRun) -> tuple[int, float]:
    force = np.linalg.norm(run.log["contact_wrench"][:, 3:6], axis=1)
    return int(np.argmax(force)), float(np.max(force))


@pytest.fixture(scope="module")
def meshcat():
    return open_meshcat()


def test_recording_has_one_frame_per_frame_period_of_the_run(runs, pages):
    for name, run in runs.items():
        _, info, tracks = pages[name]
        duration = float(run.time_s[-1])
        assert duration == pytest.approx(0.199)  # 200 ticks of 1 ms
        assert info["duration_s"] == pytest.approx(duration)
        frames = math.floor(duration * FRAMES_PER_SECOND) + 1
        assert info["frames"] == frames == 13
        assert info["frames_per_second"] == FRAMES_PER_SECOND
        # Frame j at j / fps, then the last frame held for HOLD_S.
        hold = frames - 1 + round(HOLD_S * FRAMES_PER_SECOND)
        for part in ("device", "spacecraft", "legs/0"):
            keys = [f for f, _ in tracks[(_path(part), ".position")]]
            assert keys == [*range(frames), hold]


def test_arrow_is_force_over_scale_and_its_longest_is_the_peak(runs, pages, meshcat):
    for name, run in runs.items():
        _, info, tracks = pages[name]
        _, peak_n = _peak(run)
        scale = info["force_scale_n_per_m"]
        # The automatic scale is round and draws the peak at most 0.5 m long.
        assert scale / 10 ** math.floor(math.log10(scale)) in (1.0, 2.0, 5.0)
        assert 0.2 < peak_n / scale <= 0.5
        assert info["peak_force_n"] == pytest.approx(peak_n, rel=1e-12)
        # The head's point is the arrow's tip: its z in the arrow's frame is the length.
        drawn = {f: v[2] for f, v in tracks[(_path("force/head"), ".position")]}
        assert max(drawn.values()) == pytest.approx(peak_n / scale, rel=1e-12)
        assert info["peak_arrow_m"] == pytest.approx(peak_n / scale, rel=1e-12)
        # Every frame: |force| / scale of the sample it shows; no arrow before contact.
        scene = DockingScene(meshcat, run, force_scale_n_per_m=scale)
        force = np.linalg.norm(run.log["contact_wrench"][:, 3:6], axis=1)
        visible = dict(tracks[(_path("force"), ".visible")])
        for j, index in enumerate(scene.frame_indices()):
            assert visible[j] == (force[index] > 0.0)
            if force[index] > 0.0:
                assert drawn[j] == pytest.approx(force[index] / scale, rel=1e-12)
        assert not visible[0]


def test_centre_of_pressure_on_axis_and_on_the_side_that_touches_first(runs):
    c = runs["on_axis"].params.contact
    for name, run in runs.items():
        for index in np.flatnonzero(np.linalg.norm(run.log["contact_wrench"][:, 3:], axis=1)):
            q = run.log["table_state"][index, :6]
            R = rotation_exp(q[3:6])
            cop = centre_of_pressure_m(run.log["contact_wrench"][index], q[:3], R)
            # In the port's face plane, within the ring of pads (the force along
            # W's z crosses the tilted face a little beyond a pad's centre).
            assert abs((cop - q[:3]) @ R[:, 2]) < 1e-12
            lateral = cop - q[:3]
            if name == "on_axis":
                assert np.linalg.norm(lateral) < 1e-9
            else:
                assert np.linalg.norm(lateral) < c.ring_radius_m + c.pad_radius_m
    run = runs["tilted"]
    force = np.linalg.norm(run.log["contact_wrench"][:, 3:], axis=1)
    first = int(np.flatnonzero(force)[0])
    q = run.log["table_state"][first, :6]
    pads = q[:3] + c.pad_centres_m @ rotation_exp(q[3:6]).T
    touching = pads[np.argmax(pads[:, 2])]  # the lowest pad (pitch > 0: at -x)
    assert touching[0] < -0.29
    peak, _ = _peak(run)
    q = run.log["table_state"][peak, :6]
    cop = centre_of_pressure_m(run.log["contact_wrench"][peak], q[:3], rotation_exp(q[3:6]))
    # At the peak (0.2 s) more pads touch, yet the force's centre stays on
    # that side, about two thirds of the way out.
    direction = (touching - q[:3])[:2] / np.linalg.norm((touching - q[:3])[:2])
    assert (cop - q[:3])[:2] @ direction > 0.5 * c.ring_radius_m


def test_centre_of_pressure_of_one_force_is_its_point():
    rng = np.random.default_rng(3)
    for _ in range(20):
        R = rotation_exp(rng.normal(scale=0.3, size=3))
        p = rng.normal(size=3)
        point = p + R @ np.array([*rng.normal(scale=0.3, size=2), 0.0])
        f = R @ np.array([*rng.normal(scale=100.0, size=2), -1000.0])
        wrench = np.concatenate([np.cross(point - p, f), f])
        assert centre_of_pressure_m(wrench, p, R) == pytest.approx(point, abs=1e-12)
    assert centre_of_pressure_m(np.zeros(6), np.zeros(3), np.eye(3)) is None


def test_motion_is_magnified_about_the_docked_pose(runs, pages, meshcat):
    run = runs["tilted"]
    _, info, tracks = pages["tilted"]
    m = info["magnify"]
    # Automatic: a round factor drawing the peak displacement at <= 0.3 ring radius.
    assert m / 10 ** math.floor(math.log10(m)) in (1.0, 2.0, 5.0) and m > 1.0
    assert m * info["peak_displacement_m"] <= 0.3 * run.params.contact.ring_radius_m
    scene = DockingScene(meshcat, run, magnify=m)
    drawn = dict(tracks[(_path("device"), ".position")])
    table = run.log["table_state"]
    for j, index in enumerate(scene.frame_indices()):
        assert drawn[j] == pytest.approx(m * table[index, :3], abs=1e-12)
        # The rotation angle too: the drawn pitch is m times the table's.
        _, R = scene.device_pose(index)
        angle = math.acos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
        assert angle == pytest.approx(m * np.linalg.norm(table[index, 3:6]), rel=1e-9)


def test_legs_join_the_base_to_the_drawn_plate_and_stewart_runs_use_their_geometry(runs, meshcat):
    run = runs["tilted"]
    scene = DockingScene(meshcat, run, magnify=20.0)
    g = scene.geometry
    assert g == StewartGeometry()
    peak, _ = _peak(run)
    base, legs = scene.legs(peak)
    p, R = scene.device_pose(peak)
    plate = p - R[:, 2] * g.device_length_m
    np.testing.assert_allclose(base + legs, plate + g.top_points_m @ R.T, atol=1e-12)
    # At the docked pose the drawn table is at the platform's home.
    docked = DockingRun(run.params, run.time_s[:1], {k: 0 * v[:1] for k, v in run.log.items()})
    docked.log["body_state"][0, 6:15] = np.eye(3).ravel()
    _, legs0 = DockingScene(meshcat, docked).legs(0)
    np.testing.assert_allclose(
        np.linalg.norm(legs0, axis=1), g.inverse_kinematics(g.home_pose), atol=1e-12
    )
    tall = StewartParams(geometry=StewartGeometry(home_height_m=0.9, leg_max_length_m=1.3))
    stewart_run = DockingRun(run.params.with_(table="stewart", stewart=tall), run.time_s, run.log)
    assert DockingScene(meshcat, stewart_run).geometry.home_height_m == 0.9


def test_html_is_self_contained_and_never_overwritten(runs, pages):
    path, info, _ = pages["on_axis"]
    html = path.read_text()
    assert info["bytes"] == len(html.encode()) == path.stat().st_size
    assert 1e6 < info["bytes"] < 5e6
    sources = re.findall(r"<script[^>]*\bsrc\s*=\s*[\"']?([^\"' >]+)", html, re.I)
    assert [s for s in sources if not s.startswith("data:")] == []
    assert not re.search(r"<link[^>]*href\s*=\s*[\"']?https?:", html, re.I)
    before = path.stat().st_mtime_ns
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        write_docking_html(runs["tilted"], path)
    assert path.read_text() == html and path.stat().st_mtime_ns == before
    again = write_docking_html(runs["tilted"], path, magnify=3.0, overwrite=True)
    assert again["magnify"] == 3.0 and path.read_text() != html


@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_factors_must_be_finite_and_positive(runs, meshcat, bad):
    with pytest.raises(ParameterError, match="magnify"):
        DockingScene(meshcat, runs["on_axis"], magnify=bad)
    with pytest.raises(ParameterError, match="force_scale_n_per_m"):
        DockingScene(meshcat, runs["on_axis"], force_scale_n_per_m=bad)
