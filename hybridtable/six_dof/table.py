"""The table model of the 6-DoF loop: each pose coordinate a second-order response.

The table moves the active device to the pose the spacecraft model commands.
Each of the six coordinates ``q = [p; theta]`` follows
``x'' = w^2 (u - x) - 2 zeta w x'`` (``w = 2 pi table_response_hz``) under the
command ``u`` held between ticks, solved exactly over each tick (the 1-D
table's response, per axis); an infinite response frequency is the ideal
table (``q_act = q_des``).

The table's state is kept one tick behind: its output at tick ``k`` is
``Phi s + Gamma u`` with ``u`` the command sent at tick ``k - 1`` (held over
the last interval), and its update stores that output. So the contact at tick
``k`` sees the table where the continuous 1-D table would be at ``t_k``.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import DiagramBuilder, System
from pydrake.systems.primitives import LinearSystem, PassThrough

from hybridtable.laws.table import second_order_tick
from hybridtable.systems.table import TableParams

__all__ = ["PoseTable", "add_pose_table", "table_tick_matrices"]


def table_tick_matrices(
    response_hz: float, damping_ratio: float, period_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)`` (2x2, 2x1) of one coordinate's response over a tick
    with the command held: ``[x, x'] <- Phi [x, x'] + Gamma u``
    (:func:`hybridtable.laws.table.second_order_tick`)."""
    Phi, gamma = second_order_tick(response_hz, damping_ratio, period_s)
    return Phi, gamma[:, None]


class PoseTable:
    """Handles to the table model added by :func:`add_pose_table`.

    Ports of :attr:`system`: input ``commanded_state`` (12: ``[q_des; qd_des]``,
    m, rad, m/s, rad/s), output ``table_state`` (12: ``[q_act; qd_act]``).
    """

    def __init__(self, system: System, tick: tuple[np.ndarray, np.ndarray] | None) -> None:
        self.system = system
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
        s = np.zeros(12)
        for j in range(6):
            y = np.array([table_state[j], table_state[6 + j]])
            s[2 * j : 2 * j + 2] = np.linalg.solve(Phi, y - Gamma[:, 0] * command[j])
        context.SetDiscreteState(s)


def add_pose_table(builder: DiagramBuilder, table: TableParams, period_s: float) -> PoseTable:
    """Add the table model to ``builder``: the 1-D table (``table``; an ideal
    one passes its command through) on each of the six pose coordinates,
    stepped over the rig computer's held tick."""
    if table.is_ideal:
        system = builder.AddNamedSystem("table", PassThrough(12))
        return PoseTable(system, None)
    Phi, Gamma = table_tick_matrices(table.response_frequency_hz, table.damping_ratio, period_s)
    A = np.zeros((12, 12))
    B = np.zeros((12, 12))
    P = np.zeros((12, 12))  # state [x_j, x'_j]... -> output [q; qd]
    for j in range(6):
        A[2 * j : 2 * j + 2, 2 * j : 2 * j + 2] = Phi
        B[2 * j : 2 * j + 2, j] = Gamma[:, 0]
        P[j, 2 * j] = 1.0
        P[6 + j, 2 * j + 1] = 1.0
    system = builder.AddNamedSystem("table", LinearSystem(A, B, P @ A, P @ B, period_s))
    return PoseTable(system, (Phi, Gamma))
