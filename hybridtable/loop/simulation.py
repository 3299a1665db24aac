"""Run the hybrid loop through one contact and collect the logged signals."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.analysis import Simulator

from hybridtable._components import eval_output
from hybridtable._plugins import simulation_failure
from hybridtable.errors import SimulationError
from hybridtable.laws.separation import DIVERGED_FORCE_RATIO, SeparationRule
from hybridtable.loop.budget import check_budget
from hybridtable.loop.builder import LOG_ROWS, HybridLoop, build_hybrid_loop
from hybridtable.loop.metrics import ContactMetrics, contact_metrics
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "separation_rule",
    "DIVERGED_FORCE_RATIO",
    "SimulationError",
    "SimulationResult",
    "simulate",
    "run_loop",
    "collect_result",
    "result_from_rows",
    "FIXED_STEP_INTEGRATORS",
    "default_t_max_s",
    "expected_duration_s",
    "settle_window_s",
    "check_interval_s",
    "undamped_peak_force_n",
]

#: Drake integrators stepped at a fixed step (the computer's period), not to an
#: accuracy: the others aim at the exact solution.
FIXED_STEP_INTEGRATORS: tuple[str, ...] = ("runge_kutta2", "explicit_euler", "semi_explicit_euler")

_F_ACT = LOG_ROWS.index("f_act_n")


@dataclass
class SimulationResult:
    """Logged signals of a run (SI units) and its contact metrics.

    In a sampled loop row ``k`` holds what the rig computer read at tick ``k``
    (``p_act``, ``f_mea``), the force it computed (``f_comp``) and the
    spacecraft state after the tick's update (``p_des``, ``v_des``), as in the
    ``hybridtable-run/1`` format.
    """

    params: HybridLoopParams
    time_s: np.ndarray
    p_des_m: np.ndarray
    v_des_m_per_s: np.ndarray
    p_act_m: np.ndarray
    v_act_m_per_s: np.ndarray
    f_act_n: np.ndarray
    f_mea_n: np.ndarray
    f_comp_n: np.ndarray
    metrics: ContactMetrics
    steps: int

    def signals(self) -> dict[str, np.ndarray]:
        """The time series by column name."""
        names = ("time_s", "p_des_m", "v_des_m_per_s", "p_act_m", "v_act_m_per_s")
        names += ("f_act_n", "f_mea_n", "f_comp_n")
        return {n: getattr(self, n) for n in names}


def _approach_s(params: HybridLoopParams) -> float:
    lag = params.plant.table.ramp_lag_s
    return (params.initial_gap_m + lag * params.initial_velocity_m_per_s) / (
        params.initial_velocity_m_per_s
    )


def default_t_max_s(params: HybridLoopParams) -> float:
    """The longest a run through one contact may last: the approach, ten contact
    periods, twenty effective delays and a second."""
    tail = 20.0 * params.effective_delay_s + 1.0
    return _approach_s(params) + 10.0 / params.contact_frequency_hz + tail


def expected_duration_s(params: HybridLoopParams) -> float:
    """How long a run through one contact lasts when it separates: the approach,
    two contact periods (the contact itself lasts about half of one), twenty
    effective delays and a second."""
    tail = 20.0 * params.effective_delay_s + 1.0
    return _approach_s(params) + 2.0 / params.contact_frequency_hz + tail


def settle_window_s(params: HybridLoopParams, computer_period_s: float) -> float:
    """How long no force may act before a run counts as separated [s]: the sensor
    delay, five computer periods and, for a real table, five time constants of
    its decay, at most 20 of its periods (a lightly damped table rings long
    after the devices have parted)."""
    table = params.plant.table
    settle = params.sensor_delay_s + 5.0 * computer_period_s
    if not table.is_ideal:
        settle += min(
            5.0 / max(table.damping_ratio * table.omega_rad_per_s, 1e-9),
            20.0 / table.response_frequency_hz,
        )
    return settle


def check_interval_s(params: HybridLoopParams, computer_period_s: float) -> float:
    """Simulated time between two looks at the forces (stop rule, divergence) [s]."""
    return max(10.0 * computer_period_s, settle_window_s(params, computer_period_s) / 4.0)


def undamped_peak_force_n(params: HybridLoopParams) -> float:
    """Peak force ``v sqrt(k m)`` of an undamped, undelayed contact [N]."""
    return (
        params.contact_stiffness_n_per_m
        * params.initial_velocity_m_per_s
        / (2 * math.pi * params.contact_frequency_hz)
    )


def run_loop(
    loop: HybridLoop,
    t_max_s: float | None = None,
    integrator: str = "runge_kutta3",
    accuracy: float = 1e-8,
    stop_at_separation: bool = True,
) -> SimulationResult:
    """Simulate a built loop until the spacecraft has separated, and collect.

    The run stops once a contact has happened and no force (actual, measured
    or compensated) has acted for a settling window (the sensor delay, five
    table time constants but at most 20 table periods, and five computer
    periods). With
    ``stop_at_separation=False`` it runs to ``t_max_s`` (e.g. the length of a
    recorded run) and raises only on divergence or when no contact happened.

    Raises
    ------
    SimulationError
        If a signal becomes non-finite or exceeds :data:`DIVERGED_FORCE_RATIO`
        times the undamped peak force (divergence), no separation happens
        before ``t_max_s``, or the run is over the simulation budget
        (:mod:`hybridtable.loop.budget`: too long or too stiff to simulate).
    """
    params = loop.params
    diagram = loop.diagram
    if diagram is None:
        raise ValueError(
            "run_loop: loop.diagram is None: the loop was added to a builder of yours; "
            "set loop.diagram = builder.Build(), or run your own Simulator and read the "
            "run with collect_result(loop, context)"
        )
    t_max = default_t_max_s(params) if t_max_s is None else t_max_s
    # The estimate of a run that stops at separation is its expected length;
    # one that does not separate is stopped by the steps it really takes.
    duration = min(t_max, expected_duration_s(params)) if stop_at_separation else t_max
    check_budget(params, duration, loop.computer_period_s)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    from pydrake.systems.analysis import ResetIntegratorFromFlags

    ResetIntegratorFromFlags(simulator, integrator, loop.computer_period_s)
    integ = simulator.get_mutable_integrator()
    integ.set_maximum_step_size(loop.computer_period_s)
    if integrator in FIXED_STEP_INTEGRATORS:
        integ.set_fixed_step_mode(True)
    else:
        integ.set_target_accuracy(accuracy)

    rule = separation_rule(params, loop.computer_period_s, t_max, stop_at_separation)
    watched = ((loop.contact, "force"), (loop.sensor, "measured_force"))
    watched += ((loop.compensator, "compensated_force"),)

    # Advance in chunks and look at the forces between chunks (a per-step
    # Python monitor would cost as much as the systems themselves). The
    # logger holds every step; a chunk only decides when to stop.
    first = True
    while True:
        try:
            if first:
                simulator.Initialize()
                first = False
            simulator.AdvanceTo(rule.next_check_s)
        except (Exception, SystemExit) as err:  # Drake's asserts (SystemExit), a system's callback
            raise simulation_failure(err) from None
        forces = tuple(eval_output(part, port, context)[0] for part, port in watched)
        f_act, f_mea, f_comp = forces
        if rule.check(
            simulator.get_num_steps_taken(),
            abs(f_comp),
            active=f_act > 0.0 or f_mea > params.force_deadband_n or f_comp != 0.0,
            touched=not rule.started
            and bool((loop.logger.FindLog(context).data()[_F_ACT] > 0.0).any()),
            finite=all(math.isfinite(x) for x in forces),
            forces_n=forces,
        ):
            break
    rule.verdict()
    # The separation rule decided how the run ends (a record of a given length may
    # end mid-contact).
    return collect_result(loop, context, simulator.get_num_steps_taken(), check_ended=False)


def separation_rule(
    params: HybridLoopParams,
    computer_period_s: float,
    t_max_s: float | None = None,
    stop_at_separation: bool = True,
    kind: type[SeparationRule] = SeparationRule,
    **extra,
) -> SeparationRule:
    """The :class:`~hybridtable.laws.separation.SeparationRule` of a 1-D run:
    its ``t_max``, settling window, check interval and undamped peak force
    (``kind``: a subclass, given ``extra`` keywords)."""
    return kind(
        default_t_max_s(params) if t_max_s is None else t_max_s,
        settle_window_s(params, computer_period_s),
        check_interval_s(params, computer_period_s),
        undamped_peak_force_n(params),
        params.force_deadband_n,
        stop_at_separation,
        **extra,
    )


def collect_result(
    loop: HybridLoop, root_context, steps: int = 0, check_ended: bool = True
) -> SimulationResult:
    """The run recorded in ``loop``'s log, as a :class:`SimulationResult`
    (signals by name and the contact metrics): for a loop added to one's own
    diagram (:func:`~hybridtable.loop.builder.add_hybrid_loop`) and simulated
    through its contact with one's own ``Simulator``; ``root_context`` is that
    diagram's, ``steps`` the simulator's step count, if wanted.

    Raises
    ------
    SimulationError
        If the record holds no contact, or (``check_ended``) ends while a
        force still acts: the CoR would be read mid-contact.
    """
    params = loop.params
    log = loop.logger.FindLog(root_context)
    t = log.sample_times()
    data = log.data()
    if params.sample_rate_hz is not None:
        # Logged before each tick's update: the spacecraft state after tick k
        # is the one logged at tick k + 1.
        n = len(t) - 1
        t = t[:n]
        data = np.vstack([data[:2, 1:], data[2:, :n]])
    else:
        # Drop repeated samples at discrete-event times (kept: the last).
        keep = np.append(np.diff(t) > 0, True)
        t, data = t[keep], data[:, keep]
    rows = dict(zip(LOG_ROWS, data, strict=True))
    if check_ended and len(t) and (rows["f_act_n"][-1] > 0.0 or rows["f_comp_n"][-1] != 0.0):
        raise SimulationError(
            f"the record ends at {t[-1]:.3g} s while a force still acts (contact "
            f"{rows['f_act_n'][-1]:.4g} N, compensated {rows['f_comp_n'][-1]:.4g} N): "
            "simulate past the end of the contact"
        )
    return result_from_rows(params, t, rows, steps)


def result_from_rows(
    params: HybridLoopParams, t, rows: dict[str, np.ndarray], steps: int = 0
) -> SimulationResult:
    """A :class:`SimulationResult` of a run's rows (:data:`LOG_ROWS` by name, the
    table's acceleration not needed) at times ``t``, with its contact metrics.

    Raises
    ------
    SimulationError
        If the rows hold no contact.
    """
    try:
        metrics = contact_metrics(
            t, rows["v_des_m_per_s"], rows["f_act_n"], rows["f_comp_n"], params.spacecraft_mass_kg
        )
    except ValueError as err:  # e.g. a noisy reading pushed the model away before contact
        raise SimulationError(f"{err} within the {t[-1]:.3g} s simulated") from None
    return SimulationResult(
        params=params,
        time_s=np.array(t),
        **{name: np.array(rows[name]) for name in LOG_ROWS if name != "a_act_m_per_s2"},
        metrics=metrics,
        steps=steps,
    )


def simulate(params: HybridLoopParams, **kwargs) -> SimulationResult:
    """Build the hybrid loop for ``params`` and run it through one contact.

    Keyword arguments go to :func:`run_loop`.
    """
    return run_loop(build_hybrid_loop(params), **kwargs)
