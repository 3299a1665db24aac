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
- :class:`ContactLoopLinearizer`: ``Linearize`` of each block once per
  structure, re-assembled per operating point with
  :class:`~hybridtable.analysis.interconnect.Interconnection` (fast; used by sweeps).
  Parameters enter the blocks in a known way, each checked when first used:
  the table is a time-scaled copy of the unit-frequency table (states
  ``[p, v]`` scaled by ``[1, w]``, outputs ``[p, v, a]`` by ``[1, w, w^2]``), the Pade block with its delay
  (``A = A_1 / T``, ``B = B_1 / T``), the compensator is affine in its lead
  time.

The open loop is cut at the spacecraft's force input: input ``u`` (N, the
force pushing the spacecraft back), output ``y`` = the compensated force (N);
the physical loop closes with ``u = y``. The loop transfer function in
python-control's negative-feedback convention is ``L = -G``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import control
import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import Demultiplexer, Linearize, Multiplexer

from hybridtable.analysis.interconnect import Interconnection, StateSpaceBlock, state_slices
from hybridtable.compensators.paper import Compensator, CompensatorParams
from hybridtable.errors import LinearizationError, ParameterError
from hybridtable.loop.params import HybridLoopParams
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable, TableParams

__all__ = [
    "LinearizationError",
    "LinearLoop",
    "ContactLoop",
    "add_contact_loop",
    "linearize_system",
    "linearize_contact_loop",
    "ContactLoopLinearizer",
    "CONTACT_LOOP_BLOCKS",
    "check_close",
]

#: Block names of the in-contact loop, in the order their states are stacked.
CONTACT_LOOP_BLOCKS: tuple[str, ...] = (
    "spacecraft",
    "table",
    "contact",
    "force_sensor",
    "compensator",
)


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


def _check_pade_order(pade_order: int) -> int:
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
    order = _check_pade_order(pade_order)
    sc = builder.AddNamedSystem("spacecraft", Spacecraft(params.spacecraft()))
    table = builder.AddNamedSystem("table", SecondOrderTable(params.table()))
    contact = builder.AddNamedSystem(
        "contact", UnilateralSpringContact(params.contact(), bilateral=True)
    )
    mux = builder.AddNamedSystem("force_mux", Multiplexer(2))
    sensor = builder.AddNamedSystem(
        "force_sensor",
        ForceSensorDelay(params.sensor(), mode="pade", pade_order=order, size=2),
    )
    demux = builder.AddNamedSystem("force_demux", Demultiplexer(2))
    comp = builder.AddNamedSystem(
        "compensator",
        Compensator(params.compensator_params(), derivative_period_s=None, gated=False),
    )
    builder.Connect(sc.GetOutputPort("state"), table.GetInputPort("commanded_state"))
    builder.Connect(table.GetOutputPort("motion"), contact.GetInputPort("motion"))
    builder.Connect(contact.GetOutputPort("force"), mux.get_input_port(0))
    builder.Connect(contact.GetOutputPort("force_rate"), mux.get_input_port(1))
    builder.Connect(mux.get_output_port(0), sensor.GetInputPort("force"))
    builder.Connect(sensor.GetOutputPort("measured_force"), demux.get_input_port(0))
    builder.Connect(demux.get_output_port(0), comp.GetInputPort("measured_force"))
    builder.Connect(demux.get_output_port(1), comp.GetInputPort("measured_force_rate"))
    builder.Connect(table.GetOutputPort("motion"), comp.GetInputPort("table_motion"))
    builder.Connect(sc.GetOutputPort("state"), comp.GetInputPort("commanded_state"))
    return ContactLoop(params, sc, table, contact, mux, sensor, demux, comp)


def _notes(params: HybridLoopParams) -> tuple[str, ...]:
    cp = params.compensator_params()
    if params.table().is_ideal and params.contact_damping_n_s_per_m > 0 and cp.uses_lead:
        return (
            "ideal table with a damped contact: the table reports a_act = 0, so the "
            "contact's force rate lacks c * a and the SDC lead of the linear model "
            "misses it",
        )
    return ()


