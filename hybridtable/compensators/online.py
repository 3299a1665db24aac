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
from dataclasses import replace

from pydrake.systems.framework import Diagram, DiagramBuilder, System

from hybridtable.compensators._wiring import export_compensator_ports, sensor_like_delay
from hybridtable.compensators.identification import (
    ContactIdentifier,
    IdentifierParams,
    identifier_settings,
)
from hybridtable.compensators.paper import Compensator, CompensatorParams
from hybridtable.errors import ParameterError

__all__ = [
    "AdaptiveSDMDC",
    "online_identifier_params",
    "make_online_sdmdc",
]


def AdaptiveSDMDC(
    params: CompensatorParams, derivative_period_s: float | None = None, compiled: bool = True
) -> System:
    """SDMDC whose stiffness and damping come from an input port.

    The ports of :func:`hybridtable.compensators.paper.Compensator` plus input
    ``contact_parameters`` (size 2: N/m, N s/m), the ``[k, c]`` of the MDC
    term; gating, clamping and the lead are the law of ``params`` with
    ``kind="SDMDC"`` (its stiffness and damping are ignored).
    """
    return Compensator(
        replace(params, kind="SDMDC"), derivative_period_s, gains_input=True, compiled=compiled
    )


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
        "prior_damping_n_s_per_m": comp.damping_n_s_per_m,
        "damping_std_n_s_per_m": math.sqrt(k * params.spacecraft_mass_kg),
        **overrides,
    }
    return identifier_settings(k, params.force_deadband_n, **fields)


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
    sdmdc = builder.AddNamedSystem(
        "sdmdc", AdaptiveSDMDC(comp, derivative_period_s, params.sample_rate_hz is None)
    )
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
