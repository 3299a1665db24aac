"""The 6-DoF docking loop as a Drake diagram.

::

    spacecraft --commanded_state--> table back-end --contact_wrench--> F/T sensor
        ^                              |  (table + docking contact)         |
        |                              +--table_state--+                    |
        +--compensated_wrench-- wrench compensator <---+---measured_wrench--+
                                ^--commanded_state-- spacecraft

Every part but the table back-end's inside runs at the rig computer's tick.
A table back-end is any system with input ``commanded_state`` (12) and
outputs ``table_state`` (12) and ``contact_wrench`` (6, what the F/T sensor
reads before its delay): :class:`TableModelBackend` (the table model and
Drake's contact of the devices) or the Stewart platform
(:mod:`hybridtable.six_dof.stewart_backend`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import (
    Adder,
    ConstantVectorSource,
    LinearSystem,
    LogVectorOutput,
    MatrixGain,
    Multiplexer,
    VectorLogSink,
)

from hybridtable.six_dof.compensator import stiffness_model_of
from hybridtable.six_dof.contact import DockingContactSystem, port_start_z_m
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.physics6 import DockingPhysics
from hybridtable.six_dof.registry import make_wrench_compensator
from hybridtable.six_dof.sensor import PoseNoise, add_wrench_sensor
from hybridtable.six_dof.spacecraft import BODY_STATE_SIZE, RigidSpacecraft, port_state
from hybridtable.six_dof.table import PoseTable, add_pose_table
from hybridtable.stewart.geometry import rotation_from_rpy
from hybridtable.systems.measurement_chain import low_pass_system, mount_system
from hybridtable.systems.resonant_table import StructuralModeParams

__all__ = [
    "LOG_LAYOUT",
    "TableModelBackend",
    "DockingLoop",
    "add_docking_loop",
    "build_docking_loop",
    "initial_port_state",
    "table_backend",
    "set_initial_table",
    "add_rig_part",
]

#: Blocks of the loop's log, in order: name -> size.
LOG_LAYOUT: dict[str, int] = {
    "commanded_state": 12,
    "table_state": 12,
    "contact_wrench": 6,
    "measured_wrench": 6,
    "compensated_wrench": 6,
    "body_state": BODY_STATE_SIZE,
    # the table's state as the compensator read it (its encoders' noise)
    "measured_table_state": 12,
}


class TableModelBackend(Diagram):
    """The table model (:mod:`hybridtable.six_dof.table`) carrying the active
    device against the passive one (:class:`DockingContactSystem`).

    Ports
    -----
    Input ``commanded_state`` (12: m, rad, m/s, rad/s)
    Output ``table_state`` (12), ``contact_wrench`` (6: N m, N)
    """

    def __init__(self, params: DockingLoopParams, mode: StructuralModeParams | None = None) -> None:
        Diagram.__init__(self)
        builder = DiagramBuilder()
        self.table: PoseTable = add_pose_table(
            builder, params.plant.table.response, params.sample_period_s, mode
        )
        contact = builder.AddNamedSystem("contact", DockingContactSystem(params.contact))
        builder.Connect(self.table.system.get_output_port(), contact.get_input_port())
        builder.ExportInput(self.table.system.get_input_port(), "commanded_state")
        builder.ExportOutput(self.table.system.get_output_port(), "table_state")
        builder.ExportOutput(contact.get_output_port(), "contact_wrench")
        builder.BuildInto(self)

    def set_initial_state(self, context, table_state: np.ndarray, command: np.ndarray) -> None:
        """The table's state at t = 0 (context: this diagram's)."""
        if not self.table.is_ideal:
            sub = self.GetMutableSubsystemContext(self.table.system, context)
            self.table.set_initial_state(sub, table_state, command)


@dataclass
class DockingLoop:
    """Handles to what :func:`add_docking_loop` added."""

    params: DockingLoopParams
    spacecraft: RigidSpacecraft
    backend: System
    compensator: System
    logger: VectorLogSink | None = None
    diagram: Diagram | None = None
    #: The rig's physical part (None: the scenario's own).
    physics: DockingPhysics | None = None

    def set_initial_conditions(self, root_context) -> None:
        """Write the approach of :attr:`params` into a root context."""
        command, body = initial_port_state(self.params, self.spacecraft)
        sc = self.spacecraft.GetMyMutableContextFromRoot(root_context)
        self.spacecraft.set_state(sc, body)
        set_initial_table(self.backend, root_context, self.params, command, self.physics)


def set_initial_table(
    backend: System,
    root_context,
    params: DockingLoopParams,
    command: np.ndarray,
    physics: DockingPhysics | None = None,
) -> None:
    """Start ``backend`` tracking the approach's ramp (the 1-D "tracking"
    start): at the command it sees (through the physics' table gain), behind
    it by the table's lag (the rig's table's, with the physics' changes)."""
    seen = np.asarray(command, dtype=float).copy()
    if physics is not None and physics.table_gain is not None:
        seen = _table_matrix(physics) @ seen
    true = physics.apply(params) if physics is not None else params
    table_state = seen.copy()
    table_state[:6] -= true.plant.table.response.ramp_lag_s * seen[6:]
    context = backend.GetMyMutableContextFromRoot(root_context)
    backend.set_initial_state(context, table_state, seen)


def _table_matrix(physics: DockingPhysics) -> np.ndarray:
    """The table gain on ``[q; qd]`` (12x12)."""
    T = np.array(physics.table_gain)
    return np.block([[T, np.zeros((6, 6))], [np.zeros((6, 6)), T]])


def add_rig_part(
    builder: DiagramBuilder,
    params: DockingLoopParams,
    physics: DockingPhysics | None,
    command,
    backend: System,
    noise: bool = True,
):
    """Wire the rig's physical part between the rig computer's command and
    its reading: ``command`` (an output port, ``[q; qd]``) to ``backend``'s
    ``commanded_state`` through the physics' table gain, and ``backend``'s
    ``contact_wrench`` through the sensor's gain, low pass and mount, the F/T
    sensor's delay (and its noise, if ``noise``) and bias. Returns the
    measured wrench's and the measured table state's output ports (the
    encoders' noise on the pose, if ``noise``). Drake primitives (``MatrixGain``, a
    discrete ``LinearSystem``, ``Adder``); plain connections where ``physics``
    has none. ``params`` are the rig computer's (:meth:`DockingPhysics.apply`
    gives the sensor's delay)."""
    h = params.sample_period_s
    true = physics.apply(params) if physics is not None else params
    if physics is not None and physics.table_gain is not None:
        gain = builder.AddNamedSystem("table_gain", MatrixGain(_table_matrix(physics)))
        builder.Connect(command, gain.get_input_port())
        command = gain.get_output_port()
    builder.Connect(command, backend.GetInputPort("commanded_state"))
    wrench = backend.GetOutputPort("contact_wrench")
    if physics is not None and physics.sensor_gain is not None:
        gain = builder.AddNamedSystem("sensor_gain", MatrixGain(np.array(physics.sensor_gain)))
        builder.Connect(wrench, gain.get_input_port())
        wrench = gain.get_output_port()
    if physics is not None and physics.sensor_time_constant_s > 0.0:
        # the 1-D measurement chain's low pass on each channel (its law)
        low_pass = builder.AddNamedSystem(
            "sensor_low_pass",
            LinearSystem(
                *low_pass_system(physics.sensor_time_constant_s, h, channels=6), time_period=h
            ),
        )
        builder.Connect(wrench, low_pass.get_input_port())
        wrench = low_pass.get_output_port()
    if physics is not None and physics.sensor_mount is not None:
        # the 1-D measurement chain's mount on each channel (its law)
        mount = builder.AddNamedSystem(
            "sensor_mount",
            LinearSystem(*mount_system(*physics.sensor_mount, h, channels=6), time_period=h),
        )
        builder.Connect(wrench, mount.get_input_port())
        wrench = mount.get_output_port()
    sensor_in, sensor_out = add_wrench_sensor(
        builder, true.rig.sensor, h, true.rig.noise if noise else None
    )
    builder.Connect(wrench, sensor_in.get_input_port(0))
    measured = sensor_out.get_output_port(0)
    if physics is not None and physics.sensor_bias is not None:
        bias = builder.AddNamedSystem("sensor_bias", ConstantVectorSource(physics.sensor_bias))
        adder = builder.AddNamedSystem("add_sensor_bias", Adder(2, 6))
        builder.Connect(measured, adder.get_input_port(0))
        builder.Connect(bias.get_output_port(), adder.get_input_port(1))
        measured = adder.get_output_port()
    table = backend.GetOutputPort("table_state")
    if noise and true.rig.noise.on_pose:
        n = true.rig.noise
        encoders = builder.AddNamedSystem(
            "encoders", PoseNoise(n.position_std_m, n.attitude_std_rad, n.seed, h)
        )
        builder.Connect(table, encoders.get_input_port())
        table = encoders.get_output_port()
    return measured, table


