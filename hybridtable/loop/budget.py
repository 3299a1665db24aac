"""The simulation budget: refuse a run that would be too long or too stiff to simulate.

Every parameter has a plausible range (:mod:`hybridtable.limits`), but values
inside their ranges can still combine into a run no one can wait for: a slow
approach over a long gap (10 m at 0.1 mm/s is a day of simulated time), or a
table or contact so fast that an explicit integrator needs microsecond steps.
Before a simulation starts, :func:`estimate_cost` predicts its integrator
steps from the simulated duration and the step the dynamics allow, and
:func:`check_budget` refuses a run above :data:`MAX_INTEGRATOR_STEPS` with a
:class:`~hybridtable.errors.SimulationError` that says which, why and what to
change. While it runs, :func:`~hybridtable.laws.separation.check_steps_taken`
(the separation rule's budget) stops a run whose real step
count passes the budget anyway (dynamics the estimate cannot see, e.g. a
plug-in effect), so nothing runs forever.

The steps are counted, not timed: the same run is refused or accepted on
every machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from hybridtable.errors import SimulationError
from hybridtable.laws.contact import critical_damping_n_s_per_m
from hybridtable.laws.separation import MAX_INTEGRATOR_STEPS, check_steps_taken
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "MAX_INTEGRATOR_STEPS",
    "STABLE_STEP_RAD",
    "SAMPLED_MEAN_STEP_S",
    "SimulationCost",
    "fastest_pole_rad_per_s",
    "estimate_cost",
    "check_budget",
    "check_steps_taken",
]

#: Mean step of the error-controlled integrator in a sampled loop whose table
#: is integrated [s]: the held command jumps at every tick and the step starts
#: small again (measured at the Table 1 point: 2.2e4 steps per simulated
#: second at 1 kHz, 2.7e4 at 10 kHz).
SAMPLED_MEAN_STEP_S = 5e-5

#: What a tick of a sampled rig computer costs on top of the integrator's
#: steps, in integrator steps: its discrete update (the compensator, the delay
#: line) and the restart of the step after it (measured at the Table 1 point,
#: SDMDC: 10 us a counted step at 1 kHz, 46 us a tick at 100 kHz).
SAMPLED_TICK_STEPS = 4.0

#: |lambda h| at which an explicit Runge-Kutta step stays stable on a real
#: pole (about 2.5 for RK3; the error control keeps it below).
STABLE_STEP_RAD = 2.5


@dataclass(frozen=True)
class SimulationCost:
    """A simulation's predicted size.

    Attributes
    ----------
    duration_s : float
        Simulated time [s].
    step_s : float
        The integrator step the dynamics allow [s].
    steps : float
        ``duration_s / step_s``: predicted integrator steps, and in a
        sampled loop :data:`SAMPLED_TICK_STEPS` for each of its ticks.
    limited_by : str
        What sets ``step_s``, in words.
    stiff : bool
        True when ``step_s`` is set by a fast pole (the dynamics), not by
        the computer's period or the chosen step.
    """

    duration_s: float
    step_s: float
    steps: float
    limited_by: str
    stiff: bool


def _pole(omega: float, zeta: float) -> float:
    """Magnitude of the fastest pole of ``s^2 + 2 zeta omega s + omega^2`` [rad/s]."""
    if zeta <= 1.0:
        return omega
    return omega * (zeta + math.sqrt(zeta * zeta - 1.0))


def fastest_pole_rad_per_s(params: HybridLoopParams) -> tuple[float, str]:
    """The fastest pole of the continuous dynamics an integrator must resolve,
    and its source in words.

    The table's (second order) always; the contact's (the spacecraft mass on
    the contact spring and damper) only in a continuous loop, where the
    spacecraft model is integrated (a sampled rig computer steps it itself).
    """
    poles: list[tuple[float, str]] = [(0.0, "")]
    table = params.plant.table
    if not table.is_ideal:
        poles.append(
            (
                _pole(table.omega_rad_per_s, table.damping_ratio),
                f"the table's fastest pole (table_response_hz {params.table_response_hz:g} Hz, "
                f"table_damping_ratio {params.table_damping_ratio:g})",
            )
        )
    if params.sample_rate_hz is None:
        k, m = params.contact_stiffness_n_per_m, params.spacecraft_mass_kg
        omega = math.sqrt(k / m)
        zeta = params.contact_damping_n_s_per_m / critical_damping_n_s_per_m(k, m)
        poles.append(
            (
                _pole(omega, zeta),
                f"the contact's fastest pole (contact frequency "
                f"{params.contact_frequency_hz:.3g} Hz)",
            )
        )
    return max(poles)


def estimate_cost(
    params: HybridLoopParams, duration_s: float, max_step_s: float, integrated: bool = True
) -> SimulationCost:
    """The predicted size of simulating ``params`` for ``duration_s``.

    Parameters
    ----------
    params : HybridLoopParams
        The loop.
    duration_s : float
        Simulated time [s].
    max_step_s : float
        The integrator's largest step [s] (the computer's period, or the
        continuous loop's step).
    integrated : bool
        False when no continuous state is integrated (a sampled table,
        discretized exactly): one step per ``max_step_s`` whatever the poles.
        True in a sampled loop counts steps of at most :data:`SAMPLED_MEAN_STEP_S`.
    """
    pole, source = fastest_pole_rad_per_s(params) if integrated else (0.0, "")
    stable_step = STABLE_STEP_RAD / pole if pole > 0.0 else math.inf
    if params.sample_rate_hz is not None:
        limit = "the rig computer's period (sample_rate_hz)"
        if integrated and SAMPLED_MEAN_STEP_S < max_step_s:
            max_step_s = SAMPLED_MEAN_STEP_S
            limit = "the mean error-controlled step of a sampled loop"
    else:
        limit = "the continuous loop's step (time_step_s)"
    if stable_step < max_step_s:
        step, limit, stiff = stable_step, source, True
    else:
        step, stiff = max_step_s, False
    steps = duration_s / step
    if params.sample_rate_hz is not None:
        steps += SAMPLED_TICK_STEPS * duration_s * params.sample_rate_hz
    return SimulationCost(duration_s, step, steps, limit, stiff)


def check_budget(
    params: HybridLoopParams,
    duration_s: float,
    max_step_s: float,
    budget: float | None = None,
    what: str = "the run",
    integrated: bool = True,
) -> SimulationCost:
    """:func:`estimate_cost`, refusing a run above ``budget`` steps (default
    :data:`MAX_INTEGRATOR_STEPS`; ``what`` names the run in the message).

    Raises
    ------
    SimulationError
        "too stiff to simulate" (a fast pole forces tiny steps) or "too long
        to simulate" (the simulated time itself), in one line with the
        figures and what to change.
    """
    budget = MAX_INTEGRATOR_STEPS if budget is None else budget
    cost = estimate_cost(params, duration_s, max_step_s, integrated)
    if not (math.isfinite(cost.steps) and cost.steps <= budget):
        if cost.stiff:
            raise SimulationError(
                f"too stiff to simulate: {cost.limited_by} needs integrator steps of "
                f"{cost.step_s:.2g} s, {cost.steps:.2g} steps for {what}'s "
                f"{cost.duration_s:.3g} s (budget {budget:.2g} steps); use a slower or "
                "less damped table, or a softer contact"
            )
        rate = params.sample_rate_hz
        ticks, slower = (
            ("", "")
            if rate is None
            else (
                f", each of its {rate:.4g} Hz ticks counting {SAMPLED_TICK_STEPS:g}",
                " or a slower rig computer",
            )
        )
        raise SimulationError(
            f"too long to simulate: {what} lasts {cost.duration_s:.3g} s of simulated time, "
            f"{cost.steps:.2g} integrator steps of {cost.step_s:.2g} s at "
            f"{cost.limited_by}{ticks} (budget {budget:.2g} steps); shorten the approach "
            "(initial_gap_m / initial_velocity_m_per_s) or the record, or use a longer step"
            f"{slower}"
        )
    return cost
