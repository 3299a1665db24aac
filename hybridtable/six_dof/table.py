"""The table model of the 6-DoF loop: each pose coordinate a second-order response.

The table moves the active device to the pose the spacecraft model commands.
Each of the six coordinates ``q = [p; theta]`` follows
``x'' = w^2 (u - x) - 2 zeta w x'`` (``w = 2 pi table_response_hz``) under the
command ``u`` held between ticks, solved exactly over each tick (the 1-D
table's response, per axis); an infinite response frequency is the ideal
table (``q_act = q_des``).

A structural mode between the table's servo and its contact device (the 1-D
``table_resonance``'s law, :func:`~hybridtable.systems.resonant_table.resonant_table_matrices`)
makes each coordinate fourth order (the servo, then the mode it drives), its
command ``[u, u']`` held over the tick (:func:`~hybridtable.laws.table.held_tick`,
the 1-D ``SampledTable``'s solution); the pose is the device's.

The table's state is kept one tick behind: its output at tick ``k`` is
``Phi s + Gamma u`` with ``u`` the command sent at tick ``k - 1`` (held over
the last interval), and its update stores that output. So the contact at tick
``k`` sees the table where the continuous 1-D table would be at ``t_k``.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import DiagramBuilder, System
from pydrake.systems.primitives import LinearSystem, PassThrough

from hybridtable.laws.table import held_tick, second_order_tick
from hybridtable.systems.resonant_table import StructuralModeParams, resonant_table_matrices
from hybridtable.systems.table import TableParams

__all__ = ["PoseTable", "add_pose_table", "pose_table_tick", "table_tick_matrices"]


def table_tick_matrices(
    response_hz: float, damping_ratio: float, period_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)`` (2x2, 2x1) of one coordinate's response over a tick
    with the command held: ``[x, x'] <- Phi [x, x'] + Gamma u``
    (:func:`hybridtable.laws.table.second_order_tick`)."""
    Phi, gamma = second_order_tick(response_hz, damping_ratio, period_s)
    return Phi, gamma[:, None]


def pose_table_tick(
    table: TableParams, period_s: float, mode: StructuralModeParams | None = None
) -> tuple[np.ndarray, np.ndarray] | None:
    """One pose coordinate's ``(Phi, Gamma)`` over a held tick: the
    second-order response (:func:`table_tick_matrices`), or with ``mode`` the
    servo then the structural mode (4 states; ``Gamma``'s columns the
    command's position and rate); None for the ideal table. The device's
    position and rate are the last two states."""
    if mode is not None:
        A4, B4, _, _ = resonant_table_matrices(table, mode)
        return held_tick(A4, B4, period_s)
    if table.is_ideal:
        return None
    return table_tick_matrices(table.response_frequency_hz, table.damping_ratio, period_s)


class PoseTable:
    """Handles to the table model added by :func:`add_pose_table`.

    Ports of :attr:`system`: input ``commanded_state`` (12: ``[q_des; qd_des]``,
    m, rad, m/s, rad/s), output ``table_state`` (12: ``[q_act; qd_act]``).
    """

    def __init__(self, system: System, tick: tuple[np.ndarray, np.ndarray] | None) -> None:
        self.system = system
        #: One coordinate's ``(Phi, Gamma)`` over a tick (``Gamma``'s columns:
        #: the command's position, and its rate where a mode reads it), or None
        #: (the ideal table).
        self._tick = tick

    @property
    def is_ideal(self) -> bool:
        return self._tick is None

    def set_initial_state(self, context, table_state: np.ndarray, command: np.ndarray) -> None:
        """Make the table's pose at t = 0 ``table_state`` (12) while
        ``command`` (12) is held (context: the table system's)."""
        if self._tick is None:
            return
        Phi, Gamma = self._tick
        n = Phi.shape[0]  # servo and mode at the pose, moving alike: the mode unstrained
        s = np.zeros(6 * n)
        for j in range(6):
            y = np.tile([table_state[j], table_state[6 + j]], n // 2)
            u = np.array([command[j], command[6 + j]][: Gamma.shape[1]])
            s[n * j : n * j + n] = np.linalg.solve(Phi, y - Gamma @ u)
        context.SetDiscreteState(s)


def add_pose_table(
    builder: DiagramBuilder,
    table: TableParams,
    period_s: float,
    mode: StructuralModeParams | None = None,
) -> PoseTable:
    """Add the table model to ``builder``: the 1-D table (``table``; an ideal
    one passes its command through) on each of the six pose coordinates,
    stepped over the rig computer's held tick; with ``mode``, a structural
    mode between its servo and the device on each (see the module)."""
    tick = pose_table_tick(table, period_s, mode)
    if tick is None:
        system = builder.AddNamedSystem("table", PassThrough(12))
        return PoseTable(system, None)
    Phi, Gamma = tick
    n, m = Gamma.shape
    A = np.zeros((6 * n, 6 * n))
    B = np.zeros((6 * n, 12))
    P = np.zeros((12, 6 * n))  # state [.., x_j, x'_j]... -> output [q; qd], the device's
    for j in range(6):
        A[n * j : n * j + n, n * j : n * j + n] = Phi
        for c in range(m):  # the command's position, then its rate
            B[n * j : n * j + n, j + 6 * c] = Gamma[:, c]
        P[j, n * j + n - 2] = 1.0
        P[6 + j, n * j + n - 1] = 1.0
    system = builder.AddNamedSystem("table", LinearSystem(A, B, P @ A, P @ B, period_s))
    return PoseTable(system, (Phi, Gamma))