def initial_port_state(
    params: DockingLoopParams, spacecraft: RigidSpacecraft
) -> tuple[np.ndarray, np.ndarray]:
    """The port's command ``[q; qd]`` (12) and the body state (18) at t = 0:
    the attitude off by the misalignment, the port origin ``lateral_miss_m``
    across the target's axis, the active device ``initial_gap_m`` before its
    first touch (:func:`~hybridtable.six_dof.contact.port_start_z_m`), moving
    at the approach speed along +z."""
    a = params.approach
    R0 = rotation_from_rpy(np.array([*a.misalignment_rad, 0.0]))
    miss = np.array(a.lateral_miss_m)
    port = np.array([*miss, port_start_z_m(params.contact, R0, miss, a.initial_gap_m)])
    v0 = np.array([0.0, 0.0, a.initial_velocity_m_per_s])
    body = spacecraft.initial_state(port, R0, v0, np.array(a.angular_rate_rad_per_s))
    return port_state(spacecraft.params, body), body


def table_backend(params: DockingLoopParams, physics: DockingPhysics | None = None) -> System:
    """The table back-end of ``params.table`` (the table model or the Stewart
    platform), with the structural mode of ``physics`` (the table model only:
    :meth:`DockingPhysics.apply` refuses it on the Stewart platform)."""
    mode = None if physics is None or physics.table_mode is None else physics.table_mode
    if params.table == "stewart":
        from hybridtable.six_dof.stewart_backend import StewartPoseBackend

        return StewartPoseBackend(params)
    return TableModelBackend(params, None if mode is None else StructuralModeParams(*mode))


