"""Sampled-data linear model of the in-contact loop (a rig computer at a sample rate).

Drake's ``Linearize`` refuses the sampled hybrid loop as one diagram (it mixes
continuous state with discrete state, and the rig computer alone has two
discrete groups), so each block is linearized by Drake on its own:

- the continuous part, table + bilateral contact, linearized as in
  :class:`~hybridtable.analysis.blockwise.ContactLoopLinearizer` and discretized with a
  zero-order hold over one period ``h``;
- the spacecraft model (semi-implicit Euler, period ``h``);
- the sensor's ``DiscreteTimeDelay`` of ``M`` samples, which linearizes to
  ``z^-M``; a delay between two ticks, ``(M + alpha) h``, is the two taps
  mixed, ``(1 - alpha) z^-M + alpha z^-(M+1)``, as the rig computer reads it
  (:func:`~hybridtable.systems.sensor.sample_taps`);
- the compensator with its backward-difference lead (one discrete state),
  ungated.

The blocks are wired with the tick semantics of
:func:`hybridtable.loop.builder.add_hybrid_loop` (and of the ``hybridtable-run/1``
format). At tick ``k`` every discrete update reads the values before the
tick's update: ``p_act(t_k)``, ``f_mea[k] = f_act(t_{k-M})``, the stored
``f_mea[k-1]`` and the spacecraft state ``x_k`` (the command the table was
following, ``p_des[k-1]`` in the CSV). The spacecraft then steps to
``x_{k+1} = A x_k + B f_comp[k]``, which the table follows, held, over
``[t_k, t_{k+1})``. So the zero-order hold is driven by the spacecraft's
*post-update* state (output ``C A x + C B u``), while the table's sampled
outputs at ``t_k`` see the command held over the previous interval (the
direct feedthrough of an ideal table, and ``a_act``): the discretized plant
keeps that command in two extra states (``mem``), whose modes sit at
``z = 0``.

The loop is cut at the spacecraft's force input as in the continuous model and
closed with ``control.feedback`` (:meth:`~hybridtable.analysis.linearize.LinearLoop.closed_loop`);
the contact pole ``z`` maps to ``s = ln(z) / h``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import Multiplexer
from scipy.linalg import block_diag

from hybridtable._validation import check_positive
from hybridtable.analysis.blockwise import ContactLoopLinearizer, check_close
from hybridtable.analysis.interconnect import Interconnection, StateSpaceBlock, state_slices
from hybridtable.analysis.linearize import LinearLoop, linearize_system
from hybridtable.compensators.paper import Compensator, CompensatorParams
from hybridtable.errors import LinearizationError, ParameterError
from hybridtable.laws.table import held_tick
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.wiring import LOOP_WIRING, channel_wiring, edge
from hybridtable.systems.contact import UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams, sample_taps
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable

__all__ = ["SampledLoopLinearizer", "zoh_plant", "SAMPLED_LOOP_BLOCKS"]

#: Block names of the sampled loop, in the order their states are stacked.
SAMPLED_LOOP_BLOCKS: tuple[str, ...] = ("spacecraft", "plant", "force_sensor", "compensator")


def zoh_plant(plant: StateSpaceBlock, period_s: float) -> StateSpaceBlock:
    """Zero-order-hold discretization of a continuous plant with the rig's
    tick semantics.

    Input: the command held over ``[t_k, t_{k+1})``. Outputs at tick ``k``:
    ``C xi(t_k) + D u_{k-1}`` (the sample before the tick's update sees the
    previous command). States ``[xi, u_{k-1}]``.
    """
    h = check_positive("sample_period_s", period_s)
    n, m = plant.A.shape[0], plant.B.shape[1]
    Phi, Gamma = held_tick(plant.A, plant.B, h)
    A = np.zeros((n + m, n + m))
    A[:n, :n] = Phi
    B = np.vstack([Gamma, np.eye(m)])
    C = np.hstack([plant.C, plant.D])
    D = np.zeros((plant.C.shape[0], m))
    return StateSpaceBlock(plant.name, A, B, C, D, plant.inputs, plant.outputs, h)


class SampledLoopLinearizer:
    """Sampled-data linear models of the in-contact loop from Drake blocks.

    Parameters
    ----------
    continuous : ContactLoopLinearizer, optional
        Source of the table and contact blocks (shared with a continuous
        analysis to reuse its cache).
    """

    def __init__(self, continuous: ContactLoopLinearizer | None = None) -> None:
        self._cont = continuous or ContactLoopLinearizer()
        self._cache: dict = {}
        self._plant_wiring = Interconnection(
            [
                ("table", self._table_in(), self._table_out()),
                ("contact", self._contact_in(), self._contact_out()),
            ],
            channel_wiring([edge("table.motion", "contact.motion")]),
            ["table.commanded_state[0]", "table.commanded_state[1]"],
            [*(f"table.motion[{i}]" for i in range(3)), "contact.force[0]"],
        )
        sc_out = (
            "spacecraft.state[0]",
            "spacecraft.state[1]",
            "spacecraft.state_next[0]",
            "spacecraft.state_next[1]",
        )
        plant_out = tuple(self._plant_wiring.outputs)
        comp_in = (
            "compensator.measured_force[0]",
            "compensator.measured_force_rate[0]",
            *(f"compensator.table_motion[{i}]" for i in range(3)),
            "compensator.commanded_state[0]",
            "compensator.commanded_state[1]",
        )
        # The loop's wiring, open at the spacecraft's force; the plant holds the
        # table -> contact connection; the table follows the command the tick's
        # update computes (state_next), the compensator reads the state at the tick.
        command = edge("spacecraft.state", "table.commanded_state")
        cut = {
            edge("compensator.compensated_force", "spacecraft.force"),
            edge("table.motion", "contact.motion"),
            command,
        }
        conn = channel_wiring(
            [("spacecraft", "state_next", "table", "commanded_state")]
            + [e for e in LOOP_WIRING if e not in cut]
        )
        self._loop_wiring = Interconnection(
            [
                ("spacecraft", ("spacecraft.force[0]",), sc_out),
                ("plant", self._plant_wiring.inputs, plant_out),
                ("force_sensor", ("force_sensor.force[0]",), ("force_sensor.measured_force[0]",)),
                ("compensator", comp_in, ("compensator.compensated_force[0]",)),
            ],
            conn,
            ["spacecraft.force[0]"],
            ["compensator.compensated_force[0]"],
            zero_inputs=["compensator.measured_force_rate[0]"],
        )

    @staticmethod
    def _table_in():
        return ("table.commanded_state[0]", "table.commanded_state[1]")

    @staticmethod
    def _table_out():
        return tuple(f"table.motion[{i}]" for i in range(3))

    @staticmethod
    def _contact_in():
        return tuple(f"contact.motion[{i}]" for i in range(3))

    @staticmethod
    def _contact_out():
        return ("contact.force[0]", "contact.force_rate[0]")

    def _memo(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # -- blocks ------------------------------------------------------------------
    def continuous_plant(self, params: HybridLoopParams) -> StateSpaceBlock:
        """Table + bilateral contact, continuous: command ``[p_des, v_des]`` ->
        ``[p_act, v_act, a_act, f_act]``."""
        table = self._cont.table_block(params.plant.table)
        contact = self._cont.contact_block(params.plant.contact)
        return self._plant_wiring.assemble([table, contact], "plant")

    def spacecraft_block(self, mass_kg: float, period_s: float) -> StateSpaceBlock:
        """Discrete spacecraft with outputs ``state`` (before the update) and
        ``state_next`` (after it: ``C A x + C B u``)."""

        def make():
            b = linearize_system(
                Spacecraft(SpacecraftParams(mass_kg), sample_period_s=period_s), "spacecraft"
            )
            if not math.isclose(b.dt, period_s, rel_tol=1e-12):
                raise LinearizationError("the spacecraft did not linearize at its period")
            C = np.vstack([b.C, b.C @ b.A])
            D = np.vstack([b.D, b.C @ b.B])
            outs = (*b.outputs, "spacecraft.state_next[0]", "spacecraft.state_next[1]")
            return StateSpaceBlock("spacecraft", b.A, b.B, C, D, b.inputs, outs, b.dt)

        return self._memo(("spacecraft", mass_kg, period_s), make)

    def sensor_block(self, delay_s: float, period_s: float) -> StateSpaceBlock:
        """The sampled sensor delay, ``z^-M`` with ``M = delay / h``; between two
        ticks, ``(M + alpha) h``, the taps ``z^-M`` and ``z^-(M+1)`` side by side,
        mixed ``(1 - alpha, alpha)`` as :class:`~hybridtable.systems.sensor.ForceSensorDelay`
        wires them (Drake linearizes each tap; the two together have two discrete
        groups, which its ``Linearize`` refuses)."""
        m, alpha = sample_taps(delay_s, period_s)

        def whole(n: int) -> StateSpaceBlock:
            def make():
                b = linearize_system(
                    ForceSensorDelay(SensorParams(n * period_s), "sampled", period_s),
                    "force_sensor",
                )
                return replace(b, dt=period_s)

            return self._memo(("sensor", n, period_s), make)

        if not alpha:
            return whole(m)
        near, far = whole(m), whole(m + 1)
        return near.with_matrices(
            block_diag(near.A, far.A),
            np.vstack([near.B, far.B]),
            np.hstack([(1.0 - alpha) * near.C, alpha * far.C]),
            (1.0 - alpha) * near.D + alpha * far.D,
        )

    def compensator_block(self, comp: CompensatorParams, period_s: float) -> StateSpaceBlock:
        """The discrete compensator (backward-difference lead), ungated; affine
        in the lead time (checked when first met)."""
        key = replace(comp, lead_time_s=0.0)

        def lin(T: float) -> StateSpaceBlock:
            c = Compensator(replace(key, lead_time_s=T), derivative_period_s=period_s, gated=False)
            return linearize_system(c, "compensator")

        def make():
            d0, d1, dh = lin(0.0), lin(1.0), lin(0.3)
            for a0, a1, ah in zip(
                (d0.A, d0.B, d0.C, d0.D),
                (d1.A, d1.B, d1.C, d1.D),
                (dh.A, dh.B, dh.C, dh.D),
                strict=True,
            ):
                check_close(ah, a0 + 0.3 * (a1 - a0), "the compensator (affine in its lead time)")
            return d0, d1

        d0, d1 = self._memo(("compensator", key, period_s), make)
        T = comp.lead_time_s
        return d0.with_matrices(
            d0.A + T * (d1.A - d0.A),
            d0.B + T * (d1.B - d0.B),
            d0.C + T * (d1.C - d0.C),
            d0.D + T * (d1.D - d0.D),
        )

    def verify(self, params: HybridLoopParams, rtol: float = 1e-8) -> float:
        """Compare the assembled continuous plant with Drake's ``Linearize`` of
        a table + bilateral contact diagram (the part Drake can linearize in
        one piece). Returns the largest relative difference of the transfer
        matrices near the contact frequency.

        Raises
        ------
        LinearizationError
            If they differ by more than ``rtol``.
        """
        builder = DiagramBuilder()
        table = builder.AddNamedSystem("table", SecondOrderTable(params.plant.table))
        contact = builder.AddNamedSystem(
            "contact", UnilateralSpringContact(params.plant.contact, bilateral=True)
        )
        builder.Connect(table.GetOutputPort("motion"), contact.GetInputPort("motion"))
        mux = builder.AddNamedSystem("mux", Multiplexer([3, 1]))
        builder.Connect(table.GetOutputPort("motion"), mux.get_input_port(0))
        builder.Connect(contact.GetOutputPort("force"), mux.get_input_port(1))
        builder.ExportInput(table.GetInputPort("commanded_state"), "commanded_state")
        builder.ExportOutput(mux.get_output_port(0), "y")
        direct = linearize_system(builder.Build(), "plant")
        mine = self.continuous_plant(params)
        w = 2 * math.pi * params.contact_frequency_hz
        pts = np.array([0.5j, 1j, 10j, 0.3 + 2j]) * w
        a, b = mine.transfer(pts), direct.transfer(pts)
        err = float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))
        if not err <= rtol:
            raise LinearizationError(
                f"assembled plant differs from Drake's Linearize (relative {err:.3g})"
            )
        return err

    # -- model -------------------------------------------------------------------
    def blocks(self, params: HybridLoopParams) -> list[StateSpaceBlock]:
        """The discrete blocks at ``params`` in :data:`SAMPLED_LOOP_BLOCKS`
        order (the order of the model's states); the plant's states are the
        table's then the held command.

        Raises
        ------
        ParameterError
            If ``params.sample_rate_hz`` is None.
        """
        h = params.sample_period_s
        if h is None:
            raise ParameterError("a sampled model needs sample_rate_hz")
        return [
            self.spacecraft_block(params.spacecraft_mass_kg, h),
            zoh_plant(self.continuous_plant(params), h),
            self.sensor_block(params.sensor_delay_s, h),
            self.compensator_block(params.compensator_params(), h),
        ]

    def state_slices(self, params: HybridLoopParams) -> dict[str, slice]:
        """Where each block's states sit in the state of :meth:`open_loop`."""
        return state_slices(self.blocks(params))

    def open_loop(self, params: HybridLoopParams) -> LinearLoop:
        """The sampled open loop ``G`` (force on the spacecraft at tick ``k``
        -> compensated force at tick ``k``) at ``params`` (see :meth:`blocks`
        for the errors)."""
        m = self._loop_wiring.assemble(self.blocks(params), "sampled_open_loop")
        return LinearLoop(m.A, m.B, m.C, m.D, params.sample_period_s, params, None, ())
