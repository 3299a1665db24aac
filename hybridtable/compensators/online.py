"""``sdmdc-online``: SDMDC whose contact stiffness and damping are identified
online (:mod:`hybridtable.compensators.identification`).

The compensator is the paper's SDMDC (Eq. 7),

    f_comp = f_mea + T_lead (f_mea[k] - f_mea[k-1]) / h
             + k_hat (p_des - p_act) + c_hat (v_des - v_act),

with ``[k_hat, c_hat]`` read from a :class:`~hybridtable.compensators.identification.ContactIdentifier`
that starts from the compensator's prior (``compensator_stiffness_n_per_m``,
``compensator_damping_n_s_per_m``) and is updated every rig-computer tick from
the measured force and the table motion of the same instant.
"""

from __future__ import annotations

import math

from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, Diagram, DiagramBuilder, LeafSystem_
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable.compensators._wiring import export_compensator_ports, sensor_like_delay
from hybridtable.compensators.identification import ContactIdentifier, IdentifierParams
from hybridtable.compensators.paper import CompensatorParams
from hybridtable.errors import ParameterError

__all__ = [
    "AdaptiveSDMDC",
    "AdaptiveSDMDC_",
    "online_identifier_params",
    "make_online_sdmdc",
]


@TemplateSystem.define("AdaptiveSDMDC_", T_list=[float, AutoDiffXd])
def AdaptiveSDMDC_(T):
    class Impl(LeafSystem_[T]):
        """SDMDC whose stiffness and damping come from an input port.

        Ports
        -----
        Input ``measured_force`` (size 1, N)
        Input ``measured_force_rate`` (size 1, N/s)
            Read only when ``derivative_period_s`` is None.
        Input ``table_motion`` (size 3: m, m/s, m/s^2)
        Input ``commanded_state`` (size 2: m, m/s)
        Input ``contact_parameters`` (size 2: N/m, N s/m)
            ``[k, c]`` used by the MDC term.
        Output ``compensated_force`` (size 1, N)

        Gating, clamping and the lead follow
        :class:`hybridtable.compensators.paper.Compensator` with ``kind="SDMDC"``
        (``params.stiffness_n_per_m`` and ``damping_n_s_per_m`` are ignored).
        """

        def _construct(
            self,
            params: CompensatorParams,
            derivative_period_s: float | None = None,
            converter=None,
        ):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.derivative_period_s = derivative_period_s
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self._fdot = self.DeclareVectorInputPort("measured_force_rate", 1)
            self._table = self.DeclareVectorInputPort("table_motion", 3)
            self._cmd = self.DeclareVectorInputPort("commanded_state", 2)
            self._kc = self.DeclareVectorInputPort("contact_parameters", 2)
            if derivative_period_s is not None:
                self._h = float(derivative_period_s)
                self.DeclareDiscreteState(1)
                self.DeclarePeriodicDiscreteUpdateEvent(self._h, 0.0, self._store)
            self.DeclareVectorOutputPort("compensated_force", BasicVector_[T](1), self._calc)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.derivative_period_s, converter=converter)

        def _store(self, context, discrete_state):
            discrete_state.get_mutable_vector(0).SetAtIndex(0, self._f.Eval(context)[0])

        def _calc(self, context, output):
            p = self.params
            f_mea = self._f.Eval(context)[0]
            by_force = p.contact_gate == "measured_force"
            if by_force and not (f_mea > p.force_deadband_n):
                output.SetAtIndex(0, 0.0 * f_mea)
                return
            f = f_mea
            if p.lead_time_s > 0.0:
                if self.derivative_period_s is None:
                    rate = self._fdot.Eval(context)[0]
                else:
                    rate = (f_mea - context.get_discrete_state(0).GetAtIndex(0)) / self._h
                f = f + p.lead_time_s * rate
            p_act, v_act, _ = self._table.Eval(context)
            if by_force or p_act > 0.0:
                p_des, v_des = self._cmd.Eval(context)
                k, c = self._kc.Eval(context)
                f = f + k * (p_des - p_act) + c * (v_des - v_act)
            if p.clamp_nonnegative and f < 0.0:
                f = 0.0 * f
            output.SetAtIndex(0, f)

    return Impl


