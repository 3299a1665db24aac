"""The paper's compensators on the wrench: SDC, MDC with a 6x6 stiffness, SDMDC.

With ``w_mea`` the measured wrench ``[moment; force]`` (6, W, at the port
origin), ``q = [p; theta]`` the device pose coordinates and ``K = -dw/dq``:

- SDC: ``w_hat = w_mea + T_lead (w_mea[k] - w_mea[k-1]) / h`` (Eq. 2-3 per component);
- MDC: ``w_c = w_mea - K (q_des - q_act) - C (qd_des - qd_act)`` (Eq. 6: the
  paper writes it with a 6x6 stiffness matrix; on axis it is ``k_con (p_des -
  p_act)`` on the compression force);
- SDMDC: both.

While the measured force's norm (or, ``deadband_reading="axial_force"``, its
compression along the docking axis ``-fz``: the 1-D run format's reading) is
at or below ``force_deadband_n`` the compensated wrench is zero (the 1-D gate
on the measured force); with ``clamp_nonnegative`` it is zero too while its
force would pull along the axis (``fz > 0``: the 1-D format's clamp of a
compression force that turned negative). The law is
the 1-D one, :func:`hybridtable.laws.compensation.compensate`, on arrays
(``G = -K``, ``D = -C``). ``K`` and
``C`` come from a stiffness model: the contact linearized at the table's pose
at every tick of the contact (Drake's contact, in closed form from one
evaluation: :meth:`~hybridtable.six_dof.contact.DockingContact.stiffness`), or
a given matrix.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from hybridtable.laws.compensation import CompensationLaw, backward_difference, compensate
from hybridtable.six_dof.contact import DockingContact

__all__ = ["StiffnessModel", "WrenchCompensator", "constant_stiffness", "stiffness_model_of"]

#: ``stiffness(q_act, qd_act) -> (K, C)``, each 6x6.
StiffnessModel = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def constant_stiffness(K: np.ndarray, C: np.ndarray | None = None) -> StiffnessModel:
    """A stiffness model that always gives ``K`` (and ``C``, default zero)."""
    K = np.asarray(K, dtype=float)
    C = np.zeros((6, 6)) if C is None else np.asarray(C, dtype=float)
    return lambda q, qd: (K, C)


def stiffness_model_of(params) -> StiffnessModel:
    """The MDC's stiffness model of a scenario
    (:class:`~hybridtable.six_dof.params.DockingLoopParams`): its ``given``
    matrix, its believed contact linearized once at the nominal pose, or
    (``linearized``) that contact linearized where it is asked."""
    if params.stiffness_model == "given":
        return constant_stiffness(np.array(params.compensator_stiffness_matrix))
    model = DockingContact(params.believed_contact)
    if params.stiffness_model == "nominal":
        return constant_stiffness(*model.stiffness(params.nominal_pose()))
    return model.stiffness


class WrenchCompensator(LeafSystem):
    """The rig computer's wrench compensator.

    Ports
    -----
    Input ``measured_wrench`` (6: N m, N)
        From the F/T sensor.
    Input ``table_state`` (12: m, rad, m/s, rad/s)
        ``[q_act; qd_act]`` of the table (its encoders).
    Input ``commanded_state`` (12)
        ``[q_des; qd_des]`` of the spacecraft model's port.
    Output ``compensated_wrench`` (6: N m, N)
        Fed to the spacecraft model.

    Parameters
    ----------
    period_s : float
        The rig computer's tick h (the lead's backward difference).
    lead_time_s : float
        SDC lead (0: no lead).
    stiffness : StiffnessModel or None
        The MDC's stiffness (None: no MDC term).
    force_deadband_n : float
    stiffness_scale_input : bool
        Multiply ``stiffness``'s ``K`` and ``C`` by the input ``stiffness_scale``
        (1: an online estimate of the contact's stiffness over the model's,
        :mod:`~hybridtable.six_dof.identification`).
    axial_deadband : bool
        The dead band reads the compression along the axis, ``-fz``, not the
        force's norm.
    clamp_nonnegative : bool
        Zero while the compensated force pulls along the axis (``fz > 0``).
    """

    def __init__(
        self,
        period_s: float,
        lead_time_s: float = 0.0,
        stiffness: StiffnessModel | None = None,
        force_deadband_n: float = 0.0,
        stiffness_scale_input: bool = False,
        axial_deadband: bool = False,
        clamp_nonnegative: bool = False,
    ) -> None:
        LeafSystem.__init__(self)
        self._h = float(period_s)
        self._axial = bool(axial_deadband)
        self._stiffness = stiffness
        self._scale = None
        if stiffness_scale_input:
            self._scale = self.DeclareVectorInputPort("stiffness_scale", 1)
        #: The 1-D law on the wrench, gated by the measured force's norm.
        self.law = CompensationLaw(
            lead_time_s=float(lead_time_s),
            motion_correction=stiffness is not None,
            force_deadband_n=float(force_deadband_n),
            clamp_nonnegative=bool(clamp_nonnegative),
        )
        self._w = self.DeclareVectorInputPort("measured_wrench", 6)
        self._table = self.DeclareVectorInputPort("table_state", 12)
        self._cmd = self.DeclareVectorInputPort("commanded_state", 12)
        self._prev = self.DeclareDiscreteState(6)
        self.DeclarePeriodicDiscreteUpdateEvent(self._h, 0.0, self._store)
        self.DeclareVectorOutputPort("compensated_wrench", BasicVector(6), self._calc)

    def _store(self, context, discrete_state) -> None:
        discrete_state.get_mutable_vector(0).SetFromVector(self._w.Eval(context))

    def _calc(self, context, output) -> None:
        w = np.array(self._w.Eval(context))
        level = -w[5] if self._axial else np.linalg.norm(w[3:])
        if not self.law.gate_open(level):  # before K: it costs a contact evaluation
            output.SetFromVector(np.zeros(6))
            return
        previous = context.get_discrete_state(0).value()
        rate = backward_difference(w, previous, self._h)
        if not self.law.motion_correction:
            output.SetFromVector(
                compensate(self.law, w, rate, gate_force=level, compression=_compression)
            )
            return
        x_act = self._table.Eval(context)
        x_des = self._cmd.Eval(context)
        K, C = self._stiffness(x_act[:6], x_act[6:])
        if self._scale is not None:
            scale = self._scale.Eval(context)[0]
            K, C = scale * K, scale * C
        # G = dw/dq = -K: the law predicts the wrench at the commanded pose.
        out = compensate(
            self.law,
            w,
            rate,
            x_des[:6] - x_act[:6],
            x_des[6:] - x_act[6:],
            -K,
            -C if np.any(C) else None,
            gate_force=level,
            compression=_compression,
        )
        output.SetFromVector(out)


def _compression(wrench: np.ndarray) -> float:
    """The wrench's force along the docking axis, pressing (``-fz``): what the
    1-D clamp keeps from pulling."""
    return -wrench[5]
