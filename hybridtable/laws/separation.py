"""Run until separated: when a run through one contact ends, or diverged.

Every runner of a contact (the 1-D Drake diagram, the fast exact-discrete
engine, the 6-DoF docking loop) advances in chunks of simulated time and asks
one :class:`SeparationRule` at the end of each chunk:

- the step budget: more than :data:`MAX_INTEGRATOR_STEPS` integrator steps
  (or rig-computer ticks) stops the run ("too stiff to simulate"), so nothing
  runs forever;
- divergence: a non-finite signal, or a force above ``force_limit_n`` (a
  hundred times the undamped peak force ``v sqrt(k m)``: the energy of the
  contact grown ten-thousandfold);
- the contact has started once a force acted (or the record shows a touch);
  it has ended once no force has acted for the settling window ``settle_s``;
- the run ends at ``t_max_s`` at the latest; :meth:`SeparationRule.verdict`
  then says why no separation was seen.

The steps are counted, not timed: the same run is refused or accepted on
every machine.
"""

from __future__ import annotations

import math

from hybridtable.errors import DivergenceError, SimulationError

__all__ = [
    "DIVERGED_FORCE_RATIO",
    "MAX_INTEGRATOR_STEPS",
    "SeparationRule",
    "check_steps_taken",
]

#: A force above this many times the undamped peak force ``v sqrt(k m)`` means
#: the loop diverged.
DIVERGED_FORCE_RATIO = 100.0

#: Most integrator steps one simulation may take (about one to three minutes
#: of a Drake loop with Python systems at 1e4-4e4 steps per second).
MAX_INTEGRATOR_STEPS = 3_000_000


def check_steps_taken(steps: int, t_s: float, budget: float | None = None) -> None:
    """Stop a running simulation whose integrator has taken more than ``budget``
    steps (default :data:`MAX_INTEGRATOR_STEPS`) by simulated time ``t_s``.

    Raises
    ------
    SimulationError
        "too stiff to simulate", with the steps taken and the mean step.
    """
    budget = MAX_INTEGRATOR_STEPS if budget is None else budget
    if steps > budget:
        raise SimulationError(
            f"too stiff to simulate: the integrator took {steps:.3g} steps by t = {t_s:.4g} s "
            f"(mean step {t_s / steps:.2g} s; budget {budget:.2g} steps)"
        )


class SeparationRule:
    """The stop rule of a run through one contact, checked at chunk ends.

    Parameters
    ----------
    t_max_s : float
        The run's end at the latest [s].
    settle_s : float
        How long no force may act before the contact counts as ended [s].
    check_interval_s : float
        Simulated time between two checks [s].
    peak_force_n : float
        The undamped peak force ``v sqrt(k m)`` [N]; the divergence limit is
        :data:`DIVERGED_FORCE_RATIO` times it.
    force_deadband_n : float
        The compensator's dead band [N] (named when a run did not end).
    stop_at_separation : bool
        False: run to ``t_max_s`` (e.g. the length of a record); the rule
        then stops only on divergence, the budget or ``t_max_s``.
    end_tolerance_s : float
        The run has reached ``t_max_s`` within this much [s] (half a tick of
        a discrete loop, so that rounding in the chunks' sum adds no tick).
    """

    def __init__(
        self,
        t_max_s: float,
        settle_s: float,
        check_interval_s: float,
        peak_force_n: float,
        force_deadband_n: float = 0.0,
        stop_at_separation: bool = True,
        end_tolerance_s: float = 0.0,
    ) -> None:
        self.t_max = t_max_s
        self.t_end = t_max_s - end_tolerance_s
        self.settle = settle_s
        self.chunk = check_interval_s
        self.peak = peak_force_n
        self.limit = DIVERGED_FORCE_RATIO * peak_force_n
        self.deadband = force_deadband_n
        self.stop_at_separation = stop_at_separation
        self.t = 0.0
        self.started = self.separated = False
        self.last_active = -math.inf
        self.last_forces: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def next_check_s(self) -> float:
        """The simulated time of the next check [s]."""
        return min(self.t + self.chunk, self.t_max)

    def check(
        self,
        steps: int,
        force_n: float,
        active: bool,
        touched: bool = False,
        finite: bool = True,
        active_at_s: float | None = None,
        forces_n: tuple[float, float, float] | None = None,
    ) -> bool:
        """Judge the run at :attr:`next_check_s`; True when it ends there.

        Parameters
        ----------
        steps : int
            Integrator steps (or ticks) taken so far.
        force_n : float
            The force compared with the divergence limit [N].
        active : bool
            A force acts now.
        touched : bool
            The record shows a touch already (the contact started between checks).
        finite : bool
            Every signal is finite.
        active_at_s : float, optional
            When a force last acted, where the runner knows it better than
            "now" (its record) [s].
        forces_n : tuple, optional
            ``(f_act, f_mea, f_comp)`` now, named when the contact did not end.

        Raises
        ------
        DivergenceError
        SimulationError
            Over the step budget.
        """
        t = self.t = self.next_check_s
        check_steps_taken(steps, t)
        if forces_n is not None:
            self.last_forces = forces_n
        if not finite or not (force_n <= self.limit):
            raise DivergenceError(
                f"simulation diverged by t = {t:.4f} s: the force passed "
                f"{DIVERGED_FORCE_RATIO:g} times the undamped peak force v sqrt(k m) = "
                f"{self.peak:.3g} N (the loop is unstable for these parameters)"
            )
        if active or (not self.started and touched):
            self.started, self.last_active = True, t if active_at_s is None else active_at_s
            return t >= self.t_end
        if active_at_s is not None:  # a force acted between the checks
            self.last_active = max(self.last_active, active_at_s)
        if self.started and self.stop_at_separation and t - self.last_active > self.settle:
            self.separated = True
            return True
        return t >= self.t_end

    def verdict(self) -> None:
        """Raise the error of a run that found no contact, or whose contact did
        not end by ``t_max_s``."""
        if not self.started:
            raise SimulationError(f"no contact within t_max = {self.t_max:.3f} s")
        if self.separated or not self.stop_at_separation:
            return
        f_act, f_mea, f_comp = self.last_forces
        if f_comp == 0.0 and f_act > 0.0 and f_mea <= self.deadband:
            raise SimulationError(
                f"the contact did not end within t_max = {self.t_max:.3f} s: the compensated "
                f"force is 0 while the contact pushes {f_act:.3g} N (every reading at or below "
                f"force_deadband_n = {self.deadband:g} N), so the model never slows"
            )
        if f_act == 0.0 and f_comp > 0.0 and f_mea > self.deadband:
            raise SimulationError(
                f"the contact did not end within t_max = {self.t_max:.3f} s: the devices are "
                f"apart, but the readings ({f_mea:.3g} N at the end) stay above force_deadband_n "
                f"= {self.deadband:g} N, so the compensated force never stops (the sensor's "
                "noise or bias above the dead band: raise it, or give the run a duration_s)"
            )
        raise SimulationError(
            f"the contact did not end within t_max = {self.t_max:.3f} s (spacecraft captured "
            "or loop unstable)"
        )
