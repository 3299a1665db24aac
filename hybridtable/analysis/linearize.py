"""Continuous-time linear models of the in-contact hybrid loop, from Drake's Linearize.

In contact the loop is linear once the contact is made bilateral
(``max(p, 0)`` has zero slope at ``p = 0``) and the compensator ungated::

    spacecraft --state--> table --motion--> contact --[f, df/dt]--> Pade delay
        ^                   |                                         |
        |                   +--table_motion--+                        |
        +--compensated_force-- compensator <-+--[f_mea, df_mea/dt]----+
                               ^--commanded_state-- spacecraft

The delay acts on ``[f, df/dt]`` (a delay commutes with d/dt for an LTI
signal), so the SDC's lead ``T_lead df_mea/dt`` needs no derivative block.

Two ways to get the model, both from Drake:

- :func:`linearize_contact_loop`: ``Linearize`` of the whole diagram
  (:func:`add_contact_loop`), one call per operating point;
- :class:`~hybridtable.analysis.blockwise.ContactLoopLinearizer`: ``Linearize``
  of each block (:func:`linearize_system`) once per structure, re-assembled per
  operating point (fast; used by sweeps).

The open loop is cut at the spacecraft's force input: input ``u`` (N, the
force pushing the spacecraft back), output ``y`` = the compensated force (N);
the physical loop closes with ``u = y``. The loop transfer function in
python-control's negative-feedback convention is ``L = -G``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control
import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import Demultiplexer, Linearize, Multiplexer

from hybridtable.analysis.interconnect import StateSpaceBlock
from hybridtable.compensators.paper import Compensator
from hybridtable.errors import LinearizationError, ParameterError
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.wiring import LOOP_WIRING, connect, edge
from hybridtable.systems.contact import UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay
from hybridtable.systems.spacecraft import Spacecraft
from hybridtable.systems.table import SecondOrderTable

__all__ = [
    "LinearizationError",
    "LinearLoop",
    "ContactLoop",
    "add_contact_loop",
    "linearize_system",
    "linearize_contact_loop",
    "check_pade_order",
    "linearization_notes",
]


@dataclass(frozen=True)
class LinearLoop:
    """A linear model of the hybrid loop, open at the spacecraft's force input.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        Open loop ``G``: input the force on the spacecraft (N), output the
        compensated force (N); the loop closes with ``u = y``.
    dt : float
        0 for a continuous model, else the sample period (s).
    params : HybridLoopParams
        The operating point.
    pade_order : int or None
        Order of the delay's Pade approximant (None for a sampled model).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float
    params: HybridLoopParams
    pade_order: int | None = None
    notes: tuple[str, ...] = field(default=())

    @property
    def is_discrete(self) -> bool:
        return self.dt > 0.0

    def open_loop(self) -> control.StateSpace:
        """``G``: force on the spacecraft -> compensated force."""
        return control.ss(self.A, self.B, self.C, self.D, self.dt if self.dt > 0 else 0)

    def loop_transfer(self) -> control.StateSpace:
        """``L = -G``, the loop transfer in python-control's negative-feedback
        convention (closed loop ``1 + L = 0``)."""
        return control.ss(self.A, self.B, -self.C, -self.D, self.dt if self.dt > 0 else 0)

    def closed_loop(self) -> control.StateSpace:
        """The closed loop (``u = y + d``, external force disturbance ``d``),
        closed with ``control.feedback``."""
        return control.feedback(self.open_loop(), 1, sign=1)

    def closed_loop_matrix(self) -> np.ndarray:
        """State matrix of :meth:`closed_loop`, ``A + B (I - D)^-1 C``, without
        building python-control objects (for sweeps; same matrix)."""
        return self.A + self.B @ np.linalg.solve(np.eye(1) - self.D, self.C)

    def closed_loop_poles(self) -> np.ndarray:
        """Closed-loop eigenvalues (s-plane, or z-plane when discrete)."""
        return np.linalg.eigvals(self.closed_loop_matrix())

    def response(self, w: float) -> complex:
        """``G`` at one frequency ``w`` (rad/s): ``s = i w``, or ``z = e^{i w dt}``."""
        s = np.exp(1j * w * self.dt) if self.dt > 0 else 1j * w
        n = self.A.shape[0]
        if n == 0:
            return complex(self.D[0, 0])
        x = np.linalg.solve(s * np.eye(n) - self.A, self.B[:, 0])
        return complex(self.C[0] @ x + self.D[0, 0])

    def transfer(self, s: complex | np.ndarray) -> np.ndarray:
        """``G`` at complex points (``z`` when discrete), shape of ``s``."""
        blk = StateSpaceBlock("G", self.A, self.B, self.C, self.D, ("u",), ("y",), self.dt)
        return blk.transfer(s)[..., 0, 0]


