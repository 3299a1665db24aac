"""The second-order table followed by a lightly damped structural mode
(:class:`ResonantTable`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    LinearSystem,
)

from hybridtable._validation import check_positive
from hybridtable.systems.table import SampledTable, TableParams, table_matrices

__all__ = [
    "StructuralModeParams",
    "ResonantTable",
    "resonant_table_matrices",
]


# -- table ---------------------------------------------------------------------
@dataclass(frozen=True)
class StructuralModeParams:
    """A lightly damped structural mode between the table's servo and its
    contact device.

    Parameters
    ----------
    frequency_hz : float
        Natural frequency of the mode, > 0.
    damping_ratio : float
        Its damping ratio, > 0.
    """

    frequency_hz: float
    damping_ratio: float = 0.05

    def __post_init__(self) -> None:
        object.__setattr__(self, "frequency_hz", check_positive("frequency_hz", self.frequency_hz))
        object.__setattr__(
            self, "damping_ratio", check_positive("damping_ratio", self.damping_ratio)
        )


def resonant_table_matrices(
    table: TableParams, mode: StructuralModeParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space (A, B, C, D) of the second-order table carrying a mode.

    The servo (state ``[p_s, v_s]``, the nominal table) moves the base of the
    mode (state ``[p, v]``)::

        p'' = w_r^2 (p_s - p) + 2 zeta_r w_r (v_s - v)

    Input ``[p_des, v_des]``; output ``[p, v, p'']`` (the contact device).
    An ideal servo (``p_s = p_des``, ``v_s = v_des``) leaves only the mode's state.
    """
    wr = 2.0 * math.pi * mode.frequency_hz
    zr = mode.damping_ratio
    kr, cr = wr * wr, 2.0 * zr * wr
    if table.is_ideal:
        A = np.array([[0.0, 1.0], [-kr, -cr]])
        B = np.array([[0.0, 0.0], [kr, cr]])
    else:
        As, Bs, _, _ = table_matrices(table)
        A = np.zeros((4, 4))
        A[:2, :2] = As
        A[2, 3] = 1.0
        A[3] = [kr, cr, -kr, -cr]
        B = np.zeros((4, 2))
        B[:2] = Bs
    n = A.shape[0]
    C = np.vstack([np.eye(n)[n - 2 :], A[n - 1]])
    D = np.vstack([np.zeros((2, 2)), B[n - 1]])
    return A, B, C, D


class ResonantTable(Diagram):
    """The second-order table with a structural mode (:func:`resonant_table_matrices`).

    Ports
    -----
    Input ``commanded_state`` (size 2: m, m/s)
        ``[p_des, v_des]``.
    Output ``motion`` (size 3: m, m/s, m/s^2)
        ``[p_act, v_act, a_act]`` of the contact device (what the position
        sensor and the contact see).
    """

    def __init__(self, table: TableParams, mode: StructuralModeParams) -> None:
        Diagram.__init__(self)
        self.params = table
        self.mode = mode
        A, B, C, D = resonant_table_matrices(table, mode)
        builder = DiagramBuilder()
        self._linear = builder.AddNamedSystem("resonant_table", LinearSystem(A, B, C, D))
        builder.ExportInput(self._linear.get_input_port(), "commanded_state")
        builder.ExportOutput(self._linear.get_output_port(), "motion")
        builder.BuildInto(self)

    def sampled(self, period_s: float) -> SampledTable:
        """This table at the ticks of a held command (exact, :class:`SampledTable`)."""
        return SampledTable(resonant_table_matrices(self.params, self.mode), period_s)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Servo and mode at ``position_m`` moving with ``velocity_m_per_s``
        (the mode unstrained)."""
        n = 2 if self.params.is_ideal else 4
        x = np.tile([position_m, velocity_m_per_s], n // 2)
        self.GetSubsystemContext(self._linear, context).SetContinuousState(x)
