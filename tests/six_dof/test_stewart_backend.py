"""The Stewart platform as the 6-DoF loop's table: full-pose inverse
kinematics, the payload-compensated F/T reading, the CoR against the 1-D
Stewart loop, and the workspace refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput, ZeroOrderHold

from hybridtable.errors import WorkspaceError
from hybridtable.loop.simulation import run_loop
from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.params import ApproachParams, DockingContactParams
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.six_dof.simulation import simulate6
from hybridtable.six_dof.stewart_backend import (
    PoseKinematics,
    StewartPoseBackend,
    check_stewart_scenario,
)
from hybridtable.stewart.backend import build_stewart_loop
from hybridtable.stewart.geometry import StewartGeometry, rpy_from_rotation
from hybridtable.stewart.params import StewartParams
from hybridtable.studies.paper import table1_params
from tests.six_dof.conftest import MASS_KG, docking_params

#: A tilted, offset port pose (m, rad) and a twist (m/s, rad/s) in W.
POSE = np.array([0.012, -0.008, -0.015, 0.04, -0.03, 0.05])
TWIST = np.array([0.02, -0.01, 0.08, 0.1, -0.2, 0.15])


def test_full_pose_ik_is_the_geometry_s():
    """At a tilted, offset pose the six leg lengths are
    StewartGeometry.inverse_kinematics of the plate's pose (the port sits
    device_length_m above the plate along its normal, W's origin on the
    plate's face above home); the rates are the leg Jacobian times the
    plate's twist and the derivative of the lengths along the motion."""
    g = StewartGeometry()
    kin = PoseKinematics(g)
    R = rotation_exp(POSE[3:])
    plate = np.array([0, 0, g.home_height_m + g.device_length_m]) + POSE[:3]
    plate -= R @ [0.0, 0.0, g.device_length_m]
    pose = np.concatenate([plate, rpy_from_rotation(R)])
    lengths, rates = kin.inverse_kinematics(POSE, TWIST)
    np.testing.assert_allclose(lengths, g.inverse_kinematics(pose), rtol=0, atol=1e-14)
    # The plate's twist from the port's: v_plate = v_port - omega x (R d).
    omega = TWIST[3:]
    v_plate = TWIST[:3] - np.cross(omega, R @ [0.0, 0.0, g.device_length_m])
    np.testing.assert_allclose(
        rates, g.leg_jacobian(pose) @ np.concatenate([v_plate, omega]), atol=1e-14
    )
    eps = 1e-6

    def moved(s):
        q = POSE.copy()
        q[:3] += s * eps * TWIST[:3]
        q[3:] = rotation_log(rotation_exp(s * eps * omega) @ R)
        return kin.leg_lengths(q)

    np.testing.assert_allclose(rates, (moved(1) - moved(-1)) / (2 * eps), atol=1e-8)
    # At home the port's face is on the plate's face: all legs at home length.
    np.testing.assert_allclose(kin.leg_lengths(np.zeros(6)), g.inverse_kinematics(g.home_pose))


def test_initial_state_puts_the_port_at_the_pose_with_its_twist():
    """set_initial_state: the table_state output at t = 0 is the given pose
    and twist, and the legs' reference sits at those lengths and rates."""
    backend = StewartPoseBackend(docking_params(table="stewart"))
    context = backend.CreateDefaultContext()
    state = np.concatenate([POSE, TWIST])
    backend.set_initial_state(context, state, state)
    backend.GetInputPort("commanded_state").FixValue(context, state)
    np.testing.assert_allclose(
        backend.GetOutputPort("table_state").Eval(context), state, atol=1e-12
    )
    assert not np.any(backend.GetOutputPort("contact_wrench").Eval(context))


class _TiltedSinusoid(LeafSystem):
    """A commanded port pose swinging 3 Hz in all six coordinates, 20 mm below
    the plate: lateral +-4 mm, heave +-5 mm, tilts up to +-1.7 deg."""

    AMPLITUDE = np.array([0.004, -0.003, 0.005, 0.03, -0.02, 0.01])

    def __init__(self):
        LeafSystem.__init__(self)
        self.DeclareVectorOutputPort("command", BasicVector(12), self._calc)

    def _calc(self, context, output):
        w = 2 * math.pi * 3.0
        phase = w * context.get_time() + 0.5 * np.arange(6)
        q = self.AMPLITUDE * np.sin(phase)
        q[2] -= 0.02
        output.SetFromVector(np.concatenate([q, self.AMPLITUDE * w * np.cos(phase)]))


