"""The Stewart platform as the table back-end of the 6-DoF docking loop.

The platform of :mod:`hybridtable.stewart` (MultibodyPlant, digital leg
servo, F/T sensor on the weld of the device to the plate) carries the
6-DoF docking devices (:func:`~hybridtable.six_dof.contact.register_docking_devices`:
the ring of pads on the device, the plate fixed above the platform) and
follows the full pose the spacecraft model commands.

Frames. The Stewart world has its origin at the centre of the base joint
circle and ``z`` up, the docking axis. The target frame W of the loop has
the same axes and its origin on the passive plate's face, at
``home_height_m + device_length_m`` above the base: at the plate's home pose
the port's face (the pads' tops) just touches the plate. The port frame P is
fixed on the device, ``device_length_m`` above the plate frame along the
plate normal, with the plate's axes. So with the port at ``q = [p; theta]``
(W; ``R = exp([theta]x)``) the plate frame is at
``o_W + p - R [0, 0, device_length_m]`` in the world.

Each tick of the rig computer (the plant's time step):

1. the full-pose inverse kinematics of the commanded port pose gives the six
   leg lengths (:meth:`~hybridtable.stewart.geometry.StewartGeometry.inverse_kinematics`
   checks: stroke, universal-joint limits, plate above the base) and, from the
   leg Jacobian times the plate's twist, their rates; a pose outside the
   workspace, or where the leg Jacobian's condition number exceeds
   :data:`MAX_CONDITION_NUMBER`, raises :class:`~hybridtable.errors.WorkspaceError`;
2. each leg length passes through the identified actuator response, the
   discrete second-order reference model of
   :func:`~hybridtable.stewart.params.reference_matrices` (exact for the
   command held over the tick; it takes the length only, the rates set its
   initial state);
3. the legs' digital PD servo with the static gravity feed-forward,
   :class:`~hybridtable.stewart.servo.LegServo` (the 1-D back-end's, Drake's
   primitives), tracks the reference (without a reference model: the
   commanded lengths at zero rate);
4. the F/T sensor (:class:`PoseDeviceSensor`) reads the weld's reaction
   wrench and corrects it for the device's weight and inertia by
   Newton–Euler (:mod:`hybridtable.stewart.ft_sensor`): the contact wrench
   on the device about the port origin, in W; it is held one tick, as in the
   1-D back-end, so the loop reads at tick ``k`` the wrench of the step
   ending at ``t_k`` with the pose at ``t_k``.

:func:`check_stewart_scenario` refuses, before any simulation, a scenario
whose approach the platform cannot follow.

Why one module: the kinematics, the three systems of the back-end and the
scenario check all rest on the frames above (W on the plate's face, the port
above the plate); kept together, that convention is written once.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.framework import BasicVector, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import (
    LinearSystem,
    ZeroOrderHold,
)

from hybridtable.errors import ParameterError, WorkspaceError
from hybridtable.six_dof.contact import port_start_z_m, register_docking_devices
from hybridtable.six_dof.drogue import floor_depth_m
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.six_dof.pose_kinematics import MAX_CONDITION_NUMBER, PoseKinematics
from hybridtable.stewart.backend import connect_servo_and_device, export_plate_pose
from hybridtable.stewart.ft_sensor import DeviceSensorBase
from hybridtable.stewart.geometry import (
    rotation_from_rpy,
    rpy_from_rotation,
)
from hybridtable.stewart.params import StewartParams, reference_matrices
from hybridtable.stewart.plant import StewartPlant, add_stewart_plant
from hybridtable.stewart.servo import LegServo

__all__ = [
    "MAX_CONDITION_NUMBER",
    "PoseKinematics",
    "PoseInverseKinematics",
    "PoseDeviceSensor",
    "StewartPoseBackend",
    "stewart_params_for_docking",
    "set_plate_state",
    "check_stewart_scenario",
]


class PoseInverseKinematics(LeafSystem):
    """The full-pose inverse kinematics of the commanded port pose.

    Ports
    -----
    Input ``commanded_state`` (12: m, rad, m/s, rad/s)
        ``[q; qd]`` of the port in W.
    Output ``leg_command`` (12: m, m/s)
        The six leg lengths and their rates (leg Jacobian times the plate's twist).

    Raises :class:`~hybridtable.errors.WorkspaceError` during a simulation
    when the commanded pose leaves the workspace or nears a singularity.
    """

    def __init__(self, kinematics: PoseKinematics) -> None:
        LeafSystem.__init__(self)
        self.kinematics = kinematics
        self._command = self.DeclareVectorInputPort("commanded_state", 12)
        self.DeclareVectorOutputPort("leg_command", BasicVector(12), self._calc)

    def _calc(self, context, output) -> None:
        x = self._command.Eval(context)
        output.SetFromVector(self.kinematics.commanded_legs(x))


class PoseDeviceSensor(DeviceSensorBase):
    """The port's motion and the F/T sensor's wrench, in the target frame W.

    The plant's reaction forces and accelerations (unsampled output ports)
    belong to the step that starts at the current tick; :class:`StewartPoseBackend`
    holds ``step_wrench`` one tick (as the 1-D
    :class:`~hybridtable.stewart.backend.DeviceSensor`).

    Ports
    -----
    Input ``plant_state``, ``generalized_acceleration``, ``reaction_forces``
        From the plant.
    Output ``port_state`` (12: m, rad, m/s, rad/s)
        ``[p_P; theta; v_P; omega]`` of the device's port in W (the table's
        actual pose and twist).
    Output ``step_wrench`` (6: N m, N)
        Over the coming step: the contact wrench on the device ``[moment
        about the port origin; force]`` in W, from the weld's reaction wrench
        corrected for the device's weight and inertia by Newton–Euler
        (:func:`~hybridtable.stewart.ft_sensor.payload_compensated_wrench`:
        what a 6-axis F/T sensor with payload compensation reports), each
        component rounded to ``sensor_resolution_n`` (N, and N m) so the
        round-off of the correction reads as an exact zero with the devices
        apart.
    Output ``weld_wrench`` (6: N m, N)
        The weld's raw reaction wrench on the device ``[torque about the
        plate origin; force]`` in W, over the coming step.
    """

    def __init__(self, handles: StewartPlant, kinematics: PoseKinematics) -> None:
        DeviceSensorBase.__init__(self, handles)
        self._k = kinematics
        self.DeclareVectorOutputPort(
            "port_state",
            BasicVector(12),
            self._calc_port_state,
            prerequisites_of_calc={self._state.ticket()},
        )
        self.DeclareVectorOutputPort("step_wrench", BasicVector(6), self._calc_step_wrench)
        self.DeclareVectorOutputPort("weld_wrench", BasicVector(6), self._calc_weld_wrench)

    def _calc_port_state(self, context, output) -> None:
        x = self._state.Eval(context)
        output.SetFromVector(self._k.port_state_of_plant(x, self._iq, self._nq + self._iv))

    def contact_wrench(self, context) -> np.ndarray:
        """The payload-compensated wrench (6, W, unrounded) over the coming step:
        the contact's moment about the port origin."""
        return self._compensated(context, self._k.port_in_plate_m)[4]

    def _calc_step_wrench(self, context, output) -> None:
        res = self._resolution
        output.SetFromVector(res * np.round(self.contact_wrench(context) / res))

    def _calc_weld_wrench(self, context, output) -> None:
        R = self._pose_twist(self._state.Eval(context))[0]
        F = self._weld_wrench(context)
        output.SetFromVector(np.concatenate([R @ F.rotational(), R @ F.translational()]))


