"""Stewart platform geometry: inverse / forward kinematics, workspace, plant assembly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from hybridtable.errors import ParameterError, WorkspaceError
from hybridtable.stewart.backend import StewartTable
from hybridtable.stewart.geometry import (
    StewartGeometry,
    cross,
    rotation_from_rpy,
    rpy_from_rotation,
)
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.plant import add_stewart_plant

GEOMETRIES = {
    "3-3": StewartGeometry(),
    "6-6": StewartGeometry(base_pair_angle_rad=0.3, top_pair_angle_rad=0.5, top_radius_m=0.4),
}


def _random_poses(geometry: StewartGeometry, n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    poses = []
    while len(poses) < n:
        pose = geometry.home_pose + np.concatenate(
            [rng.uniform(-0.08, 0.08, 3), rng.uniform(-0.15, 0.15, 3)]
        )
        try:
            geometry.inverse_kinematics(pose)
        except WorkspaceError:
            continue
        poses.append(pose)
    return poses


@pytest.mark.parametrize("name", sorted(GEOMETRIES))
def test_inverse_then_forward_kinematics_reproduces_the_pose(name):
    g = GEOMETRIES[name]
    for pose in _random_poses(g, 20, seed=1):
        lengths = g.inverse_kinematics(pose)
        found = g.forward_kinematics(lengths)  # Newton from home, not from the answer
        # Every top joint where it was: position error of the plate, not of angles.
        error = np.abs(g.leg_vectors(found) - g.leg_vectors(pose)).max()
        assert error < 1e-9
        np.testing.assert_allclose(found, pose, atol=1e-9)


def test_three_three_layout_shares_joints_and_pairs_are_apart_otherwise():
    g = GEOMETRIES["3-3"]
    base, top = g.base_points_m, g.top_points_m
    # Legs 2i+1 and 2i+2 share a base joint, legs 2i and 2i+1 a top joint.
    for i in range(3):
        np.testing.assert_allclose(top[2 * i], top[2 * i + 1], atol=1e-15)
        np.testing.assert_allclose(base[2 * i + 1], base[(2 * i + 2) % 6], atol=1e-15)
    g6 = GEOMETRIES["6-6"]
    gap = np.linalg.norm(g6.top_points_m[0] - g6.top_points_m[1])
    assert gap == pytest.approx(2 * 0.4 * math.sin(0.25), rel=1e-12)
    # Symmetric layout: pure heave keeps all legs equal.
    lengths = g.inverse_kinematics(g.axis_pose(0.05))
    assert np.ptp(lengths) < 1e-14


def test_leg_jacobian_matches_finite_differences():
    g = GEOMETRIES["6-6"]
    pose = _random_poses(g, 1, seed=3)[0]
    J = g.leg_jacobian(pose)
    R = rotation_from_rpy(pose[3:])
    eps = 1e-7
    for k in range(6):
        twist = np.zeros(6)
        twist[k] = eps
        # Move the plate by the twist: translation, then rotation about B's axes.
        w = twist[3:]
        theta = np.linalg.norm(w)
        K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        dR = np.eye(3) + K + (K @ K) / 2 if theta else np.eye(3)
        moved = np.concatenate([pose[:3] + twist[:3], rpy_from_rotation(dR @ R)])
        numeric = (g.inverse_kinematics(moved) - g.inverse_kinematics(pose)) / eps
        np.testing.assert_allclose(numeric, J[:, k], atol=1e-6)


def test_workspace_errors_name_the_leg_and_the_limit():
    g = GEOMETRIES["3-3"]
    with pytest.raises(WorkspaceError, match="stroke"):
        g.inverse_kinematics(g.axis_pose(0.5))
    stiff_joints = StewartGeometry(max_joint_angle_rad=0.1)
    with pytest.raises(WorkspaceError, match="tilts"):
        stiff_joints.inverse_kinematics(g.home_pose + np.array([0.15, 0, 0, 0, 0, 0]))
    with pytest.raises(WorkspaceError, match="above the base"):
        g.inverse_kinematics(np.array([0, 0, -0.8, 0, 0, 0]))
    with pytest.raises(WorkspaceError, match="stroke"):
        g.forward_kinematics(np.full(6, 2.0))
    assert issubclass(WorkspaceError, ParameterError)


def test_axis_workspace_ends_where_a_leg_reaches_its_stroke():
    g = GEOMETRIES["3-3"]
    lo, hi = g.axis_workspace()
    # All legs equal in heave: L^2 = r^2 + z^2 with r the horizontal leg span.
    r2 = g.inverse_kinematics(g.home_pose)[0] ** 2 - g.home_height_m**2
    assert hi == pytest.approx(math.sqrt(g.leg_max_length_m**2 - r2) - g.home_height_m, abs=1e-8)
    assert lo == pytest.approx(math.sqrt(g.leg_min_length_m**2 - r2) - g.home_height_m, abs=1e-8)
    g.inverse_kinematics(g.axis_pose(hi - 1e-6))
    with pytest.raises(WorkspaceError):
        g.inverse_kinematics(g.axis_pose(hi + 1e-6))


def test_geometry_validation():
    with pytest.raises(ParameterError, match="leg_min_length_m"):
        StewartGeometry(leg_min_length_m=1.2, leg_max_length_m=1.1)
    with pytest.raises(ParameterError, match="home pose"):
        StewartGeometry(home_height_m=2.0)
    with pytest.raises(ParameterError, match="triangle"):
        StewartGeometry(plate_inertia_kg_m2=(1.0, 1.0, 5.0))
    with pytest.raises(ParameterError, match="base_pair_angle_rad"):
        StewartGeometry(base_pair_angle_rad=-0.1)


def test_plant_state_satisfies_the_ball_constraints():
    params = StewartParams(gravity_m_per_s2=0.0)
    builder = DiagramBuilder()
    handles = add_stewart_plant(builder, params, 1e5)
    plant = handles.plant
    context = plant.CreateDefaultContext()
    offset, speed = -0.03, 0.2
    handles.set_axis_state(context, offset, speed)
    top = handles.geometry.top_points_m
    world = plant.world_frame()
    for i, joint in enumerate(handles.leg_joints):
        piston = joint.child_body()
        tip = plant.CalcPointsPositions(context, piston.body_frame(), np.zeros(3), world)[:, 0]
        on_plate = plant.CalcPointsPositions(context, handles.plate.body_frame(), top[i], world)
        np.testing.assert_allclose(tip, on_plate[:, 0], atol=1e-12)
        v_tip = plant.EvalBodySpatialVelocityInWorld(context, piston).translational()
        # The plate only translates: every point of it moves at [0, 0, speed].
        np.testing.assert_allclose(v_tip, [0.0, 0.0, speed], atol=1e-8)
    plate_z = plant.EvalBodyPoseInWorld(context, handles.plate).translation()[2]
    assert plate_z == pytest.approx(handles.geometry.home_height_m + offset, abs=1e-15)


def test_servo_holds_the_platform_still_against_gravity():
    # The static leg forces (constraint statics) make the held pose exact.
    params = StewartParams()
    builder = DiagramBuilder()
    table = builder.AddSystem(StewartTable(params, 1e5))
    command = builder.AddSystem(ConstantVectorSource(np.array([-0.01, 0.0])))
    builder.Connect(command.get_output_port(), table.GetInputPort("commanded_state"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    table.set_initial_state(table.GetMyMutableContextFromRoot(context), -0.01, 0.0)
    simulator.AdvanceTo(0.2)
    p, v, _ = table.GetOutputPort("motion").Eval(table.GetMyContextFromRoot(context))
    # Gravity feed-forward computed at home; 1 cm away the static error stays
    # below a micrometre (without it: m g / K ~ 40 um).
    assert abs(p + 0.01) < 1e-6
    assert abs(v) < 1e-5


def test_the_scalar_cross_product_is_numpy_s_bit_for_bit():
    """``cross`` (the 6-DoF contact's moments, the F/T device's kinematics) is
    ``np.cross`` of two 3-vectors, the same bits: the same products and
    differences in the same order; and anticommutative, orthogonal to both."""
    rng = np.random.default_rng(3)
    for _ in range(2000):
        a, b = rng.normal(size=3) * 10.0 ** rng.integers(-6, 6), rng.normal(size=3)
        c = cross(a, b)
        assert np.array_equal(c, np.cross(a, b))
        assert np.array_equal(cross(b, a), -c)
        assert abs(c @ a) <= 1e-12 * np.linalg.norm(a) ** 2 * np.linalg.norm(b)