def test_payload_compensation_reads_zero_while_the_plate_swings():
    """Devices apart, the plate driven through a tilted 3 Hz sinusoid: the F/T
    reading corrected for the device's weight and inertia stays below 1e-9 N
    and N m (measured 1e-14, with the sensor's rounding off), while the
    weld's raw force carries the weight (14.7 N) and, minus the weight, an
    inertial swing of several newtons (the correction is not a constant)."""
    stewart = StewartParams(sensor_resolution_n=1e-12)
    params = docking_params(table="stewart", stewart=stewart)
    h = params.sample_period_s
    builder = DiagramBuilder()
    backend = builder.AddSystem(StewartPoseBackend(params))
    source = builder.AddSystem(_TiltedSinusoid())
    computer = builder.AddSystem(ZeroOrderHold(h, 12))
    builder.Connect(source.get_output_port(), computer.get_input_port())
    builder.Connect(computer.get_output_port(), backend.GetInputPort("commanded_state"))
    logs = {
        name: LogVectorOutput(backend.GetOutputPort(name), builder, h)
        for name in ("table_state", "contact_wrench", "weld_wrench")
    }
    command_log = LogVectorOutput(computer.get_output_port(), builder, h)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    x0 = source.get_output_port().Eval(source.GetMyContextFromRoot(context)).copy()
    computer.GetMyMutableContextFromRoot(context).SetDiscreteState(x0)
    backend.set_initial_state(backend.GetMyMutableContextFromRoot(context), x0, x0)
    simulator.AdvanceTo(0.6)
    log = {name: sink.FindLog(context).data().T for name, sink in logs.items()}
    command = command_log.FindLog(context).data().T
    # The plate really swings and tilts (after the reference model's start).
    assert np.ptp(log["table_state"][200:, 3]) > 0.05
    np.testing.assert_allclose(log["table_state"][200:, :6], command[200:, :6], atol=0.007)
    assert np.max(np.abs(log["contact_wrench"])) < 1e-9
    raw = log["weld_wrench"][1:, 3:]
    weight = params.stewart.geometry.device_mass_kg * params.stewart.gravity_m_per_s2
    assert np.min(np.linalg.norm(raw, axis=1)) > 0.2 * weight
    inertial = raw - [0.0, 0.0, weight]
    assert np.max(np.linalg.norm(inertial, axis=1)) > 5.0
    assert np.max(np.linalg.norm(log["weld_wrench"][1:, :3], axis=1)) > 0.5


def _one_d_stewart_cor(compensator: str, table_start: np.ndarray) -> float:
    """The 1-D Stewart loop with the same plant step and the same reference
    model (StewartParams' 25 Hz, 0.8, untuned), its table started where the
    6-DoF loop started its table (``table_start``: the logged table_state at
    t = 0; on axis the port's z is the 1-D penetration)."""
    params = table1_params(
        compensator,
        sample_rate_hz=1000.0,
        table_initial_state="given",
        table_initial_position_m=float(table_start[2]),
        table_initial_velocity_m_per_s=float(table_start[8]),
    )
    assert params.spacecraft_mass_kg == pytest.approx(MASS_KG)
    return run_loop(build_stewart_loop(params, StewartParams())).metrics.cor


@pytest.mark.parametrize(
    "compensator,stiffness_model,tolerance",
    [("none", "linearized", 1e-4), ("SDMDC", "nominal", 1e-4), ("SDMDC", "linearized", 0.01)],
)
def test_on_axis_cor_is_the_1d_stewart_loop_s(compensator, stiffness_model, tolerance):
    """Table 1 point on the Stewart table (2533 kg, 1e5 N/m, 0.1 m/s, 5 ms,
    1 kHz): the 6-DoF loop gives the 1-D Stewart loop's CoR. Measured: none
    1.166436 vs 1.166436 (2e-7), SDMDC with the 1-D MDC's constant k
    (nominal) 1.000077 vs 1.000077, SDMDC with K linearized at the
    table's pose 1.0022."""
    params = docking_params(
        sensor_delay_s=0.005,
        table="stewart",
        compensator=compensator,
        stiffness_model=stiffness_model,
    )
    check_stewart_scenario(params)
    run = simulate6(params)
    expected = _one_d_stewart_cor(compensator, run.log["table_state"][0])
    assert run.metrics.cor_normal == pytest.approx(expected, abs=tolerance)
    assert expected > 1.1 if compensator == "none" else abs(expected - 1.0) < 0.01
    # On axis nothing turns or slides.
    assert run.metrics.rotational_energy_j < 1e-9
    assert np.max(np.abs(run.log["table_state"][:, [0, 1, 3, 4, 5]])) < 1e-9