def stewart_params_for_docking(params: DockingLoopParams) -> StewartParams:
    """The platform of ``params`` (``params.stewart``, default
    ``StewartParams()``) with its time step set to the rig computer's tick,
    so the plant, its servo and the loop share one period.

    Raises
    ------
    ParameterError
        If the platform cannot run at that tick (e.g. a reference model above
        the Nyquist rate).
    """
    stewart = params.stewart if isinstance(params.stewart, StewartParams) else StewartParams()
    h = params.sample_period_s
    if stewart.time_step_s != h:
        try:
            stewart = replace(stewart, time_step_s=h)
        except ParameterError as err:
            raise ParameterError(
                f"the Stewart platform cannot run at sample_rate_hz {params.sample_rate_hz:g}: "
                f"{err}"
            ) from None
    return stewart


def set_plate_state(
    handles: StewartPlant,
    plant_context,
    position_m: np.ndarray,
    rotation: np.ndarray,
    velocity_m_per_s: np.ndarray,
    angular_velocity_rad_per_s: np.ndarray,
) -> None:
    """Put the plate at ``position_m`` (world, m) with ``rotation`` (3x3),
    moving with the origin's velocity and the angular velocity (world): plate
    pose and twist, leg lengths and rates, universal-joint angles and rates,
    all consistent with the ball constraints (the full-pose generalization of
    :meth:`~hybridtable.stewart.plant.StewartPlant.set_axis_state`).

    Raises
    ------
    WorkspaceError
        If the pose leaves the workspace.
    """
    g = handles.geometry
    p = np.asarray(position_m, dtype=float)
    R = np.asarray(rotation, dtype=float)
    v = np.asarray(velocity_m_per_s, dtype=float)
    w = np.asarray(angular_velocity_rad_per_s, dtype=float)
    pose = np.concatenate([p, rpy_from_rotation(R)])
    g.inverse_kinematics(pose)  # raises outside the workspace
    lengths, angles = handles._leg_coordinates_at(pose)
    rates = g.leg_jacobian(pose) @ np.concatenate([v, w])
    eps = 1e-6

    def moved(sign: float) -> np.ndarray:
        Rs = rotation_exp(sign * eps * w) @ R
        return np.concatenate([p + sign * eps * v, rpy_from_rotation(Rs)])

    angle_rates = (
        handles._leg_coordinates_at(moved(1.0))[1] - handles._leg_coordinates_at(moved(-1.0))[1]
    ) / (2.0 * eps)
    plant = handles.plant
    plant.SetFreeBodyPose(plant_context, handles.plate, RigidTransform(RotationMatrix(R), p))
    plant.SetFreeBodySpatialVelocity(plant_context, handles.plate, SpatialVelocity(w, v))
    for i in range(6):
        handles.leg_joints[i].set_translation(plant_context, lengths[i])
        handles.leg_joints[i].set_translation_rate(plant_context, rates[i])
        handles.universal_joints[i].set_angles(plant_context, angles[i])
        handles.universal_joints[i].set_angular_rates(plant_context, angle_rates[i])


