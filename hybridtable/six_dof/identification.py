"""Online identification of the docking contact's stiffness from the wrench:
the 6-DoF ``sdmdc-online``.

The paper's MDC needs the contact stiffness, "identified in real time from
several past sampled contact force and position data points". Along one axis
``sdmdc-online`` fits ``f = k delta`` (and ``c delta_dot``) by recursive least
squares (:mod:`hybridtable.compensators.identification`). In 6-DoF the rig
computer's contact model (its pads and face, :class:`~hybridtable.six_dof.contact.DockingContact`,
with the stiffness it believes) says how the wrench depends on the pose: with
Hunt–Crossley pads every component is the stiffness times a function of the
pose and twist,

    w(q, qd) = k G(q, qd),     G = the model's wrench / its stiffness,

so each tick's six wrench components are six samples of the 1-D regression
``w_r = k G_r``, taken with the same recursive least squares, stabilized
forgetting and prior (:func:`~hybridtable.compensators.identification.information_step`
on the 1-D identifier's settings, :class:`~hybridtable.compensators.identification.IdentifierParams`).
Moments enter divided by the ring's radius, so every sample is a force. The
pose of a sample is the table's when the wrench was measured (a delay line
built like the F/T sensor's). The compensator's 6x6 ``K`` and ``C`` are then
the model's, in closed form at the table's pose, times ``k_hat / k_model``.

Why not fit a 6x6 matrix freely: on the offset example (10 mm, 2 deg) the
tangent stiffness along the axis goes from 1.25e4 to 1e5 N/m and back within
one contact as the tilted ring rolls onto its pads; an affine fit of the wrench
over a 0.1 s memory lags that by half, and ``K (q_des - q_act)`` came out
wrong by twice its size (2026-11-28).

Friction is not in the model; its forces lie in components the model gives
as zero (the face's plane, the moment about its normal), which then carry no
information. A sample is used while the measured force's norm exceeds the
identifier's threshold; outside contact the state is frozen and the estimate
is the prior.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import BasicVector, Diagram, DiagramBuilder, LeafSystem

from hybridtable.compensators.identification import (
    IdentifierParams,
    forgetting_factor,
    identifier_settings,
    information_step,
)
from hybridtable.six_dof.compensator import StiffnessModel, WrenchCompensator
from hybridtable.six_dof.contact import DockingContact
from hybridtable.systems.sensor import ForceSensorDelay

__all__ = ["StiffnessIdentifier", "online_wrench_identifier_params", "make_online_sdmdc"]


class StiffnessIdentifier(LeafSystem):
    """Recursive least squares of the contact's stiffness on the wrench,
    updated every ``period_s`` (see the module docstring).

    Ports
    -----
    Input ``measured_wrench`` (6: N m, N)
        From the F/T sensor.
    Input ``aligned_table_state`` (12: m, rad, m/s, rad/s)
        The table's ``[q; qd]`` of the instant the wrench was measured.
    Output ``stiffness_scale`` (1)
        ``k_hat / k_model``: the estimate over the model's stiffness (1 before
        the first contact sample, when ``params`` has the model's stiffness as
        its prior).

    Parameters
    ----------
    model : DockingContact
        The rig computer's contact model (its stiffness ``k_model``).
    params : IdentifierParams
        The 1-D identifier's settings (prior, its standard deviation, noise,
        memory, threshold); the damping is the model's (not identified).
    period_s : float
    """

    def __init__(self, model: DockingContact, params: IdentifierParams, period_s: float) -> None:
        LeafSystem.__init__(self)
        self.model = model
        self.params = params
        self._k_model = model.params.contact_stiffness_n_per_m
        arm = model.params.moment_arm_m
        self._scale = np.array([1.0 / arm] * 3 + [1.0] * 3)  # moments -> forces
        self._lam = forgetting_factor(params.forgetting_time_s, period_s)
        self._info = [params.prior_information()[0]]
        self._prior = [[params.prior_stiffness_n_per_m]]
        self._weight = 1.0 / params.force_noise_std_n**2
        self._w = self.DeclareVectorInputPort("measured_wrench", 6)
        self._x = self.DeclareVectorInputPort("aligned_table_state", 12)
        i_k = self._info[0]
        self._state = self.DeclareDiscreteState([i_k, i_k * params.prior_stiffness_n_per_m])
        self.DeclarePeriodicDiscreteUpdateEvent(period_s, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "stiffness_scale",
            BasicVector(1),
            self._output,
            {self.discrete_state_ticket(self._state)},
        )

    def _update(self, context, discrete_state) -> None:
        w = self._w.Eval(context)
        if not math.sqrt(w[3] ** 2 + w[4] ** 2 + w[5] ** 2) > self.params.force_threshold_n:
            return
        x = self._x.Eval(context)
        G = self._scale * self.model.wrench(x[:6], x[6:]) / self._k_model
        target = self._scale * np.asarray(w)
        Y, y = context.get_discrete_state(self._state).value()
        Y, y = [[Y]], [[y]]
        lam = self._lam  # the tick's forgetting and prior once, then its six samples
        for r in range(6):
            Y, y = information_step(
                Y, y, [G[r]], [target[r]], lam, self._info, self._prior, self._weight
            )
            lam = 1.0
        discrete_state.get_mutable_vector(self._state).SetFromVector([Y[0][0], y[0][0]])

    def _output(self, context, output) -> None:
        Y, y = context.get_discrete_state(self._state).value()
        output.SetFromVector([max(y / Y, 0.0) / self._k_model])


def online_wrench_identifier_params(params, **overrides) -> IdentifierParams:
    """Identifier settings for a 6-DoF loop (a
    :class:`~hybridtable.six_dof.params.DockingLoopParams`), by the 1-D
    ``sdmdc-online``'s rules (:func:`~hybridtable.compensators.identification.identifier_settings`)
    with the believed stiffness, the force deadband and the F/T sensor's force
    noise; the damping is not identified. Keyword arguments override any field."""
    return identifier_settings(
        params.believed_contact.contact_stiffness_n_per_m,
        params.force_deadband_n,
        params.force_noise_n,
        **overrides,
    )


def make_online_sdmdc(params, stiffness: StiffnessModel) -> Diagram:
    """The 6-DoF ``sdmdc-online`` (a wrench compensator registry factory):
    SDMDC on the wrench with ``K`` and ``C`` those of ``stiffness`` (the
    compensator's contact model linearized at the table's pose, or at the
    nominal pose; or the given matrix) times the identified stiffness over the
    believed one.

    Ports: those of :class:`~hybridtable.six_dof.compensator.WrenchCompensator`,
    plus the output ``stiffness_scale`` (the estimate over the model's stiffness).
    """
    h = params.sample_period_s
    builder = DiagramBuilder()
    delay = builder.AddNamedSystem(
        "state_alignment", ForceSensorDelay(params.rig.sensor, "sampled", h, size=12)
    )
    ident = builder.AddNamedSystem(
        "identifier",
        StiffnessIdentifier(
            DockingContact(params.believed_contact), online_wrench_identifier_params(params), h
        ),
    )
    sdmdc = builder.AddNamedSystem(
        "sdmdc",
        WrenchCompensator(
            h,
            lead_time_s=params.effective_lead_time_s,
            stiffness=stiffness,
            force_deadband_n=params.force_deadband_n,
            stiffness_scale_input=True,
            axial_deadband=params.deadband_reading == "axial_force",
            clamp_nonnegative=params.clamp_nonnegative,
        ),
    )
    builder.Connect(delay.get_output_port(0), ident.GetInputPort("aligned_table_state"))
    builder.Connect(ident.GetOutputPort("stiffness_scale"), sdmdc.GetInputPort("stiffness_scale"))
    index = builder.ExportInput(sdmdc.GetInputPort("measured_wrench"), "measured_wrench")
    builder.ConnectInput(index, ident.GetInputPort("measured_wrench"))
    index = builder.ExportInput(sdmdc.GetInputPort("table_state"), "table_state")
    builder.ConnectInput(index, delay.get_input_port(0))
    builder.ExportInput(sdmdc.GetInputPort("commanded_state"), "commanded_state")
    builder.ExportOutput(sdmdc.GetOutputPort("compensated_wrench"), "compensated_wrench")
    builder.ExportOutput(ident.GetOutputPort("stiffness_scale"), "stiffness_scale")
    diagram = builder.Build()
    diagram.set_name("sdmdc_online")
    return diagram
