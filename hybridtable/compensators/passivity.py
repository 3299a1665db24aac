"""Time-domain passivity observer and controller (Hannaford and Ryu, 2002)
guarding any compensator.

Seen from the spacecraft model, everything else in the hybrid loop (table,
contact, sensor, compensator) is a one-port that takes the model's velocity
``v_des`` and returns the force ``f`` (compression positive; the model is pushed
by ``-f``). A real contact is passive: the energy it has absorbed,

    E(t) = integral of f v_des dt,

never becomes negative. Delays break this and the loop creates energy (CoR > 1).
The guard sits between the compensator and the spacecraft:

- the **passivity observer** (PO) integrates ``E``: exactly, as a continuous
  state, in the continuous loop; in the sampled loop with the energy the
  model's semi-implicit Euler step really receives from a held force,
  ``f_k h (v_k + v_{k+1}) / 2``;
- the **passivity controller** (PC) adds a variable damper,
  ``f = f_comp + alpha v_des`` with ``alpha >= 0``, just large enough that ``E``
  stays non-negative: in the sampled loop ``alpha`` makes the energy predicted
  after the tick zero; in the continuous loop it keeps ``dE/dt >= -E / tau``
  (``tau`` the computer period), so ``E`` cannot cross zero.
  ``alpha <= mass / h`` (the damper never reverses the model's velocity).

The guard dissipates only energy the loop created, so with any compensator the
CoR of an undamped contact ends at or below about 1; it does not make the
force profile right (the damper acts in bursts, typically at the end of the
contact). Energy dissipated earlier (``E > 0``) is credit that later contacts
may spend, as in every PO/PC scheme.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import (
    BasicVector_,
    Diagram,
    DiagramBuilder,
    LeafSystem_,
    System,
)
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative, check_positive

__all__ = [
    "DEFAULT_ENERGY_TOLERANCE",
    "PassivityParams",
    "PassivityGuard",
    "PassivityGuard_",
    "passivity_guarded",
]


@dataclass(frozen=True)
class PassivityParams:
    """Parameters of the passivity guard, SI units.

    Parameters
    ----------
    period_s : float
        Period of the rig computer, > 0: the sampled loop's tick, or the
        continuous loop's time constant ``tau`` of the PC.
    mass_kg : float
        Mass of the spacecraft model, > 0: caps the damper at ``mass / period``.
    sampled : bool
        True for the sampled loop (force held over each tick).
    energy_tolerance : float
        Energy the loop may create, as a fraction of the largest energy the
        loop has absorbed so far, >= 0: the PC keeps
        ``E >= -energy_tolerance * max E``, which bounds the CoR of a contact
        by ``sqrt(1 + energy_tolerance)``. 0 is the strict PO/PC.
    velocity_threshold_m_per_s : float
        Below this model speed the PC does not act (no damper can dissipate
        without motion), >= 0.
    """

    period_s: float
    mass_kg: float
    sampled: bool = False
    energy_tolerance: float = 0.0
    velocity_threshold_m_per_s: float = 1e-9

    def __post_init__(self) -> None:
        object.__setattr__(self, "period_s", check_positive("period_s", self.period_s))
        object.__setattr__(self, "mass_kg", check_positive("mass_kg", self.mass_kg))
        for name in ("energy_tolerance", "velocity_threshold_m_per_s"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))

    @property
    def max_damping_n_s_per_m(self) -> float:
        """Largest damper gain, ``mass / period``."""
        return self.mass_kg / self.period_s


#: Energy tolerance of the guard that ``HybridLoopParams.passivity`` adds.
DEFAULT_ENERGY_TOLERANCE = 0.0

#: The PC aims at this fraction of the model's kinetic energy above zero, so
#: that rounding never leaves the observed energy negative (and the damper
#: stops acting in a finite time once the energy is restored).
ENERGY_MARGIN = 1e-9


def _damping(energy, f0, v, params: PassivityParams):
    """Damper gain alpha in [0, mass / h] that keeps the observed energy
    non-negative.

    ``energy`` is the observed energy now above its floor (the tolerance), ``f0`` the compensator's force and
    ``v`` the model's velocity. Sampled: the energy after the tick,
    ``E + h f v - h^2 f^2 / (2 m)`` with ``f = f0 + alpha v`` (exact for the
    model's semi-implicit Euler step), must not be negative (when it would
    be, the damper restores it to the margin).
    Continuous: ``dE/dt = f v >= -E / tau`` while ``E >= 0``, and
    ``>= (margin - E) / tau`` once ``E < 0``.
    """
    if not (v * v > params.velocity_threshold_m_per_s**2):
        return 0.0 * v
    h, m = params.period_s, params.mass_kg
    margin = ENERGY_MARGIN * 0.5 * m * v * v
    if params.sampled:
        if energy + h * f0 * v - h * h * f0 * f0 / (2.0 * m) >= 0.0:
            return 0.0 * v
        disc = v * v + 2.0 * (energy - margin) / m
        # The smaller-force root of E + h v f - h^2 f^2 / 2m = margin; none if
        # even stopping the model in this tick cannot restore the energy.
        root = m / h * v if disc < 0.0 else m / h * (v - _sign(v) * disc**0.5)
        alpha = (root - f0) / v
    else:
        demand = (margin - energy) / h if energy < 0.0 else -energy / h
        alpha = (demand - f0 * v) / (v * v)
    if not alpha > 0.0:
        return 0.0 * alpha
    if alpha > params.max_damping_n_s_per_m:
        return params.max_damping_n_s_per_m + 0.0 * alpha
    return alpha


def _sign(x) -> float:
    return 1.0 if x >= 0.0 else -1.0


@TemplateSystem.define("PassivityGuard_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__])
def PassivityGuard_(T):
    class Impl(LeafSystem_[T]):
        """Passivity observer and controller between a compensator and the
        spacecraft model.

        Ports
        -----
        Input ``force`` (size 1, N)
            The compensator's force f_comp.
        Input ``commanded_state`` (size 2: m, m/s)
            ``[p_des, v_des]`` of the spacecraft model.
        Output ``compensated_force`` (size 1, N)
            ``f_comp + alpha v_des``, fed to the spacecraft.
        Output ``observed_energy`` (size 1, J)
            Energy the loop has absorbed so far (PO), >= 0 for a passive loop.

        State: continuous ``[E]`` and discrete ``[max E]``; sampled: discrete
        ``[E, f_prev, v_prev, max E]`` (the energy through the previous tick,
        and that tick's force and velocity, completed at the next tick when
        ``v_{k+1}`` is known). ``max E`` is sampled every period.
        """

        def _construct(self, params: PassivityParams, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self._f = self.DeclareVectorInputPort("force", 1)
            self._x = self.DeclareVectorInputPort("commanded_state", 2)
            if params.sampled:
                self.DeclareDiscreteState(4)
            else:
                self.DeclareContinuousState(1)
                self.DeclareDiscreteState(1)
            self.DeclarePeriodicDiscreteUpdateEvent(params.period_s, 0.0, self._update)
            self.DeclareVectorOutputPort("compensated_force", BasicVector_[T](1), self._calc)
            self.DeclareVectorOutputPort("observed_energy", BasicVector_[T](1), self._calc_energy)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, converter=converter)

        def _energy_now(self, context, v):
            if self.params.sampled:
                e, f_prev, v_prev, _ = context.get_discrete_state(0).value()
                return e + f_prev * self.params.period_s * 0.5 * (v_prev + v)
            return context.get_continuous_state_vector().GetAtIndex(0)

        def _max_energy(self, context):
            return context.get_discrete_state(0).GetAtIndex(3 if self.params.sampled else 0)

        def _force(self, context):
            f0 = self._f.Eval(context)[0]
            v = self._x.Eval(context)[1]
            energy = self._energy_now(context, v)
            floor = -self.params.energy_tolerance * self._max_energy(context)
            return f0 + _damping(energy - floor, f0, v, self.params) * v, v, energy

        def _calc(self, context, output):
            output.SetAtIndex(0, self._force(context)[0])

        def _calc_energy(self, context, output):
            output.SetAtIndex(0, self._energy_now(context, self._x.Eval(context)[1]))

        def _update(self, context, discrete_state):
            f, v, energy = self._force(context)
            vec = discrete_state.get_mutable_vector(0)
            peak = self._max_energy(context)
            if energy > peak:
                peak = energy
            if self.params.sampled:
                vec.SetFromVector([energy, f, v, peak])
            else:
                vec.SetAtIndex(0, peak)

        def DoCalcTimeDerivatives(self, context, derivatives):
            if self.params.sampled:
                return
            f, v, _ = self._force(context)
            derivatives.get_mutable_vector().SetAtIndex(0, f * v)

    return Impl


PassivityGuard = PassivityGuard_[None]


def passivity_guarded(
    compensator: System,
    params,
    derivative_period_s: float | None = None,
    energy_tolerance: float | None = None,
) -> Diagram:
    """``compensator`` followed by a :class:`PassivityGuard`, as one system
    with the compensator's ports (and the extra output ``observed_energy``).

    Parameters
    ----------
    compensator : System
        Any system with the ports of :class:`hybridtable.compensators.paper.Compensator`.
    params : HybridLoopParams
        The loop (mass, sampled or continuous).
    derivative_period_s : float, optional
        The rig computer's period (default: the sample period, or
        ``params.step_s`` in the continuous loop).
    energy_tolerance : float, optional
        See :class:`PassivityParams` (default :data:`DEFAULT_ENERGY_TOLERANCE`).
    """
    if energy_tolerance is None:
        energy_tolerance = DEFAULT_ENERGY_TOLERANCE
    period = derivative_period_s or params.sample_period_s or params.step_s
    guard_params = PassivityParams(
        period_s=period,
        mass_kg=params.spacecraft_mass_kg,
        sampled=params.sample_period_s is not None,
        energy_tolerance=energy_tolerance,
    )
    builder = DiagramBuilder()
    inner = builder.AddNamedSystem("inner_compensator", compensator)
    guard = builder.AddNamedSystem("passivity_guard", PassivityGuard(guard_params))
    builder.Connect(inner.GetOutputPort("compensated_force"), guard.GetInputPort("force"))
    for name in ("measured_force", "measured_force_rate", "table_motion"):
        builder.ExportInput(inner.GetInputPort(name), name)
    index = builder.ExportInput(inner.GetInputPort("commanded_state"), "commanded_state")
    builder.ConnectInput(index, guard.GetInputPort("commanded_state"))
    builder.ExportOutput(guard.GetOutputPort("compensated_force"), "compensated_force")
    builder.ExportOutput(guard.GetOutputPort("observed_energy"), "observed_energy")
    diagram = builder.Build()
    diagram.set_name(f"passivity_guarded_{compensator.get_name() or 'compensator'}")
    return diagram
