"""The Stewart platform as a drop-in table + contact back-end of the hybrid loop.

The loop's back-end ports (see :mod:`hybridtable.loop.builder`) are kept exactly:

- :class:`StewartTable` (passed as ``table=``): input ``commanded_state``
  (2: p_des m, v_des m/s along the docking axis), output ``motion`` (3:
  [p, v, a] of the active device along the docking axis, penetration
  positive). It holds the MultibodyPlant, the legs' digital PD servo and the
  F/T sensor readout, and has an extra output ``sensed_force`` (2: contact
  force from the sensor, N, compression positive, and its backward-difference
  rate, N/s) and ``sensor_wrench`` (6: the weld's raw reaction wrench).
- :class:`StewartContactReadout` (passed as ``contact=``): input ``motion``
  (unused: the contact happens inside the plant) and ``sensed_force``;
  outputs ``force`` and ``force_rate``, forwarded from the sensor.

:func:`add_stewart_loop` builds the loop with them and connects the two.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams
from pydrake.systems.framework import Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import (
    Demultiplexer,
    DiscreteDerivative,
    LinearSystem,
    MatrixGain,
    Multiplexer,
    PassThrough,
    ZeroOrderHold,
)

from hybridtable.errors import WorkspaceError
from hybridtable.loop.builder import HybridLoop, add_hybrid_loop
from hybridtable.loop.params import HybridLoopParams
from hybridtable.stewart.ft_sensor import DeviceSensorBase
from hybridtable.stewart.hunt_crossley import hunt_crossley_dissipation
from hybridtable.stewart.params import StewartParams, reference_matrices
from hybridtable.stewart.plant import StewartPlant, add_stewart_plant
from hybridtable.stewart.servo import LegServo

__all__ = [
    "AxisInverseKinematics",
    "DeviceSensor",
    "StewartTable",
    "StewartContactReadout",
    "add_stewart_loop",
    "build_stewart_loop",
    "stewart_params_for_loop",
    "export_plate_pose",
    "connect_servo_and_device",
    "write_meshcat_html",
]


def connect_servo_and_device(builder: DiagramBuilder, plant, servo, sensor) -> None:
    """Wire a leg servo and an F/T device to the Stewart plant, as both
    back-ends do (this one on the docking axis, the 6-DoF one on the pose):
    the servo reads the plant's state (input ``plant_state``) and drives its
    actuation (output ``leg_forces``); the device reads the state, the
    generalized accelerations and the weld's reaction forces (inputs
    ``plant_state``, ``generalized_acceleration``, ``reaction_forces``)."""
    builder.Connect(plant.get_state_output_port(), servo.GetInputPort("plant_state"))
    builder.Connect(servo.GetOutputPort("leg_forces"), plant.get_actuation_input_port())
    builder.Connect(plant.get_state_output_port(), sensor.GetInputPort("plant_state"))
    builder.Connect(
        plant.get_generalized_acceleration_output_port(),
        sensor.GetInputPort("generalized_acceleration"),
    )
    builder.Connect(plant.get_reaction_forces_output_port(), sensor.GetInputPort("reaction_forces"))


class AxisInverseKinematics(LeafSystem):
    """The legs' reference from the docking axis: ``L_r,i = L_i(p_r)`` and
    ``L'_r,i = dL_i/dp(p_r) v_r``, where ``L_i(p)`` is the length of leg i
    with the plate at ``p`` from home along the docking axis (z). The
    reference ``[p_r, v_r]`` is the reference model's output, or without one
    ``[p_des, 0]`` (the servo then follows the commanded position only, like
    the second-order table model).

    Ports
    -----
    Input ``commanded_state`` (2: m, m/s)
        ``[p_des, v_des]``, checked against the workspace.
    Input ``reference_state`` (2: m, m/s), only with a reference model
        ``[p_r, v_r]``.
    Output ``leg_reference`` (12: m, m/s)

    Raises :class:`~hybridtable.errors.WorkspaceError` during a
    simulation when ``p_des`` leaves the docking axis' workspace.
    """

    def __init__(self, handles: StewartPlant, use_reference: bool) -> None:
        LeafSystem.__init__(self)
        g = handles.geometry
        self._geometry = g
        # L_i(p) = |c_i + p z|, precomputed: |c|^2 and c.z.
        c = g.leg_vectors(g.home_pose)
        self._c2 = np.einsum("ij,ij->i", c, c)
        self._cz = c[:, 2].copy()
        self.workspace_m = g.axis_workspace()
        self._command = self.DeclareVectorInputPort("commanded_state", 2)
        self._reference = (
            self.DeclareVectorInputPort("reference_state", 2) if use_reference else None
        )
        self.DeclareVectorOutputPort("leg_reference", 12, self._calc)

    def leg_lengths(self, offset_m: float) -> np.ndarray:
        """Leg lengths with the plate at ``offset_m`` from home along z."""
        return np.sqrt(self._c2 + 2.0 * offset_m * self._cz + offset_m * offset_m)

    def _check(self, p: float) -> None:
        lo, hi = self.workspace_m
        if not (lo <= p <= hi) or not math.isfinite(p):
            try:
                self._geometry.inverse_kinematics(self._geometry.axis_pose(p))
                reason = ""
            except WorkspaceError as err:
                reason = f": {err}"
            raise WorkspaceError(
                f"commanded table position {p:.6f} m leaves the docking-axis workspace "
                f"[{lo:.4f}, {hi:.4f}] m{reason}"
            )

    def _calc(self, context, output) -> None:
        p_des = float(self._command.Eval(context)[0])
        self._check(p_des)
        if self._reference is None:
            p_ref, v_ref = p_des, 0.0
        else:
            p_ref, v_ref = self._reference.Eval(context)
        lengths = self.leg_lengths(p_ref)
        output.SetFromVector(np.concatenate([lengths, (self._cz + p_ref) / lengths * v_ref]))


class DeviceSensor(DeviceSensorBase):
    """Motion of the active device and the F/T sensor's contact force.

    The plant's reaction forces and accelerations (unsampled output ports)
    belong to the step that starts at the current tick; :class:`StewartTable`
    holds ``step_readings`` for one tick, so the loop reads at tick k the
    force and acceleration of the step that ended at tick k, together with the
    position and velocity at tick k.

    Ports
    -----
    Input ``plant_state``, ``generalized_acceleration``, ``reaction_forces``
        From the plant.
    Output ``position_velocity`` (2: m, m/s)
        ``[p, v]`` of the device's tip along the docking axis (world z): ``p``
        is the penetration into the passive device (the tip's top point minus
        the contact face), exact for any plate pose.
    Output ``step_readings`` (2: N, m/s^2)
        Over the coming step: the contact force along the docking axis,
        compression positive, from the weld's reaction force corrected for the
        device's weight and inertia (what a rig's F/T sensor with payload
        compensation reports: minus the force component along z of
        :func:`~hybridtable.stewart.ft_sensor.payload_compensated_wrench`,
        rounded to ``sensor_resolution_n``), and the tip's acceleration along
        the axis.
    Output ``wrench`` (6: N m, N)
        Raw reaction wrench ``[torque; force]`` of the plate on the device,
        at the sensor (the device frame origin), in the device frame, over the
        coming step.
    """

    def __init__(self, handles: StewartPlant) -> None:
        DeviceSensorBase.__init__(self, handles)
        g = handles.geometry
        self._tip = g.device_tip_center_m
        self._tip_radius = g.device_tip_radius_m
        self._face = handles.contact_face_height_m
        self.DeclareVectorOutputPort(
            "position_velocity",
            2,
            self._calc_position_velocity,
            prerequisites_of_calc={self._state.ticket()},
        )
        self.DeclareVectorOutputPort("step_readings", 2, self._calc_step_readings)
        self.DeclareVectorOutputPort("wrench", 6, self._calc_wrench)

    @staticmethod
    def _z_kinematics(R, w, dw, dv, r_body) -> tuple[float, float, float]:
        """z of ``R r``, z of ``w x R r`` and z of the point's acceleration
        ``dv + dw x r + w x (w x r)`` (scalar arithmetic: np.cross is slow)."""
        rx, ry, rz = R @ r_body
        wx, wy, wz = w
        # w x r
        cx, cy, cz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
        acc = 0.0
        if dv is not None:
            acc = dv[2] + dw[0] * ry - dw[1] * rx + wx * cy - wy * cx
        return rz, cz, acc

    def _calc_position_velocity(self, context, output) -> None:
        R, p, w, v = self._pose_twist(self._state.Eval(context))
        rz, vz, _ = self._z_kinematics(R, w, None, None, self._tip)
        # The sphere's highest point is its centre + radius along z.
        output.SetFromVector([p[2] + rz + self._tip_radius - self._face, v[2] + vz])

    def _calc_step_readings(self, context, output) -> None:
        R, w, dw, dv, wrench = self._compensated(context)
        # The contact force on the device along z; compression pushes it down.
        compression = -wrench[5]
        compression = self._resolution * round(compression / self._resolution)
        output.SetFromVector([compression, self._z_kinematics(R, w, dw, dv, self._tip)[2]])

    def _calc_wrench(self, context, output) -> None:
        F = self._weld_wrench(context)
        output.SetFromVector(np.concatenate([F.rotational(), F.translational()]))


class StewartTable(Diagram):
    """The Stewart platform table back-end (plant, leg servo, F/T sensor).

    Inside: the command -> (reference model, if any) ->
    :class:`AxisInverseKinematics` -> :class:`~hybridtable.stewart.servo.LegServo`
    -> plant -> :class:`DeviceSensor` -> one-tick hold of the step readings
    (force, acceleration) -> ``motion`` / ``sensed_force``.

    Ports
    -----
    Input ``commanded_state`` (2: m, m/s)
        ``[p_des, v_des]`` along the docking axis.
    Output ``motion`` (3: m, m/s, m/s^2)
        ``[p, v, a]`` of the active device, penetration positive.
    Output ``sensed_force`` (2: N, N/s)
        Contact force from the F/T sensor (compression positive) and its
        backward difference over one time step.
    Output ``sensor_wrench`` (6: N m, N)
        The weld's raw reaction wrench (see :class:`DeviceSensor`).
    Output ``plate_pose`` (7: 1, m)
        The plate's pose in the world: quaternion ``[w, x, y, z]`` and
        position ``[x, y, z]`` (what :mod:`hybridtable.stewart.view` draws).

    Parameters
    ----------
    params : StewartParams
    contact_stiffness_n_per_m : float
    contact_dissipation_s_per_m : float
        Hunt–Crossley dissipation of the contact.
    meshcat : Meshcat, optional
        Visualize the platform in this Meshcat.
    """

    def __init__(
        self,
        params: StewartParams,
        contact_stiffness_n_per_m: float,
        contact_dissipation_s_per_m: float = 0.0,
        meshcat: Meshcat | None = None,
    ) -> None:
        Diagram.__init__(self)
        self.params = params
        builder = DiagramBuilder()
        handles = add_stewart_plant(
            builder, params, contact_stiffness_n_per_m, contact_dissipation_s_per_m
        )
        self.handles = handles
        plant = handles.plant
        use_reference = params.reference_response_hz is not None
        ik = builder.AddNamedSystem(
            "axis_kinematics", AxisInverseKinematics(handles, use_reference)
        )
        servo = builder.AddNamedSystem("leg_servo", LegServo(handles))
        builder.Connect(ik.get_output_port(), servo.GetInputPort("leg_reference"))
        sensor = builder.AddNamedSystem("ft_sensor", DeviceSensor(handles))
        h = params.time_step_s
        hold = builder.AddNamedSystem("sensor_sample", ZeroOrderHold(h, 2))
        split = builder.AddNamedSystem("sensor_split", Demultiplexer(2, 1))
        motion = builder.AddNamedSystem("motion", Multiplexer([2, 1]))
        rate = builder.AddNamedSystem("force_rate", DiscreteDerivative(1, h))
        mux = builder.AddNamedSystem("sensed_force", Multiplexer([1, 1]))
        connect_servo_and_device(builder, plant, servo, sensor)
        builder.Connect(sensor.GetOutputPort("step_readings"), hold.get_input_port())
        builder.Connect(hold.get_output_port(), split.get_input_port())
        builder.Connect(sensor.GetOutputPort("position_velocity"), motion.get_input_port(0))
        builder.Connect(split.get_output_port(1), motion.get_input_port(1))
        builder.Connect(split.get_output_port(0), rate.get_input_port())
        builder.Connect(split.get_output_port(0), mux.get_input_port(0))
        builder.Connect(rate.get_output_port(), mux.get_input_port(1))
        if use_reference:
            reference = builder.AddNamedSystem(
                "reference_model",
                LinearSystem(*reference_matrices(params), time_period=params.time_step_s),
            )
            command = builder.AddNamedSystem("command", PassThrough(2))
            builder.Connect(command.get_output_port(), ik.GetInputPort("commanded_state"))
            builder.Connect(command.get_output_port(), reference.get_input_port())
            builder.Connect(reference.get_output_port(), ik.GetInputPort("reference_state"))
            builder.ExportInput(command.get_input_port(), "commanded_state")
            self._reference = reference
        else:
            builder.ExportInput(ik.GetInputPort("commanded_state"), "commanded_state")
            self._reference = None
        builder.ExportOutput(motion.get_output_port(), "motion")
        builder.ExportOutput(mux.get_output_port(), "sensed_force")
        builder.ExportOutput(sensor.GetOutputPort("wrench"), "sensor_wrench")
        self.visualizer = export_plate_pose(builder, handles, meshcat)
        self._axis = ik
        self._sensor = sensor
        self._hold = hold
        builder.BuildInto(self)

    @property
    def plant(self):
        return self.handles.plant

    @property
    def workspace_m(self) -> tuple[float, float]:
        """Reachable interval of the docking-axis position (m)."""
        return self._axis.workspace_m

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Put the device at penetration ``position_m`` moving at
        ``velocity_m_per_s`` (context: this diagram's)."""
        plant_context = self.GetMutableSubsystemContext(self.handles.plant, context)
        self.handles.set_axis_state(plant_context, position_m, velocity_m_per_s)
        # No force and no acceleration "over the step before t = 0".
        self.GetMutableSubsystemContext(self._hold, context).SetDiscreteState(np.zeros(2))
        if self._reference is not None:
            reference_context = self.GetMutableSubsystemContext(self._reference, context)
            reference_context.SetDiscreteState([position_m, velocity_m_per_s])


