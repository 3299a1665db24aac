"""``polynomial``: Horiuchi-style polynomial extrapolation over the loop delay.

Horiuchi et al. (1999) compensate an actuator delay ``tau`` in real-time hybrid
testing by sending the actuator the command extrapolated ``tau`` ahead with a
polynomial through the last ``n + 1`` computed commands. In this loop the
compensator cannot change the table's command (it only returns a force), so
the same extrapolation is applied on the other side of the loop: the measured
force, which lags the model's command by the whole loop delay, is extrapolated
ahead by that delay,

    f_comp(t_k) = sum_{i=0..n} a_i f_mea(t_k - i Delta),

with the Lagrange weights ``a_i`` of the degree-``n`` polynomial through the
samples spaced ``Delta`` apart, evaluated ``horizon_s`` ahead. For a linear
contact and a table that acts as a pure delay ``tau`` this equals Horiuchi's
command extrapolation (``f_mea(t) = k p_des(t - tau)``); it needs no contact
stiffness. The default horizon is the loop's effective delay
``T_fms + 2 zeta / omega_resp``. The paper's SDC is the case ``n = 1``,
``Delta = h``, horizon ``T_lead``.

Gating and clamping follow :class:`hybridtable.compensators.paper.Compensator`
(``f_comp = 0`` while ``f_mea <= force_deadband_n``).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, LeafSystem_
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_choice, check_nonnegative, check_positive
from hybridtable.compensators.paper import CONTACT_GATES
from hybridtable.errors import ParameterError
from hybridtable.laws.compensation import CompensationLaw, compensate

__all__ = [
    "PolynomialParams",
    "PolynomialExtrapolator",
    "PolynomialExtrapolator_",
    "extrapolation_weights",
    "polynomial_params",
    "make_polynomial",
]


def extrapolation_weights(order: int, horizon: float) -> np.ndarray:
    """Lagrange weights ``a_i``, ``i = 0..order``, of the polynomial through
    samples at ``0, -1, ..., -order`` evaluated at ``horizon`` (all in units of
    the sample spacing): ``p(horizon) = sum a_i y(-i)``.

    Exact for every polynomial of degree <= ``order``; ``sum a_i = 1``.
    """
    if order < 0:
        raise ParameterError(f"order must be >= 0 (got {order})")
    nodes = -np.arange(order + 1, dtype=float)
    weights = np.ones(order + 1)
    for i in range(order + 1):
        for j in range(order + 1):
            if j != i:
                weights[i] *= (horizon - nodes[j]) / (nodes[i] - nodes[j])
    return weights


@dataclass(frozen=True)
class PolynomialParams:
    """Parameters of the polynomial extrapolator, SI units.

    Parameters
    ----------
    horizon_s : float
        How far ahead the force is extrapolated, >= 0.
    order : int
        Polynomial degree n >= 1 (1: linear, 2: quadratic, ...).
    spacing_s : float or None
        Time between the samples used, > 0, rounded to a whole number of
        computer periods (at least one). ``None``: ``horizon_s / order``.
    force_deadband_n : float
        Measured forces at or below this are "no contact": f_comp = 0.
    clamp_nonnegative : bool
        Clamp f_comp at zero.
    contact_gate : {"measured_force", "table_position"}
        ``"table_position"``: no gating (the extrapolated force always passes,
        as the SDC part of :class:`~hybridtable.compensators.paper.Compensator`).
    """

    horizon_s: float
    order: int = 2
    spacing_s: float | None = None
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False
    contact_gate: str = "measured_force"

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "horizon_s", check_nonnegative("horizon_s", self.horizon_s))
        if int(self.order) != self.order or self.order < 1:
            raise ParameterError(f"order must be an integer >= 1 (got {self.order!r})")
        s(self, "order", int(self.order))
        if self.spacing_s is not None:
            s(self, "spacing_s", check_positive("spacing_s", self.spacing_s))
        s(self, "force_deadband_n", check_nonnegative("force_deadband_n", self.force_deadband_n))
        check_choice("contact_gate", self.contact_gate, CONTACT_GATES)

    def spacing_ticks(self, period_s: float) -> int:
        """Sample spacing in computer periods (>= 1)."""
        spacing = self.spacing_s if self.spacing_s is not None else self.horizon_s / self.order
        return max(1, int(round(spacing / period_s)))

    def weights(self, period_s: float) -> np.ndarray:
        """Extrapolation weights for the computer period ``period_s``."""
        return extrapolation_weights(
            self.order, self.horizon_s / (self.spacing_ticks(period_s) * period_s)
        )


@TemplateSystem.define(
    "PolynomialExtrapolator_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__]
)
def PolynomialExtrapolator_(T):
    class Impl(LeafSystem_[T]):
        """Polynomial extrapolation of the measured force.

        Ports: those of :class:`hybridtable.compensators.paper.Compensator`
        (``measured_force_rate`` and ``commanded_state`` are not used;
        ``table_motion`` only by the ``"table_position"`` gate).

        Discrete state: the last ``order * s`` measured forces
        ``f_mea[k-1], ..., f_mea[k - order s]`` (``s`` the spacing in ticks),
        shifted every ``period_s``; zero before the start.
        """

        def _construct(self, params: PolynomialParams, period_s: float, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.period_s = check_positive("period_s", period_s)
            self._s = params.spacing_ticks(period_s)
            self._w = params.weights(period_s)
            self._n = params.order * self._s
            self._law = CompensationLaw(
                force_deadband_n=params.force_deadband_n,
                gate=params.contact_gate,
                clamp_nonnegative=params.clamp_nonnegative,
            )
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self.DeclareVectorInputPort("measured_force_rate", 1)
            self._table = self.DeclareVectorInputPort("table_motion", 3)
            self.DeclareVectorInputPort("commanded_state", 2)
            self.DeclareDiscreteState(self._n)
            self.DeclarePeriodicDiscreteUpdateEvent(self.period_s, 0.0, self._shift)
            self.DeclareVectorOutputPort("compensated_force", BasicVector_[T](1), self._calc)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.period_s, converter=converter)

        def _shift(self, context, discrete_state):
            past = context.get_discrete_state(0).value()
            new = np.concatenate([[self._f.Eval(context)[0]], past[:-1]])
            discrete_state.get_mutable_vector(0).SetFromVector(new)

        def _calc(self, context, output):
            f_mea = self._f.Eval(context)[0]
            past = context.get_discrete_state(0).value()
            f = self._w[0] * f_mea
            for i in range(1, self.params.order + 1):
                f = f + self._w[i] * past[i * self._s - 1]
            # The extrapolated force through the compensation law's gate and clamp.
            output.SetAtIndex(0, compensate(self._law, f, gate_force=f_mea))

    return Impl


PolynomialExtrapolator = PolynomialExtrapolator_[None]


def polynomial_params(params, **overrides) -> PolynomialParams:
    """Settings for a loop (a :class:`~hybridtable.loop.params.HybridLoopParams`):
    horizon ``lead_time_s`` if set, else the effective delay
    ``T_fms + 2 zeta / omega_resp``; order 2; spacing ``horizon / order``."""
    horizon = params.lead_time_s if params.lead_time_s is not None else params.effective_delay_s
    if not math.isfinite(horizon):
        raise ParameterError("polynomial: the loop delay is not finite")
    fields = {
        "horizon_s": horizon,
        "force_deadband_n": params.force_deadband_n,
        "clamp_nonnegative": params.clamp_nonnegative,
        "contact_gate": params.contact_gate,
    }
    fields.update(overrides)
    return PolynomialParams(**fields)


def make_polynomial(params, derivative_period_s: float) -> PolynomialExtrapolator:
    """The ``polynomial`` compensator for a loop (registry factory)."""
    if derivative_period_s is None:
        raise ParameterError("polynomial needs a discrete period (derivative_period_s)")
    return PolynomialExtrapolator(polynomial_params(params), derivative_period_s)