def add_docking_loop(
    builder: DiagramBuilder,
    params: DockingLoopParams,
    backend: System | None = None,
    compensator: System | None = None,
    log: bool = True,
    physics: DockingPhysics | None = None,
) -> DockingLoop:
    """Add the 6-DoF docking loop to ``builder``, wire it, and return its handles.

    Parameters
    ----------
    builder : DiagramBuilder
    params : DockingLoopParams
    backend : System, optional
        A table back-end (default: from ``params.table``).
    compensator : System, optional
        A wrench compensator (default: the registered ``params.compensator``).
    log : bool
        Log every block of :data:`LOG_LAYOUT` at each tick.
    physics : DockingPhysics, optional
        The rig's physical part where it differs from ``params`` (the contact,
        the table and the sensor are built from :meth:`DockingPhysics.apply`;
        the spacecraft and the compensator are the rig computer's, from
        ``params`` as the physics' :meth:`DockingPhysics.computer` changes
        them: its spacecraft's centre of mass, its compensator's lead and
        stiffness).
    """
    h = params.sample_period_s
    true = physics.apply(params) if physics is not None else params
    computer = physics.computer(params) if physics is not None else params
    spacecraft = builder.AddNamedSystem("spacecraft", RigidSpacecraft(computer.spacecraft, h))
    backend = builder.AddNamedSystem("table_backend", backend or table_backend(true, physics))
    compensator = builder.AddNamedSystem(
        "compensator",
        compensator or make_wrench_compensator(computer, stiffness_model_of(computer)),
    )
    command = spacecraft.GetOutputPort("commanded_state")
    measured, table = add_rig_part(builder, params, physics, command, backend)
    builder.Connect(measured, compensator.GetInputPort("measured_wrench"))
    builder.Connect(table, compensator.GetInputPort("table_state"))
    builder.Connect(command, compensator.GetInputPort("commanded_state"))
    builder.Connect(
        compensator.GetOutputPort("compensated_wrench"),
        spacecraft.GetInputPort("compensated_wrench"),
    )
    loop = DockingLoop(params, spacecraft, backend, compensator, physics=physics)
    if log:
        ports = [
            command,
            backend.GetOutputPort("table_state"),
            backend.GetOutputPort("contact_wrench"),
            measured,
            compensator.GetOutputPort("compensated_wrench"),
            spacecraft.GetOutputPort("body_state"),
            table,
        ]
        mux = builder.AddNamedSystem("log_mux", Multiplexer([p.size() for p in ports]))
        for i, port in enumerate(ports):
            builder.Connect(port, mux.get_input_port(i))
        sink = LogVectorOutput(mux.get_output_port(), builder, h)
        sink.set_name("log")
        loop.logger = sink
    return loop


def build_docking_loop(params: DockingLoopParams, **kwargs) -> DockingLoop:
    """:func:`add_docking_loop` as a stand-alone diagram."""
    builder = DiagramBuilder()
    loop = add_docking_loop(builder, params, **kwargs)
    loop.diagram = builder.Build()
    loop.diagram.set_name("docking_loop")
    return loop