def _channels(name: str, ports) -> tuple[str, ...]:
    return tuple(f"{name}.{p.get_name()}[{i}]" for p in ports for i in range(p.size()))


def linearize_system(system: System, name: str | None = None) -> StateSpaceBlock:
    """Drake's ``Linearize`` of one system at zero state and inputs, all ports.

    Multi-port systems are wrapped with a ``Demultiplexer`` on their inputs and
    a ``Multiplexer`` on their outputs, so every port is linearized. Channel
    names are ``"<name>.<port>[i]"``.

    Raises
    ------
    LinearizationError
        If Drake refuses (e.g. mixed continuous/discrete state).
    """
    name = name or system.get_name()
    inputs = [system.get_input_port(i) for i in range(system.num_input_ports())]
    outputs = [system.get_output_port(i) for i in range(system.num_output_ports())]
    builder = DiagramBuilder()
    sys = builder.AddSystem(system)
    if inputs:
        demux = builder.AddSystem(Demultiplexer([p.size() for p in inputs]))
        for i, p in enumerate(inputs):
            builder.Connect(demux.get_output_port(i), p)
        builder.ExportInput(demux.get_input_port(0), "u")
    mux = builder.AddSystem(Multiplexer([p.size() for p in outputs]))
    for i, p in enumerate(outputs):
        builder.Connect(p, mux.get_input_port(i))
    builder.ExportOutput(mux.get_output_port(0), "y")
    diagram = builder.Build()
    del sys
    context = diagram.CreateDefaultContext()
    if inputs:
        diagram.get_input_port(0).FixValue(context, np.zeros(diagram.get_input_port(0).size()))
    _zero_state(context)
    lin = _linearize(diagram, context, name)
    n_in = diagram.get_input_port(0).size() if inputs else 0
    B = np.asarray(lin.B()).reshape(lin.A().shape[0], n_in)
    D = np.asarray(lin.D()).reshape(-1, n_in)
    return StateSpaceBlock(
        name,
        np.asarray(lin.A()),
        B,
        np.asarray(lin.C()).reshape(D.shape[0], -1),
        D,
        _channels(name, inputs),
        _channels(name, outputs),
        float(lin.time_period()),
    )


def _zero_state(context) -> None:
    if context.num_continuous_states():
        context.SetContinuousState(np.zeros(context.num_continuous_states()))
    for i in range(context.num_discrete_state_groups()):
        n = context.get_discrete_state(i).size()
        context.SetDiscreteState(i, np.zeros(n))


def _linearize(system: System, context, name: str):
    try:
        return Linearize(system, context, equilibrium_check_tolerance=1e-6)
    except (RuntimeError, SystemExit) as err:  # Drake asserts reach Python as SystemExit
        raise LinearizationError(f"Drake could not linearize {name}: {err}") from None


# -- the in-contact loop as one Drake diagram ----------------------------------


@dataclass
class ContactLoop:
    """Handles to the systems :func:`add_contact_loop` added."""

    params: HybridLoopParams
    spacecraft: System
    table: System
    contact: System
    force_mux: System
    force_sensor: System
    force_demux: System
    compensator: System


def check_pade_order(pade_order: int) -> int:
    """``pade_order`` as an int >= 1, or a ParameterError naming it."""
    if int(pade_order) != pade_order or pade_order < 1:
        raise ParameterError(f"pade_order must be an integer >= 1 (got {pade_order})")
    return int(pade_order)