AdaptiveSDMDC = AdaptiveSDMDC_[None]


def online_identifier_params(params, **overrides) -> IdentifierParams:
    """Identifier settings for a loop (a :class:`~hybridtable.loop.params.HybridLoopParams`).

    Prior: what the compensator believes (``compensator_stiffness_n_per_m``,
    ``compensator_damping_n_s_per_m``, default the true values). Prior
    standard deviations: 100 % of the prior stiffness, and half the critical
    damping ``2 sqrt(k m)`` of the prior stiffness with the model's mass.
    Noise: a third of the force deadband (at least 1 mN). Samples are used
    above the force deadband; the memory is 0.1 s. Keyword arguments override
    any field of :class:`~hybridtable.compensators.identification.IdentifierParams`.
    """
    comp = params.with_(compensator="SDMDC").compensator_params()
    k = comp.stiffness_n_per_m
    if not k > 0.0:
        raise ParameterError(
            "sdmdc-online needs a prior stiffness > 0 (compensator_stiffness_n_per_m)"
        )
    fields = {
        "prior_stiffness_n_per_m": k,
        "prior_damping_n_s_per_m": comp.damping_n_s_per_m,
        "stiffness_std_n_per_m": k,
        "damping_std_n_s_per_m": math.sqrt(k * params.spacecraft_mass_kg),
        "force_noise_std_n": max(params.force_deadband_n / 3.0, 1e-3),
        "forgetting_time_s": 0.1,
        "force_threshold_n": params.force_deadband_n,
    }
    fields.update(overrides)
    return IdentifierParams(**fields)


def make_online_sdmdc(
    params, derivative_period_s: float, identifier: IdentifierParams | None = None
) -> Diagram:
    """The ``sdmdc-online`` compensator for a loop (registry factory).

    Parameters
    ----------
    params : HybridLoopParams
    derivative_period_s : float
        The rig computer's period (backward difference and identifier updates).
    identifier : IdentifierParams, optional
        Default: :func:`online_identifier_params`.

    Returns
    -------
    Diagram
        Ports of :class:`hybridtable.compensators.paper.Compensator`, plus the output
        ``contact_parameters`` (the estimate ``[k, c]``).
    """
    if derivative_period_s is None:
        raise ParameterError("sdmdc-online needs a discrete period (derivative_period_s)")
    identifier = identifier or online_identifier_params(params)
    comp = params.with_(compensator="SDMDC").compensator_params()
    builder = DiagramBuilder()
    ident = builder.AddNamedSystem(
        "identifier",
        ContactIdentifier(identifier, derivative_period_s, sensor_like_delay(params, 3)),
    )
    sdmdc = builder.AddNamedSystem("sdmdc", AdaptiveSDMDC(comp, derivative_period_s))
    builder.Connect(
        ident.GetOutputPort("contact_parameters"), sdmdc.GetInputPort("contact_parameters")
    )
    export_compensator_ports(
        builder,
        {
            "measured_force": [
                sdmdc.GetInputPort("measured_force"),
                ident.GetInputPort("measured_force"),
            ],
            "measured_force_rate": [sdmdc.GetInputPort("measured_force_rate")],
            "table_motion": [
                sdmdc.GetInputPort("table_motion"),
                ident.GetInputPort("table_motion"),
            ],
            "commanded_state": [sdmdc.GetInputPort("commanded_state")],
        },
        sdmdc.GetOutputPort("compensated_force"),
        {"contact_parameters": ident.GetOutputPort("contact_parameters")},
    )
    diagram = builder.Build()
    diagram.set_name("sdmdc_online")
    return diagram