def linearize_contact_loop(params: HybridLoopParams, pade_order: int = 3) -> LinearLoop:
    """Drake's ``Linearize`` of the whole in-contact loop diagram, open at the
    spacecraft's force input (one call per operating point; see
    :class:`ContactLoopLinearizer` for sweeps)."""
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
        _check_pade_order(pade_order),
        _notes(params),
    )


# -- block-wise linearization, assembled per operating point --------------------


def check_close(a: np.ndarray, b: np.ndarray, what: str, rtol: float = 1e-9) -> None:
    """Raise :class:`LinearizationError` unless ``a`` equals ``b`` to ``rtol``
    (relative to the largest entry of ``b``)."""
    scale = max(1.0, float(np.max(np.abs(b))) if b.size else 1.0)
    if a.shape != b.shape or (a.size and float(np.max(np.abs(a - b))) > rtol * scale):
        raise LinearizationError(f"the assumed parameter structure of {what} does not hold")


def _same_transfer(a: StateSpaceBlock, b: StateSpaceBlock, points: Sequence[complex], what: str):
    ta, tb = a.transfer(np.asarray(points)), b.transfer(np.asarray(points))
    check_close(ta, tb, what, rtol=1e-8)


class ContactLoopLinearizer:
    """Block-wise Drake linearization of the in-contact loop, assembled per point.

    Each block of :func:`add_contact_loop` is linearized with Drake's
    ``Linearize`` once per structure (and cached); the blocks' parameters are
    applied by the scalings described in :mod:`hybridtable.analysis.linearize`, each
    verified against a second direct ``Linearize`` when the structure is
    first met. :meth:`verify` compares an assembled model with a direct
    ``Linearize`` of the full diagram.

    Parameters
    ----------
    pade_order : int
        Order of the Pade approximant of the sensor delay.
    """

    def __init__(self, pade_order: int = 3) -> None:
        self.pade_order = _check_pade_order(pade_order)
        self._cache: dict = {}
        names = CONTACT_LOOP_BLOCKS
        self._wiring_names = names
        blocks = [self._template(n) for n in names]
        self._open = Interconnection(
            [(b.name, b.inputs, b.outputs) for b in blocks],
            self._connections(with_sensor=True),
            ["spacecraft.force[0]"],
            ["compensator.compensated_force[0]"],
        )
        no_sensor = [b for b in blocks if b.name != "force_sensor"]
        self._cut = Interconnection(
            [(b.name, b.inputs, b.outputs) for b in no_sensor],
            self._connections(with_sensor=False),
            [
                "spacecraft.force[0]",
                "compensator.measured_force[0]",
                "compensator.measured_force_rate[0]",
            ],
            [
                "compensator.compensated_force[0]",
                "contact.force[0]",
                "contact.force_rate[0]",
            ],
        )

    # channel wiring of add_contact_loop
    @staticmethod
    def _connections(with_sensor: bool) -> dict[str, str]:
        c = {
            "table.commanded_state[0]": "spacecraft.state[0]",
            "table.commanded_state[1]": "spacecraft.state[1]",
            "compensator.commanded_state[0]": "spacecraft.state[0]",
            "compensator.commanded_state[1]": "spacecraft.state[1]",
        }
        for i in range(3):
            c[f"contact.motion[{i}]"] = f"table.motion[{i}]"
            c[f"compensator.table_motion[{i}]"] = f"table.motion[{i}]"
        if with_sensor:
            c["force_sensor.force[0]"] = "contact.force[0]"
            c["force_sensor.force[1]"] = "contact.force_rate[0]"
            c["compensator.measured_force[0]"] = "force_sensor.measured_force[0]"
            c["compensator.measured_force_rate[0]"] = "force_sensor.measured_force[1]"
        return c

    def _template(self, name: str) -> StateSpaceBlock:
        p = HybridLoopParams(
            spacecraft_mass_kg=1.0,
            contact_stiffness_n_per_m=1.0,
            sensor_delay_s=1.0,
            table_response_hz=1.0,
            compensator="SDMDC",
        )
        return self._block(name, p)

    def _memo(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # -- blocks ------------------------------------------------------------------
    def spacecraft_block(self, mass_kg: float) -> StateSpaceBlock:
        return self._memo(
            ("spacecraft", mass_kg),
            lambda: linearize_system(Spacecraft(SpacecraftParams(mass_kg)), "spacecraft"),
        )

    def table_block(self, table: TableParams) -> StateSpaceBlock:
        if table.is_ideal:
            return self._memo(
                ("table", math.inf),
                lambda: linearize_system(SecondOrderTable(table), "table"),
            )
        unit = self._memo(("table_unit", table.damping_ratio), lambda: self._unit_table(table))
        return self._scale_table(unit, table.omega_rad_per_s)

    @staticmethod
    def _scale_table(unit: StateSpaceBlock, w: float) -> StateSpaceBlock:
        # Time scaling t -> w t of the unit table, in the physical state basis
        # [p, v] (state scale diag(1, w)); outputs [p, v, a] scale by [1, w, w^2].
        sx = np.array([1.0, w])
        sy = np.array([[1.0], [w], [w * w]])
        A = w * unit.A * sx[:, None] / sx[None, :]
        B = w * unit.B * sx[:, None]
        C = sy * unit.C / sx[None, :]
        return unit.with_matrices(A, B, C, sy * unit.D)

    def _unit_table(self, table: TableParams) -> StateSpaceBlock:
        z = table.damping_ratio
        unit = linearize_system(SecondOrderTable(TableParams(1.0 / (2 * math.pi), z)), "table")
        # Check the frequency scaling once against a direct linearization.
        w = 7.0
        direct = linearize_system(SecondOrderTable(TableParams(w / (2 * math.pi), z)), "table")
        scaled = self._scale_table(unit, w)
        for a, b in zip(
            (scaled.A, scaled.B, scaled.C, scaled.D),
            (direct.A, direct.B, direct.C, direct.D),
            strict=True,
        ):
            check_close(a, b, "the table (frequency scaling)")
        return unit

    def contact_block(self, contact: ContactParams) -> StateSpaceBlock:
        return self._memo(
            ("contact", contact),
            lambda: linearize_system(UnilateralSpringContact(contact, bilateral=True), "contact"),
        )

    def sensor_block(self, delay_s: float) -> StateSpaceBlock:
        if delay_s == 0.0:
            return self._memo(("sensor", 0.0), lambda: self._sensor_direct(0.0))
        unit = self._memo(("sensor_unit",), self._unit_sensor)
        return unit.with_matrices(unit.A / delay_s, unit.B / delay_s, unit.C, unit.D)

    def _sensor_direct(self, delay_s: float) -> StateSpaceBlock:
        return linearize_system(
            ForceSensorDelay(SensorParams(delay_s), "pade", pade_order=self.pade_order, size=2),
            "force_sensor",
        )

    def _unit_sensor(self) -> StateSpaceBlock:
        unit = self._sensor_direct(1.0)
        T = 0.37
        scaled = unit.with_matrices(unit.A / T, unit.B / T, unit.C, unit.D)
        pts = [1j * 0.5 / T, 2j / T, (1 + 3j) / T]
        _same_transfer(scaled, self._sensor_direct(T), pts, "the Pade delay (time scaling)")
        return unit

    def compensator_block(self, comp: CompensatorParams) -> StateSpaceBlock:
        key = replace(comp, lead_time_s=0.0)
        d0, d1 = self._memo(("compensator", key), lambda: self._affine_compensator(key))
        T = comp.lead_time_s
        return d0.with_matrices(d0.A, d0.B, d0.C, d0.D + T * (d1.D - d0.D))

    def _affine_compensator(self, key: CompensatorParams):
        def lin(T):
            c = Compensator(replace(key, lead_time_s=T), derivative_period_s=None, gated=False)
            return linearize_system(c, "compensator")

        d0, d1, dh = lin(0.0), lin(1.0), lin(0.3)
        for b in (d0, d1, dh):
            if b.num_states:
                raise LinearizationError("the continuous compensator must be stateless")
        check_close(dh.D, d0.D + 0.3 * (d1.D - d0.D), "the compensator (affine in its lead time)")
        return d0, d1

    def _block(self, name: str, p: HybridLoopParams) -> StateSpaceBlock:
        if name == "spacecraft":
            return self.spacecraft_block(p.spacecraft_mass_kg)
        if name == "table":
            return self.table_block(p.table())
        if name == "contact":
            return self.contact_block(p.contact())
        if name == "force_sensor":
            return self.sensor_block(p.sensor_delay_s)
        return self.compensator_block(p.compensator_params())

    # -- models ------------------------------------------------------------------
    def open_loop(self, params: HybridLoopParams) -> LinearLoop:
        """The open loop ``G`` at ``params`` (same model as
        :func:`linearize_contact_loop`, in another state basis)."""
        m = self._open.assemble(self.blocks(params), "open_loop")
        return LinearLoop(m.A, m.B, m.C, m.D, 0.0, params, self.pade_order, _notes(params))

    def blocks(self, params: HybridLoopParams) -> list[StateSpaceBlock]:
        """The linearized blocks at ``params``, in :data:`CONTACT_LOOP_BLOCKS`
        order (the order of the model's states)."""
        return [self._block(n, params) for n in CONTACT_LOOP_BLOCKS]

    def state_slices(self, params: HybridLoopParams) -> dict[str, slice]:
        """Where each block's states sit in the state of :meth:`open_loop`."""
        return state_slices(self.blocks(params))

    def delay_cut(self, params: HybridLoopParams) -> StateSpaceBlock:
        """The loop without the sensor delay: inputs ``[u, f_mea, df_mea/dt]``,
        outputs ``[f_comp, f, df/dt]``. Closing ``f_mea = e^{-sT} f`` gives
        the exact-delay loop (:mod:`hybridtable.analysis.exact_delay`)."""
        blocks = [self._block(n, params) for n in CONTACT_LOOP_BLOCKS if n != "force_sensor"]
        return self._cut.assemble(blocks, "delay_cut")

    def verify(self, params: HybridLoopParams, rtol: float = 1e-7) -> float:
        """Compare the assembled model with a direct ``Linearize`` of the full
        diagram: transfer function at points around the contact frequency and
        closed-loop poles. Returns the largest relative difference.

        Raises
        ------
        LinearizationError
            If they differ by more than ``rtol``.
        """
        a = self.open_loop(params)
        b = linearize_contact_loop(params, self.pade_order)
        w = 2 * math.pi * params.contact_frequency_hz
        pts = np.array([0.5j, 1j, 3j, 0.2 + 1.3j, 20j]) * w
        ga, gb = a.transfer(pts), b.transfer(pts)
        err = float(np.max(np.abs(ga - gb) / np.maximum(np.abs(gb), 1e-300)))
        pa = np.sort_complex(a.closed_loop_poles())
        pb = np.sort_complex(b.closed_loop_poles())
        if pa.shape != pb.shape:
            raise LinearizationError("assembled and direct models differ in order")
        err = max(err, float(np.max(np.abs(pa - pb) / np.maximum(np.abs(pb), w))))
        if not err <= rtol:
            raise LinearizationError(
                f"assembled model differs from Drake's Linearize of the full diagram "
                f"(relative {err:.3g})"
            )
        return err
