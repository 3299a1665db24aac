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

from pydrake.systems.framework import System

from hybridtable._validation import check_choice, check_nonnegative
from hybridtable.laws.compensation import CompensationLaw, backward_difference, compensate
from hybridtable.laws.compiled import compiled_system

__all__ = [
    "COMPENSATOR_INPUTS",
    "COMPENSATORS",
    "CONTACT_GATES",
    "CompensatorParams",
    "Compensator",
    "compensation_law",
    "compensator_output",
    "paper_compensator",
]


COMPENSATORS: tuple[str, ...] = ("none", "SDC", "MDC", "SDMDC")


CONTACT_GATES: tuple[str, ...] = ("measured_force", "table_position")

#: Input ports of every compensator, name -> size (units in :func:`Compensator`).
COMPENSATOR_INPUTS: dict[str, int] = {
    "measured_force": 1,
    "measured_force_rate": 1,
    "table_motion": 3,
    "commanded_state": 2,
}


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


def compensation_law(params: CompensatorParams, gated: bool = True) -> CompensationLaw:
    """The :class:`~hybridtable.laws.compensation.CompensationLaw` of ``params``
    (``gated=False``: no contact gate and no clamp, the linear compensator of
    the stability analysis)."""
    return CompensationLaw(
        lead_time_s=params.lead_time_s if params.uses_lead else 0.0,
        motion_correction=params.uses_motion_correction,
        force_deadband_n=params.force_deadband_n,
        gate=params.contact_gate if gated else "none",
        clamp_nonnegative=gated and params.clamp_nonnegative,
    )


def compensator_output(
    law: CompensationLaw,
    signals,
    derivative_period_s: float | None,
    stiffness,
    damping,
):
    """:func:`~hybridtable.laws.compensation.compensate` on the compensator's
    ports (``signals``: port name -> its values; ``previous_measured_force``
    the sample held at the last tick when ``derivative_period_s`` is set)."""
    f_mea = signals["measured_force"][0]
    rate = 0.0  # read only by a lead (the others may be unconnected)
    if law.lead_time_s > 0.0 and derivative_period_s is None:
        rate = signals["measured_force_rate"][0]
    elif law.lead_time_s > 0.0:
        previous = signals["previous_measured_force"][0]
        rate = backward_difference(f_mea, previous, derivative_period_s)
    if not law.motion_correction:
        return compensate(law, f_mea, rate)
    p_act, v_act, _ = signals["table_motion"]
    p_des, v_des = signals["commanded_state"]
    touching = p_act > 0.0
    return compensate(
        law, f_mea, rate, p_des - p_act, v_des - v_act, stiffness, damping, touching=touching
    )


def Compensator(
    params: CompensatorParams,
    derivative_period_s: float | None = None,
    gated: bool = True,
    gains_input: bool = False,
    compiled: bool = True,
) -> System:
    """The rig computer's force compensator, compiled from the law.

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
    Input ``contact_parameters`` (size 2: N/m, N s/m), with ``gains_input``
        ``[k, c]`` of the MDC term (an online identifier's estimate; the
        stiffness and damping of ``params`` are then ignored).
    Output ``compensated_force`` (size 1, N)
        f_comp = f_sim, fed to the spacecraft.

    With ``derivative_period_s = h`` the lead uses the backward difference
    ``(f_mea[k] - f_mea[k-1]) / h`` of the sample a ``ZeroOrderHold`` took at
    the last tick, as a rig computer does. ``gated=False`` removes the contact
    gating and the clamp (the linear compensator used by the stability
    analysis: an ``AffineSystem``). The law is
    :func:`hybridtable.laws.compensation.compensate`, evaluated in C++
    (:func:`hybridtable.laws.compiled.compiled_system`); ``compiled=False``
    evaluates it in a Python callback, cheaper where the diagram reads the
    compensator only at the ticks of a sampled rig computer.
    """
    law = compensation_law(params, gated)
    h = None if derivative_period_s is None else float(derivative_period_s)
    inputs = dict(COMPENSATOR_INPUTS)
    if gains_input:
        inputs["contact_parameters"] = 2
    c = params.damping_n_s_per_m

    def compensated_force(signals):
        if gains_input:
            k_hat, c_hat = signals["contact_parameters"]
            gains = (k_hat, c_hat)
        else:
            gains = (params.stiffness_n_per_m, c if c > 0.0 else None)
        return compensator_output(law, signals, h, *gains)

    held = {} if h is None else {"previous_measured_force": ("measured_force", h)}
    outputs = {"compensated_force": compensated_force}
    system = compiled_system("compensator", inputs, outputs, held, compiled)
    system.params = params
    system.derivative_period_s = h
    system.gated = bool(gated)
    return system


def paper_compensator(params: Any, derivative_period_s: float | None) -> System:
    """The paper's compensator ``params.compensator_params().kind`` for a
    :class:`~hybridtable.loop.params.HybridLoopParams` (the registry's factory
    of ``none``, ``SDC``, ``MDC`` and ``SDMDC``): compiled in a continuous
    loop, where every integrator stage reads it; a Python callback on a
    sampled rig computer, which reads it once a tick (measured in
    ``benchmarks/bench_core.py``)."""
    return Compensator(
        params.compensator_params(),
        derivative_period_s=derivative_period_s,
        compiled=params.sample_rate_hz is None,
    )
