"""Delay compensators of the paper: none, SDC (Eq. 2-3), MDC (Eq. 4-6), SDMDC (Eq. 7).

- SDC: phase lead on the measured force, ``f_hat = f_mea + T_lead df_mea/dt``.
- MDC: force correction from the table's response error,
  ``df_resp = k_con (p_des - p_act) + c_con (v_des - v_act)``.
- SDMDC: ``f_comp = f_hat + df_resp``.

The compensation acts during contact only (an MDC term acting in free flight
would drag the spacecraft). Two ways to tell contact, ``contact_gate``:

- ``"measured_force"`` (default, what a rig computer does and the
  ``hybridtable-run/1`` format defines): while the measured force is at or below
  ``force_deadband_n`` the compensated force is zero;
- ``"table_position"``: the MDC term acts while the table's position says the
  devices touch (``p_act > 0``); the measured force and its lead always pass. The paper's simulations feed
``f_comp`` to the spacecraft unclamped; a rig may clamp it at zero
(``clamp_nonnegative``), as the ``hybridtable-run/1`` format does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, LeafSystem_, System
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_choice, check_nonnegative

__all__ = [
    "COMPENSATORS",
    "CONTACT_GATES",
    "CompensatorParams",
    "Compensator",
    "paper_compensator",
    "Compensator_",
]


COMPENSATORS: tuple[str, ...] = ("none", "SDC", "MDC", "SDMDC")


CONTACT_GATES: tuple[str, ...] = ("measured_force", "table_position")


@dataclass(frozen=True)
class CompensatorParams:
    """Parameters of a compensator.

    Parameters
    ----------
    kind : {"none", "SDC", "MDC", "SDMDC"}
    lead_time_s : float
        Lead time T_lead of the SDC, >= 0 (the paper uses T_lead = T_fms).
    stiffness_n_per_m : float
        Contact stiffness k_con the MDC believes, >= 0.
    damping_n_s_per_m : float
        Contact damping the MDC believes (Eq. 6), >= 0.
    force_deadband_n : float
        Measured forces at or below this are "no contact": f_comp = 0.
    clamp_nonnegative : bool
        Clamp f_comp at zero (the compensated contact never pulls).
    contact_gate : {"measured_force", "table_position"}
        How the compensator tells contact (see the module docstring).
    """

    kind: str = "none"
    lead_time_s: float = 0.0
    stiffness_n_per_m: float = 0.0
    damping_n_s_per_m: float = 0.0
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False
    contact_gate: str = "measured_force"

    def __post_init__(self) -> None:
        check_choice("compensator", self.kind, COMPENSATORS)
        check_choice("contact_gate", self.contact_gate, CONTACT_GATES)
        for name in ("lead_time_s", "stiffness_n_per_m", "damping_n_s_per_m", "force_deadband_n"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))

    @property
    def uses_lead(self) -> bool:
        """True when the SDC phase lead is active."""
        return self.kind in ("SDC", "SDMDC")

    @property
    def uses_motion_correction(self) -> bool:
        """True when the MDC force correction is active."""
        return self.kind in ("MDC", "SDMDC")


@TemplateSystem.define("Compensator_", T_list=[float, AutoDiffXd])
def Compensator_(T):
    class Impl(LeafSystem_[T]):
        """The rig computer's force compensator.

        Ports
        -----
        Input ``measured_force`` (size 1, N)
            f_mea from the force sensor.
        Input ``measured_force_rate`` (size 1, N/s)
            d f_mea / dt; read only when ``derivative_period_s`` is None
            (continuous analysis), where it comes from delaying ``[f, df/dt]``.
        Input ``table_motion`` (size 3: m, m/s, m/s^2)
            ``[p_act, v_act, a_act]`` of the table.
        Input ``commanded_state`` (size 2: m, m/s)
            ``[p_des, v_des]`` of the spacecraft model (the table's command).
        Output ``compensated_force`` (size 1, N)
            f_comp = f_sim, fed to the spacecraft.

        With ``derivative_period_s = h`` the lead uses the backward difference
        ``(f_mea[k] - f_mea[k-1]) / h`` of a discrete state updated every ``h``,
        as a rig computer does. ``gated=False`` removes the contact gating and
        the clamp (the linear compensator used by the stability analysis).
        """

        def _construct(
            self,
            params: CompensatorParams,
            derivative_period_s: float | None = None,
            gated: bool = True,
            converter=None,
        ):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.derivative_period_s = derivative_period_s
            self.gated = bool(gated)
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self._fdot = self.DeclareVectorInputPort("measured_force_rate", 1)
            self._table = self.DeclareVectorInputPort("table_motion", 3)
            self._cmd = self.DeclareVectorInputPort("commanded_state", 2)
            # Flags of the hot path.
            p = params
            self._lead = p.lead_time_s if p.uses_lead else 0.0
            self._mdc = p.uses_motion_correction
            self._k = p.stiffness_n_per_m
            self._c = p.damping_n_s_per_m
            self._deadband = p.force_deadband_n
            self._gate_by_force = self.gated and p.contact_gate == "measured_force"
            self._gate_by_position = self.gated and p.contact_gate == "table_position"
            self._clamp = self.gated and p.clamp_nonnegative
            self._h = None
            if derivative_period_s is not None:
                self._h = float(derivative_period_s)
                self._prev = self.DeclareDiscreteState(1)
                self.DeclarePeriodicDiscreteUpdateEvent(self._h, 0.0, self._store)
            self.DeclareVectorOutputPort("compensated_force", BasicVector_[T](1), self._calc_force)

        def _construct_copy(self, other, converter=None):
            Impl._construct(
                self, other.params, other.derivative_period_s, other.gated, converter=converter
            )

        def _store(self, context, discrete_state):
            discrete_state.get_mutable_vector(0).SetAtIndex(0, self._f.Eval(context)[0])

        def _calc_force(self, context, output):
            # Hot path (called at every integrator stage): flags precomputed.
            f_mea = self._f.Eval(context)[0]
            if self._gate_by_force and not (f_mea > self._deadband):
                output.SetAtIndex(0, 0.0 * f_mea)
                return
            f = f_mea
            if self._lead > 0.0:
                if self._h is None:
                    rate = self._fdot.Eval(context)[0]
                else:
                    rate = (f_mea - context.get_discrete_state(0).GetAtIndex(0)) / self._h
                f = f + self._lead * rate
            if self._mdc:
                p_act, v_act, _ = self._table.Eval(context)
                if p_act > 0.0 or not self._gate_by_position:
                    p_des, v_des = self._cmd.Eval(context)
                    f = f + self._k * (p_des - p_act)
                    if self._c > 0.0:
                        f = f + self._c * (v_des - v_act)
            if self._clamp and f < 0.0:
                f = 0.0 * f
            output.SetAtIndex(0, f)

    return Impl


Compensator = Compensator_[None]


def paper_compensator(params: Any, derivative_period_s: float | None) -> System:
    """The paper's compensator ``params.compensator_params().kind`` for a
    :class:`~hybridtable.loop.params.HybridLoopParams` (the registry's factory
    of ``none``, ``SDC``, ``MDC`` and ``SDMDC``)."""
    return Compensator(params.compensator_params(), derivative_period_s=derivative_period_s)
