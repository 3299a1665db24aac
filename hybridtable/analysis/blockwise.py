"""Block-wise Drake linearization of the in-contact loop, assembled per operating point.

Each block of :func:`~hybridtable.analysis.linearize.add_contact_loop` is
linearized with Drake's ``Linearize``
(:func:`~hybridtable.analysis.linearize.linearize_system`) once per structure
and re-assembled per operating point with
:class:`~hybridtable.analysis.interconnect.Interconnection` (fast; used by
sweeps). Parameters enter the blocks in a known way, each checked when first
used: the table is a time-scaled copy of the unit-frequency table (states
``[p, v]`` scaled by ``[1, w]``, outputs ``[p, v, a]`` by ``[1, w, w^2]``), the
Pade block with its delay (``A = A_1 / T``, ``B = B_1 / T``), the compensator
is affine in its lead time. The model is the
:class:`~hybridtable.analysis.linearize.LinearLoop` of
:func:`~hybridtable.analysis.linearize.linearize_contact_loop`, in another
state basis.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from hybridtable.analysis.interconnect import Interconnection, StateSpaceBlock, state_slices
from hybridtable.analysis.linearize import (
    LinearLoop,
    check_pade_order,
    linearization_notes,
    linearize_contact_loop,
    linearize_system,
)
from hybridtable.compensators.paper import Compensator, CompensatorParams
from hybridtable.errors import LinearizationError
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.wiring import LOOP_WIRING, channel_wiring, edge
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.systems.table import SecondOrderTable, TableParams

__all__ = [
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

    Each block of :func:`~hybridtable.analysis.linearize.add_contact_loop` is
    linearized with Drake's ``Linearize`` once per structure (and cached); the
    blocks' parameters are applied by the scalings described in
    :mod:`hybridtable.analysis.blockwise`, each verified against a second
    direct ``Linearize`` when the structure is first met. :meth:`verify` compares an assembled model with a direct
    ``Linearize`` of the full diagram.

    Parameters
    ----------
    pade_order : int
        Order of the Pade approximant of the sensor delay.
    """

    def __init__(self, pade_order: int = 3) -> None:
        self.pade_order = check_pade_order(pade_order)
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

    # channel wiring of add_contact_loop: the loop's, open at the spacecraft's
    # force, with the sensor carrying [f, df/dt] to the compensator's two inputs
    @staticmethod
    def _connections(with_sensor: bool) -> dict[str, str]:
        cut = {edge("compensator.compensated_force", "spacecraft.force")}
        if not with_sensor:
            cut |= {
                edge("contact.force", "force_sensor.force"),
                edge("force_sensor.measured_force", "compensator.measured_force"),
            }
        c = channel_wiring(e for e in LOOP_WIRING if e not in cut)
        if with_sensor:
            c["force_sensor.force[1]"] = "contact.force_rate[0]"
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
            return self.table_block(p.plant.table)
        if name == "contact":
            return self.contact_block(p.plant.contact)
        if name == "force_sensor":
            return self.sensor_block(p.sensor_delay_s)
        return self.compensator_block(p.compensator_params())

    # -- models ------------------------------------------------------------------
    def open_loop(self, params: HybridLoopParams) -> LinearLoop:
        """The open loop ``G`` at ``params`` (same model as
        :func:`~hybridtable.analysis.linearize.linearize_contact_loop`, in another
        state basis)."""
        m = self._open.assemble(self.blocks(params), "open_loop")
        return LinearLoop(
            m.A, m.B, m.C, m.D, 0.0, params, self.pade_order, linearization_notes(params)
        )

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
