"""The Stewart platform's leg servo: one digital PD law for both back-ends.

The 1-D back-end (:mod:`hybridtable.stewart.backend`) feeds it the legs'
reference from the docking axis, the 6-DoF one
(:mod:`hybridtable.six_dof.stewart_backend`) from the full pose.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import AffineSystem, MatrixGain, Multiplexer

if TYPE_CHECKING:
    from hybridtable.stewart.plant import StewartPlant

__all__ = ["LegServo"]


class LegServo(Diagram):
    """The legs' digital PD servo with the static gravity feed-forward, both
    back-ends' (the 1-D behind :class:`AxisInverseKinematics`, the 6-DoF
    behind the full-pose inverse kinematics):
    ``u_i = Kp (L_r,i - L_i) + Kd (L'_r,i - dL_i/dt) + u_g,i`` with ``u_g``
    the static leg forces against gravity at home.

    Drake's primitives, no Python per step: a ``Multiplexer`` of the two
    inputs, a ``MatrixGain`` selecting the errors ``[L_r - L; L'_r - dL/dt]``
    (differences, exact), and an ``AffineSystem`` ``[Kp I, Kd I] e + u_g``.

    Ports
    -----
    Input ``leg_reference`` (12: m, m/s)
        ``[L_r; L'_r]``: the reference legs' lengths and rates.
    Input ``plant_state``
    Output ``leg_forces`` (6, N)
        Actuation of legs 0..5.

    Parameters
    ----------
    handles : StewartPlant
    use_rates : bool
        Track ``L'_r``; without, the rates' reference is zero (a servo that
        follows the commanded lengths only).
    """

    def __init__(self, handles: StewartPlant, use_rates: bool = True) -> None:
        Diagram.__init__(self)
        kp, kd = handles.params.servo_gains()
        n = handles.plant.num_multibody_states()
        iq = 12 + np.asarray(handles.leg_position_indices)
        iv = 12 + handles.plant.num_positions() + np.asarray(handles.leg_velocity_indices)
        select = np.zeros((12, 12 + n))
        legs = np.arange(6)
        select[legs, legs] = 1.0
        select[legs, iq] = -1.0
        if use_rates:
            select[6 + legs, 6 + legs] = 1.0
        select[6 + legs, iv] = -1.0
        eye = np.eye(6)
        builder = DiagramBuilder()
        mux = builder.AddNamedSystem("inputs", Multiplexer([12, n]))
        errors = builder.AddNamedSystem("errors", MatrixGain(select))
        pd = builder.AddNamedSystem(
            "pd",
            AffineSystem(
                np.zeros((0, 0)),
                np.zeros((0, 12)),
                np.zeros(0),
                np.zeros((6, 0)),
                np.hstack([kp * eye, kd * eye]),
                handles.gravity_feedforward_n.copy(),
            ),
        )
        builder.Connect(mux.get_output_port(), errors.get_input_port())
        builder.Connect(errors.get_output_port(), pd.get_input_port())
        builder.ExportInput(mux.get_input_port(0), "leg_reference")
        builder.ExportInput(mux.get_input_port(1), "plant_state")
        builder.ExportOutput(pd.get_output_port(), "leg_forces")
        builder.BuildInto(self)