def test_off_axis_the_sensor_reads_drake_s_contact_at_the_table_s_pose():
    """Offset 10 mm, tilt 2 deg: in contact, the back-end's F/T reading is the
    devices' contact wrench evaluated at the table's actual pose and twist
    (DockingContact), moment about the port origin included, within 0.5 % of
    the peaks (the plant's contact is discrete, implicit in the stiffness)."""
    params = docking_params(
        0.01, 2.0, sensor_delay_s=0.005, table="stewart", compensator="SDMDC",
        stiffness_model="nominal",
    )  # fmt: skip
    run = simulate6(params)
    wrench, table = run.log["contact_wrench"], run.log["table_state"]
    touching = np.flatnonzero(np.linalg.norm(wrench[:, 3:], axis=1) > 0)
    assert touching.size > 300
    contact = DockingContact(params.contact)
    expected = np.array([contact.wrench(table[k, :6], table[k, 6:]) for k in touching])
    peak_force = np.max(np.abs(expected[:, 5]))
    peak_moment = np.max(np.linalg.norm(expected[:, :3], axis=1))
    assert peak_moment > 100.0  # the tilted ring presses on one side
    assert np.max(np.abs(wrench[touching, 3:] - expected[:, 3:])) < 0.005 * peak_force
    assert np.max(np.abs(wrench[touching, :3] - expected[:, :3])) < 0.005 * peak_moment


def test_a_pose_past_a_leg_s_stroke_is_refused():
    """The IK refuses a port 0.3 m into the plate (past the legs' 1.15 m) in
    one line naming the pose and the leg, and so does the running loop's
    servo; a pose with a tiny condition limit is refused as a singularity."""
    kin = PoseKinematics(StewartGeometry())
    with pytest.raises(WorkspaceError, match=r"port at \[0, 0, 0\.3\] m.*leg \d length"):
        kin.leg_lengths(np.array([0.0, 0.0, 0.3, 0.0, 0.0, 0.0]))
    with pytest.raises(WorkspaceError, match="singularity.*condition number.*leg \\d"):
        PoseKinematics(StewartGeometry(), max_condition_number=1.5).leg_lengths(POSE)

    params = docking_params(table="stewart")
    builder = DiagramBuilder()
    backend = builder.AddSystem(StewartPoseBackend(params))
    far = np.zeros(12)
    far[2] = 0.3
    source = builder.AddSystem(ConstantVectorSource(far))
    builder.Connect(source.get_output_port(), backend.GetInputPort("commanded_state"))
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    backend.set_initial_state(backend.GetMyMutableContextFromRoot(context), np.zeros(12), far)
    with pytest.raises(WorkspaceError, match="outside the Stewart platform's workspace") as err:
        simulator.AdvanceTo(0.01)
    assert "\n" not in str(err.value)


def test_the_scenario_check_refuses_an_unreachable_approach():
    """Before any run: the Table 1 scenario with a 2 deg tilt passes; a fast
    approach into a soft contact (3 v0 / omega = 1.7 m deep) and a 0.3 m
    initial gap are refused in one line naming what to change."""
    check_stewart_scenario(docking_params(0.01, 2.0, table="stewart"))
    soft = docking_params(table="stewart")
    soft = soft.with_(approach=ApproachParams(0.5, 0.001))
    soft = soft.with_(contact=DockingContactParams(2e3))
    with pytest.raises(WorkspaceError, match="initial_velocity_m_per_s") as err:
        check_stewart_scenario(soft)
    assert "\n" not in str(err.value) and "leg " in str(err.value)
    far = docking_params(table="stewart")
    far = far.with_(approach=ApproachParams(0.1, 0.3))
    with pytest.raises(WorkspaceError, match="initial_gap_m 0.3"):
        check_stewart_scenario(far)