class StewartPoseBackend(Diagram):
    """The Stewart platform as a table back-end of the 6-DoF loop.

    Inside: ``commanded_state`` -> :class:`PoseInverseKinematics` ->
    per-leg reference model (if any) -> :class:`~hybridtable.stewart.servo.LegServo` -> plant (with
    the docking devices) -> :class:`PoseDeviceSensor` -> one-tick hold of the
    wrench -> ``contact_wrench``.

    Ports
    -----
    Input ``commanded_state`` (12: m, rad, m/s, rad/s)
        The port's commanded pose ``[p; theta]`` and twist ``[v; omega]`` in W.
    Output ``table_state`` (12)
        The device port's actual pose and twist in W, from the plant's state.
    Output ``contact_wrench`` (6: N m, N)
        The payload-compensated F/T reading ``[moment about the port origin;
        force]`` in W, on the device (of the step ending at the current tick).
    Output ``weld_wrench`` (6: N m, N)
        The weld's raw reaction wrench in W (not held: over the coming step).
    Output ``plate_pose`` (7: 1, m)
        The plate's quaternion ``[w, x, y, z]`` and position in the world.

    Parameters
    ----------
    params : DockingLoopParams
        ``params.stewart`` is the platform (its time step becomes the tick),
        ``params.contact`` the devices.
    meshcat : Meshcat, optional
        Visualize the platform in this Meshcat.
    """

    def __init__(self, params: DockingLoopParams, meshcat: Meshcat | None = None) -> None:
        Diagram.__init__(self)
        stewart = stewart_params_for_docking(params)
        self.params = stewart
        self.docking = params
        g = stewart.geometry
        kinematics = PoseKinematics(g)
        self.kinematics = kinematics
        X_port = RigidTransform(kinematics.port_in_plate_m)
        X_face = RigidTransform(kinematics.world_origin_m)

        def register(plant, device, world) -> None:
            register_docking_devices(plant, device, X_port, world, X_face, params.contact)

        builder = DiagramBuilder()
        c = params.contact
        handles = add_stewart_plant(
            builder,
            stewart,
            c.contact_stiffness_n_per_m,
            c.contact_dissipation_s_per_m,
            register_devices=register,
        )
        self.handles = handles
        plant = handles.plant
        h = stewart.time_step_s
        use_reference = stewart.reference_response_hz is not None
        ik = builder.AddNamedSystem("inverse_kinematics", PoseInverseKinematics(kinematics))
        servo = builder.AddNamedSystem("leg_servo", LegServo(handles, use_rates=use_reference))
        sensor = builder.AddNamedSystem("ft_sensor", PoseDeviceSensor(handles, kinematics))
        hold = builder.AddNamedSystem("sensor_sample", ZeroOrderHold(h, 6))
        if use_reference:
            A, B, C, D = reference_matrices(stewart)
            eye = np.eye(6)
            reference = builder.AddNamedSystem(
                "reference_model",
                LinearSystem(np.kron(A, eye), np.kron(B, eye), np.kron(C, eye), np.kron(D, eye), h),
            )
            builder.Connect(ik.get_output_port(), reference.get_input_port())
            builder.Connect(reference.get_output_port(), servo.GetInputPort("leg_reference"))
            self._reference = reference
        else:
            builder.Connect(ik.get_output_port(), servo.GetInputPort("leg_reference"))
            self._reference = None
        connect_servo_and_device(builder, plant, servo, sensor)
        builder.Connect(sensor.GetOutputPort("step_wrench"), hold.get_input_port())
        builder.ExportInput(ik.get_input_port(), "commanded_state")
        builder.ExportOutput(sensor.GetOutputPort("port_state"), "table_state")
        builder.ExportOutput(hold.get_output_port(), "contact_wrench")
        builder.ExportOutput(sensor.GetOutputPort("weld_wrench"), "weld_wrench")
        self.visualizer = export_plate_pose(builder, handles, meshcat)
        self._sensor = sensor
        self._hold = hold
        builder.BuildInto(self)

    @property
    def plant(self):
        return self.handles.plant

    def set_initial_state(self, context, table_state: np.ndarray, command: np.ndarray) -> None:
        """Put the port at the pose and twist of ``table_state`` (12, W):
        plate, legs and joints consistent, the reference model at those leg
        lengths and rates, no wrench over the step before t = 0 (context:
        this diagram's). ``command`` (12), the command held at t = 0, is not
        needed: the servo reads it from the input port at the first tick.

        Raises
        ------
        WorkspaceError
            If the pose leaves the workspace or nears a singularity.
        """
        x = np.asarray(table_state, dtype=float)
        lengths, rates = self.kinematics.inverse_kinematics(x[:6], x[6:])
        position, R = self.kinematics.plate_of_port(x[:6])
        twist = self.kinematics.plate_twist_of_port(R, x[6:])
        plant_context = self.GetMutableSubsystemContext(self.handles.plant, context)
        set_plate_state(self.handles, plant_context, position, R, twist[:3], twist[3:])
        self.GetMutableSubsystemContext(self._hold, context).SetDiscreteState(np.zeros(6))
        if self._reference is not None:
            self.GetMutableSubsystemContext(self._reference, context).SetDiscreteState(
                np.concatenate([lengths, rates])
            )


