"""``smith``: a model-based Smith predictor of the contact force.

The loop's "plant", seen from the spacecraft model, maps the commanded state
``[p_des, v_des]`` to the measured force: the table lags the command, the
contact turns the table motion into force, the sensor delays it by ``T_fms``.
A Smith predictor feeds back the delay-free model output corrected by the
difference between the measurement and the delayed model output:

    f_comp = f_mea + F(p_des, v_des) - F(p_act(t - T), v_act(t - T)),

with the contact model ``F(p, v) = max(k p + c v, 0)`` for ``p > 0`` and 0
otherwise (unilateral, with the stiffness and damping the compensator
believes). ``F(p_des, v_des)`` is the force an ideal table would have produced
now; ``F`` of the table motion delayed exactly like the force sensor delays
the force (:func:`hybridtable.compensators._wiring.sensor_like_delay`) predicts
``f_mea``. With an exact model the measured force and its prediction cancel
and ``f_comp`` is the ideal force, including at contact onset (before any
force is measured) and at separation. A model error ``k - k_model`` leaves
``(k - k_model) p_act(t - T)`` of delayed force in ``f_comp``.

Measured forces at or below ``force_deadband_n`` count as zero, and so do
predicted delayed forces (the model of the measurement includes the
deadband).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, Diagram, DiagramBuilder, LeafSystem_
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative
from hybridtable.compensators._wiring import export_compensator_ports, sensor_like_delay
from hybridtable.compensators.identification import ContactIdentifier, IdentifierParams
from hybridtable.errors import ParameterError
from hybridtable.laws.compensation import above_deadband, nonnegative
from hybridtable.laws.contact import spring_contact_force

__all__ = [
    "SmithParams",
    "SmithPredictor",
    "SmithPredictor_",
    "smith_params",
    "unilateral_force",
    "make_smith",
    "make_smith_online",
]


@dataclass(frozen=True)
class SmithParams:
    """Parameters of the Smith predictor, SI units.

    Parameters
    ----------
    stiffness_n_per_m, damping_n_s_per_m : float
        The contact model, >= 0.
    force_deadband_n : float
        Measured (and predicted measured) forces at or below this count as 0.
    clamp_nonnegative : bool
        Clamp f_comp at zero.
    """

    stiffness_n_per_m: float
    damping_n_s_per_m: float = 0.0
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False

    def __post_init__(self) -> None:
        for name in ("stiffness_n_per_m", "damping_n_s_per_m", "force_deadband_n"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))

    def contact_force(self, p, v):
        """The model ``F(p, v)``: unilateral spring-damper."""
        return unilateral_force(self.stiffness_n_per_m, self.damping_n_s_per_m, p, v)


def unilateral_force(k, c, p, v):
    """``max(k p + c v, 0)`` while ``p > 0``, else 0 (any scalar type): the
    contact law :func:`hybridtable.laws.contact.spring_contact_force`."""
    return spring_contact_force(k, c, p, v)


@TemplateSystem.define("SmithPredictor_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__])
def SmithPredictor_(T):
    class Impl(LeafSystem_[T]):
        """Smith predictor of the contact force.

        Ports: those of :class:`hybridtable.compensators.paper.Compensator`
        (``measured_force_rate`` unused), plus

        Input ``delayed_table_motion`` (size 3: m, m/s, m/s^2)
            The table motion delayed like the measured force.
        Input ``contact_parameters`` (size 2: N/m, N s/m), when ``adaptive``
            The model ``[k, c]`` (e.g. an online identifier's estimate);
            ``params.stiffness_n_per_m`` and ``damping_n_s_per_m`` are then
            not used.

        Output ``compensated_force`` (size 1, N)
            ``f_mea + F(p_des, v_des) - F(p_act(t - T), v_act(t - T))``.
        """

        def _construct(self, params: SmithParams, adaptive: bool = False, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.adaptive = bool(adaptive)
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self.DeclareVectorInputPort("measured_force_rate", 1)
            self.DeclareVectorInputPort("table_motion", 3)
            self._cmd = self.DeclareVectorInputPort("commanded_state", 2)
            self._delayed = self.DeclareVectorInputPort("delayed_table_motion", 3)
            if self.adaptive:
                self._kc = self.DeclareVectorInputPort("contact_parameters", 2)
            self.DeclareVectorOutputPort("compensated_force", BasicVector_[T](1), self._calc)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.adaptive, converter=converter)

        def _calc(self, context, output):
            p = self.params
            deadband = p.force_deadband_n
            f_mea = above_deadband(self._f.Eval(context)[0], deadband)
            p_des, v_des = self._cmd.Eval(context)
            p_old, v_old, _ = self._delayed.Eval(context)
            if self.adaptive:
                k, c = self._kc.Eval(context)
            else:
                k, c = p.stiffness_n_per_m, p.damping_n_s_per_m
            predicted = above_deadband(unilateral_force(k, c, p_old, v_old), deadband)
            f = f_mea + unilateral_force(k, c, p_des, v_des) - predicted
            if p.clamp_nonnegative:
                f = nonnegative(f)
            output.SetAtIndex(0, f)

    return Impl


SmithPredictor = SmithPredictor_[None]


def smith_params(params, **overrides) -> SmithParams:
    """Settings for a loop: the contact the compensator believes
    (``compensator_stiffness_n_per_m``, ``compensator_damping_n_s_per_m``,
    default the true values), the loop's deadband and clamp."""
    comp = params.with_(compensator="SDMDC").compensator_params()
    fields = {
        "stiffness_n_per_m": comp.stiffness_n_per_m,
        "damping_n_s_per_m": comp.damping_n_s_per_m,
        "force_deadband_n": params.force_deadband_n,
        "clamp_nonnegative": params.clamp_nonnegative,
    }
    fields.update(overrides)
    return SmithParams(**fields)


def make_smith(params, derivative_period_s: float | None = None) -> Diagram:
    """The ``smith`` compensator for a loop (registry factory): the predictor
    and a delay of the table motion built like the loop's force sensor
    (``derivative_period_s`` is not needed: the delay line has the sensor's
    period)."""
    builder = DiagramBuilder()
    delay = builder.AddNamedSystem("motion_delay", sensor_like_delay(params, 3))
    smith = builder.AddNamedSystem("smith", SmithPredictor(smith_params(params)))
    builder.Connect(delay.get_output_port(0), smith.GetInputPort("delayed_table_motion"))
    export_compensator_ports(
        builder,
        {
            "measured_force": [smith.GetInputPort("measured_force")],
            "measured_force_rate": [smith.GetInputPort("measured_force_rate")],
            "table_motion": [smith.GetInputPort("table_motion"), delay.get_input_port(0)],
            "commanded_state": [smith.GetInputPort("commanded_state")],
        },
        smith.GetOutputPort("compensated_force"),
    )
    diagram = builder.Build()
    diagram.set_name("smith")
    return diagram


def make_smith_online(
    params, derivative_period_s: float, identifier: IdentifierParams | None = None
) -> Diagram:
    """The ``smith-online`` compensator (registry factory): the Smith
    predictor whose contact model ``[k, c]`` comes from the online identifier
    (:mod:`hybridtable.compensators.identification`), started at the compensator's prior.

    One delay line, built like the force sensor, feeds both the predictor's
    delayed model and the identifier (the motion paired with each force
    sample). Extra output ``contact_parameters``: the estimate.
    """
    from hybridtable.compensators.online import online_identifier_params

    if derivative_period_s is None:
        raise ParameterError("smith-online needs a discrete period (derivative_period_s)")
    identifier = identifier or online_identifier_params(params)
    builder = DiagramBuilder()
    delay = builder.AddNamedSystem("motion_delay", sensor_like_delay(params, 3))
    ident = builder.AddNamedSystem(
        "identifier", ContactIdentifier(identifier, derivative_period_s, None)
    )
    smith = builder.AddNamedSystem("smith", SmithPredictor(smith_params(params), True))
    builder.Connect(delay.get_output_port(0), smith.GetInputPort("delayed_table_motion"))
    builder.Connect(delay.get_output_port(0), ident.GetInputPort("table_motion"))
    builder.Connect(
        ident.GetOutputPort("contact_parameters"), smith.GetInputPort("contact_parameters")
    )
    export_compensator_ports(
        builder,
        {
            "measured_force": [
                smith.GetInputPort("measured_force"),
                ident.GetInputPort("measured_force"),
            ],
            "measured_force_rate": [smith.GetInputPort("measured_force_rate")],
            "table_motion": [smith.GetInputPort("table_motion"), delay.get_input_port(0)],
            "commanded_state": [smith.GetInputPort("commanded_state")],
        },
        smith.GetOutputPort("compensated_force"),
        {"contact_parameters": ident.GetOutputPort("contact_parameters")},
    )
    diagram = builder.Build()
    diagram.set_name("smith_online")
    return diagram