class StewartContactReadout(Diagram):
    """The contact back-end of the Stewart loop: forwards the sensed force.

    The contact itself happens inside the plant (:class:`StewartTable`); this
    system only gives the loop its ``force`` / ``force_rate`` ports.

    Ports
    -----
    Input ``motion`` (3)
        Required by the loop's wiring; unused.
    Input ``sensed_force`` (2: N, N/s)
        Connect to :class:`StewartTable`'s ``sensed_force``.
    Output ``force`` (1, N), ``force_rate`` (1, N/s)
    """

    def __init__(self) -> None:
        Diagram.__init__(self)
        builder = DiagramBuilder()
        mux = builder.AddNamedSystem("inputs", Multiplexer([3, 2]))
        select = np.zeros((2, 5))
        select[0, 3] = select[1, 4] = 1.0
        gain = builder.AddNamedSystem("select", MatrixGain(select))
        demux = builder.AddNamedSystem("outputs", Demultiplexer(2, 1))
        builder.Connect(mux.get_output_port(), gain.get_input_port())
        builder.Connect(gain.get_output_port(), demux.get_input_port())
        builder.ExportInput(mux.get_input_port(0), "motion")
        builder.ExportInput(mux.get_input_port(1), "sensed_force")
        builder.ExportOutput(demux.get_output_port(0), "force")
        builder.ExportOutput(demux.get_output_port(1), "force_rate")
        builder.BuildInto(self)