def _approach_poses(params: DockingLoopParams, count: int = 201) -> tuple[np.ndarray, np.ndarray]:
    """Port poses (count, 6) along the approach, with the misalignment, from
    the initial pose to three undamped peak presses past the target's face
    (a drogue's: its socket's floor, on its axis, where the cone guides the
    probe), and the initial pose (6): ``lateral_miss_m`` across the axis, the
    active device ``initial_gap_m`` before its first touch (as the loop
    starts). A body turning at the approach's angular rate turns on at it
    (torque-free, the rate taken constant over the approach: a bound for the
    check, not the body's motion)."""
    a = params.approach
    c = params.contact
    R0 = rotation_from_rpy(np.array([*a.misalignment_rad, 0.0]))
    miss = np.array(a.lateral_miss_m)
    z0 = port_start_z_m(c, R0, miss, a.initial_gap_m)
    z1 = 3.0 * params.peak_press_m + (floor_depth_m(c) if c.is_cone else 0.0)
    poses = np.zeros((count, 6))
    poses[:, :2] = np.outer(np.linspace(1.0, 0.0 if c.is_cone else 1.0, count), miss)
    poses[:, 2] = np.linspace(z0, z1, count)
    rate = np.array(a.angular_rate_rad_per_s)
    times = (poses[:, 2] - z0) / a.initial_velocity_m_per_s
    for pose, t in zip(poses, times, strict=True):
        pose[3:] = rotation_log(R0 @ rotation_exp(rate * t))
    return poses, poses[0].copy()