def add_contact_loop(
    builder: DiagramBuilder, params: HybridLoopParams, pade_order: int = 3
) -> ContactLoop:
    """Add the linearizable in-contact loop (continuous, Pade delay) to ``builder``.

    Every connection of :func:`hybridtable.loop.builder.add_hybrid_loop` is made except
    the spacecraft's force input, left for the caller (export it and the
    compensator's ``compensated_force`` to linearize the open loop, or connect
    them to close it). The contact is bilateral, the sensor a Pade delay of
    ``[f, df/dt]``, the compensator ungated and reading ``df_mea/dt``.
    """
    order = check_pade_order(pade_order)
    sc = builder.AddNamedSystem("spacecraft", Spacecraft(params.plant.spacecraft))
    table = builder.AddNamedSystem("table", SecondOrderTable(params.plant.table))
    contact = builder.AddNamedSystem(
        "contact", UnilateralSpringContact(params.plant.contact, bilateral=True)
    )
    mux = builder.AddNamedSystem("force_mux", Multiplexer(2))
    sensor = builder.AddNamedSystem(
        "force_sensor",
        ForceSensorDelay(params.rig.sensor, mode="pade", pade_order=order, size=2),
    )
    demux = builder.AddNamedSystem("force_demux", Demultiplexer(2))
    comp = builder.AddNamedSystem(
        "compensator",
        Compensator(params.compensator_params(), derivative_period_s=None, gated=False),
    )
    # The loop's wiring, but the spacecraft's force left open and the sensor
    # carrying [f, df/dt] from the contact to the compensator's two inputs.
    sensor_path = {
        edge("compensator.compensated_force", "spacecraft.force"),
        edge("contact.force", "force_sensor.force"),
        edge("force_sensor.measured_force", "compensator.measured_force"),
    }
    systems = dict(
        spacecraft=sc, table=table, contact=contact, force_sensor=sensor, compensator=comp
    )
    connect(builder, systems, [e for e in LOOP_WIRING if e not in sensor_path])
    builder.Connect(contact.GetOutputPort("force"), mux.get_input_port(0))
    builder.Connect(contact.GetOutputPort("force_rate"), mux.get_input_port(1))
    builder.Connect(mux.get_output_port(0), sensor.GetInputPort("force"))
    builder.Connect(sensor.GetOutputPort("measured_force"), demux.get_input_port(0))
    builder.Connect(demux.get_output_port(0), comp.GetInputPort("measured_force"))
    builder.Connect(demux.get_output_port(1), comp.GetInputPort("measured_force_rate"))
    return ContactLoop(params, sc, table, contact, mux, sensor, demux, comp)


def linearization_notes(params: HybridLoopParams) -> tuple[str, ...]:
    """Caveats of the linear model at ``params``, in words (empty when none)."""
    cp = params.compensator_params()
    if params.plant.table.is_ideal and params.contact_damping_n_s_per_m > 0 and cp.uses_lead:
        return (
            "ideal table with a damped contact: the table reports a_act = 0, so the "
            "contact's force rate lacks c * a and the SDC lead of the linear model "
            "misses it",
        )
    return ()


def linearize_contact_loop(params: HybridLoopParams, pade_order: int = 3) -> LinearLoop:
    """Drake's ``Linearize`` of the whole in-contact loop diagram, open at the
    spacecraft's force input (one call per operating point; see
    :class:`~hybridtable.analysis.blockwise.ContactLoopLinearizer` for sweeps)."""
    builder = DiagramBuilder()
    loop = add_contact_loop(builder, params, pade_order)
    builder.ExportInput(loop.spacecraft.GetInputPort("force"), "force")
    builder.ExportOutput(loop.compensator.GetOutputPort("compensated_force"), "compensated_force")
    diagram: Diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    diagram.get_input_port(0).FixValue(context, [0.0])
    _zero_state(context)
    lin = _linearize(diagram, context, "the in-contact loop")
    n = lin.A().shape[0]
    return LinearLoop(
        np.asarray(lin.A()),
        np.asarray(lin.B()).reshape(n, 1),
        np.asarray(lin.C()).reshape(1, n),
        np.asarray(lin.D()).reshape(1, 1),
        0.0,
        params,
        check_pade_order(pade_order),
        linearization_notes(params),
    )