def export_plate_pose(
    builder: DiagramBuilder, handles: StewartPlant, meshcat: Meshcat | None = None
) -> MeshcatVisualizer | None:
    """Export the plate's pose as ``plate_pose`` (7: quaternion ``[w, x, y,
    z]``, position m) of the diagram ``builder`` builds, and add a Meshcat
    visualizer of the plant when ``meshcat`` is given (returned)."""
    plant = handles.plant
    select = np.zeros((7, plant.num_multibody_states()))
    select[:, handles.plate_position_start : handles.plate_position_start + 7] = np.eye(7)
    pose = builder.AddNamedSystem("plate_pose", MatrixGain(select))
    builder.Connect(plant.get_state_output_port(), pose.get_input_port())
    builder.ExportOutput(pose.get_output_port(), "plate_pose")
    if meshcat is None:
        return None
    return MeshcatVisualizer.AddToBuilder(
        builder, handles.scene_graph, meshcat, MeshcatVisualizerParams(publish_period=1.0 / 64.0)
    )


def stewart_params_for_loop(params: HybridLoopParams, stewart: StewartParams) -> StewartParams:
    """``stewart`` with its time step set to the loop's sample period (a
    sampled loop) so that every discrete part shares one period."""
    if params.sample_period_s is not None and params.sample_period_s != stewart.time_step_s:
        return replace(stewart, time_step_s=params.sample_period_s)
    return stewart