def check_stewart_scenario(params: DockingLoopParams) -> None:
    """Refuse, before any simulation, a scenario the Stewart platform cannot run.

    Checks that the platform runs at the rig's tick and that the port's
    initial pose and every pose along the approach, with the misalignment, up
    to ``3 v0 / omega_contact`` past the plate's face (three times the
    undamped peak penetration: a delayed loop presses deeper) are reachable
    and away from singularities.

    Raises
    ------
    ParameterError
        The platform cannot run at the tick.
    WorkspaceError
        One line naming the pose, the leg and the scenario's keys to change.
    """
    stewart = stewart_params_for_docking(params)
    kinematics = PoseKinematics(stewart.geometry)
    poses, initial = _approach_poses(params)
    a = params.approach
    tilt = ", ".join(f"{math.degrees(x):.3g}" for x in a.misalignment_rad)
    try:
        kinematics.leg_lengths(initial)
    except WorkspaceError as err:
        advice = "lower [approach] initial_gap_m or misalignment_deg"
        if params.contact.is_cone:  # the probe starts just before its first touch
            advice = (
                "a smaller [approach] lateral_miss_m or misalignment_deg, or a shallower "
                "drogue ([contact] socket_depth_m, mouth_radius_m, cone_half_angle_rad)"
            )
        raise WorkspaceError(
            f"initial_gap_m {a.initial_gap_m:g} with misalignment_deg [{tilt}] starts the "
            f"Stewart platform out of its reach: {err}; {advice}"
        ) from None
    deepest = float(poses[-1, 2])
    for q in poses:
        try:
            kinematics.leg_lengths(q)
        except WorkspaceError as err:
            if params.contact.is_cone:
                raise WorkspaceError(
                    f"the Stewart platform cannot follow the probe (misalignment_deg [{tilt}]) "
                    f"into the drogue's socket, its floor {floor_depth_m(params.contact):.4f} m "
                    f"deep, and three undamped peak presses past it (z = {deepest:.4f} m): "
                    f"{err}; a shallower drogue ([contact] socket_depth_m, mouth_radius_m, "
                    "throat_radius_m, cone_half_angle_rad) or a lower initial_velocity_m_per_s"
                ) from None
            raise WorkspaceError(
                f"the Stewart platform cannot follow the approach (misalignment_deg [{tilt}]) "
                f"to the deepest expected press, 3 initial_velocity_m_per_s / (2 pi contact "
                f"frequency) = {deepest:.4f} m past the plate's face: {err}; lower [approach] "
                "initial_velocity_m_per_s or misalignment_deg, or raise [contact] "
                "contact_stiffness_n_per_m"
            ) from None