def add_stewart_loop(
    builder: DiagramBuilder,
    params: HybridLoopParams,
    stewart: StewartParams,
    meshcat: Meshcat | None = None,
    **kwargs,
) -> HybridLoop:
    """Add the hybrid loop with the Stewart back-end to ``builder``.

    The contact stiffness is ``params.contact_stiffness_n_per_m``; the viscous
    ``contact_damping_n_s_per_m`` becomes the Hunt–Crossley dissipation with
    the same CoR for an impact of the spacecraft at the approach velocity.
    ``params.table_response_hz`` is not used: the table's response is the
    servo's (see :func:`hybridtable.stewart.identify.tune_leg_gains`).
    Keyword arguments go to :func:`~hybridtable.loop.builder.add_hybrid_loop`.
    """
    stewart = stewart_params_for_loop(params, stewart)
    dissipation = hunt_crossley_dissipation(
        params.contact_stiffness_n_per_m,
        params.contact_damping_n_s_per_m,
        params.spacecraft_mass_kg,
        params.initial_velocity_m_per_s,
    )
    table = StewartTable(stewart, params.contact_stiffness_n_per_m, dissipation, meshcat)
    contact = StewartContactReadout()
    loop = add_hybrid_loop(builder, params, table=table, contact=contact, **kwargs)
    builder.Connect(table.GetOutputPort("sensed_force"), contact.GetInputPort("sensed_force"))
    return loop


def build_stewart_loop(
    params: HybridLoopParams,
    stewart: StewartParams,
    meshcat: Meshcat | None = None,
    **kwargs,
) -> HybridLoop:
    """:func:`add_stewart_loop` as a stand-alone diagram."""
    builder = DiagramBuilder()
    loop = add_stewart_loop(builder, params, stewart, meshcat=meshcat, **kwargs)
    loop.diagram = builder.Build()
    loop.diagram.set_name("hybrid_loop_stewart")
    return loop


def write_meshcat_html(meshcat: Meshcat, path: str | Path) -> Path:
    """Publish the recording of ``meshcat`` and write it as a self-contained
    HTML file (refusing to overwrite an existing file)."""
    path = Path(path)
    meshcat.StopRecording()
    meshcat.PublishRecording()
    html = meshcat.StaticHtml()
    with open(path, "x", encoding="utf-8") as fh:
        fh.write(html)
    return path
