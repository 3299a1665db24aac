"""Replay: drive the rig's physical part with the recorded command.

The recorded ``p_des`` (and ``v_des``) of a run, zero-order held from tick
``k`` to tick ``k + 1`` exactly as the rig computer sent them, drive the table,
the contact and the force sensor; the replay predicts ``p_act`` and ``f_mea``
at the ticks. Unlike the closed loop, no error of the model feeds back into
the command, so the residuals of the replay isolate the physics.

::

    TrajectorySource --> ZeroOrderHold(h) --commanded_state--> table --motion--> contact
    (recorded p_des, v_des)                                                        |
                                                 f_mea <-- force sensor <--force---+

The command source is a piecewise-constant trajectory whose pieces are
centred on the ticks. A linear table (one with a ``sampled(h)`` method, e.g.
:class:`~hybridtable.systems.table.SecondOrderTable`) is replaced by its exact
discretization (:class:`~hybridtable.systems.table.SampledTable`) when the
contact and the sensor have no continuous state: the replay is then discrete,
exact at the ticks and needs no integrator (three times faster). Otherwise a
Drake ``ZeroOrderHold`` samples the command at the ticks, so the table's
integrator never steps across a jump. The physical part comes from
:func:`hybridtable.measurement.rig.add_physical_part` (swappable with
:class:`~hybridtable.measurement.rig.RigPhysics`); the logs are read at the ticks with the
loop's semantics (``f_mea[k] = f_act(t_k - T_fms)`` for the sampled sensor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, TrajectorySource, ZeroOrderHold
from pydrake.trajectories import PiecewisePolynomial

from hybridtable._plugins import simulation_failure
from hybridtable.errors import SimulationError
from hybridtable.laws.compiled import LawSystem
from hybridtable.loop.budget import check_budget
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import FIXED_STEP_INTEGRATORS
from hybridtable.measurement.rig import (
    RigPhysics,
    add_physical_part,
    rig_params,
    set_table_initial_state,
)
from hybridtable.measurement.run_format import Run
from hybridtable.systems.contact_law import ContactLaw
from hybridtable.systems.measurement_chain import MeasurementChain
from hybridtable.systems.sensor import ForceSensorDelay
from hybridtable.systems.table import SampledTable

__all__ = ["ReplayResult", "replay", "replay_command"]


@dataclass
class ReplayResult:
    """The physical part's response to a recorded command, one row per tick.

    Attributes
    ----------
    params : HybridLoopParams
        The model's parameters (after the physics changes).
    time_s, p_des_m, v_des_m_per_s : ndarray
        Ticks and the command held from each tick to the next.
    p_act_m, v_act_m_per_s : ndarray
        Table position and velocity at the ticks.
    f_act_n : ndarray
        Actual (model) contact force at the ticks.
    f_mea_n : ndarray
        The force sensor's reading at the ticks.
    steps : int
        Integrator steps taken.
    """

    params: HybridLoopParams
    time_s: np.ndarray
    p_des_m: np.ndarray
    v_des_m_per_s: np.ndarray
    p_act_m: np.ndarray
    v_act_m_per_s: np.ndarray
    f_act_n: np.ndarray
    f_mea_n: np.ndarray
    steps: int


def replay_command(
    params: HybridLoopParams,
    p_des_m: np.ndarray,
    v_des_m_per_s: np.ndarray,
    physics: RigPhysics | None = None,
    integrator: str = "runge_kutta3",
    accuracy: float = 1e-8,
) -> ReplayResult:
    """Drive the physical part of ``params`` with a command held over ticks.

    Parameters
    ----------
    params : HybridLoopParams
        A sampled loop's parameters (``sample_rate_hz`` set); the physics of
        ``physics`` is applied to them.
    p_des_m, v_des_m_per_s : array
        Command of tick ``k`` (held on ``[k h, (k + 1) h)``).
    physics : RigPhysics, optional
        Model variant of the physical part (default: nominal).
    integrator, accuracy :
        As in :func:`hybridtable.loop.simulation.run_loop` (the step never exceeds
        a tick).

    Raises
    ------
    SimulationError
        If the response becomes non-finite, or the replay is over the
        simulation budget (:func:`hybridtable.loop.budget.check_budget`).
    """
    physics = physics or RigPhysics()
    params = physics.apply(params)
    h = params.sample_period_s
    if h is None:
        raise ValueError("replay needs a sampled loop (sample_rate_hz set)")
    p = np.asarray(p_des_m, dtype=float)
    v = np.asarray(v_des_m_per_s, dtype=float)
    n = len(p)
    if n < 2 or len(v) != n:
        raise ValueError("the command needs two equally long series of at least 2 ticks")
    laws = _law_replay(params, physics, p, v)
    if laws is not None:
        return laws
    builder = DiagramBuilder()
    # Pieces centred on the ticks: the value at tick k is sample k even when
    # Drake's event time differs from k h by rounding.
    breaks = h * (np.arange(n + 1) - 0.5)
    samples = np.vstack([np.append(p, p[-1]), np.append(v, v[-1])])
    source = builder.AddNamedSystem(
        "recorded_command",
        TrajectorySource(PiecewisePolynomial.ZeroOrderHold(breaks, samples)),
    )
    part = add_physical_part(builder, params, physics, sampled_table_period_s=h)
    # A sampled table is exact per tick; a continuous one must be integrated.
    check_budget(params, n * h, h, what="the replay", integrated=not part.table_is_sampled)
    if part.table_is_sampled:
        # The sampled table holds the command of each tick itself.
        builder.Connect(source.get_output_port(), part.table.GetInputPort("commanded_state"))
    else:
        hold = builder.AddNamedSystem("command_hold", ZeroOrderHold(h, 2))
        builder.Connect(source.get_output_port(), hold.get_input_port())
        builder.Connect(hold.get_output_port(), part.table.GetInputPort("commanded_state"))
    logs = {
        "motion": LogVectorOutput(part.table.GetOutputPort("motion"), builder, h),
        "f_act": LogVectorOutput(part.contact.GetOutputPort("force"), builder, h),
        "f_mea": LogVectorOutput(part.sensor.GetOutputPort("measured_force"), builder, h),
    }
    diagram = builder.Build()
    diagram.set_name("replay")
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    set_table_initial_state(part.table, part.table.GetMyMutableContextFromRoot(context), params)
    ResetIntegratorFromFlags(simulator, integrator, h)
    integ = simulator.get_mutable_integrator()
    integ.set_maximum_step_size(h)  # (unused when the replay is discrete)
    if integrator in FIXED_STEP_INTEGRATORS:
        integ.set_fixed_step_mode(True)
    else:
        integ.set_target_accuracy(accuracy)
    try:
        simulator.Initialize()
        simulator.AdvanceTo((n - 0.5) * h)
    except (Exception, SystemExit) as err:  # Drake's asserts (SystemExit), a system's callback
        raise simulation_failure(err, "replay failed") from None
    found = {name: sink.FindLog(context) for name, sink in logs.items()}
    t = found["motion"].sample_times()
    if len(t) < n or not np.allclose(t[:n], h * np.arange(n), rtol=0.0, atol=1e-6 * h):
        raise SimulationError(f"replay logged {len(t)} samples out of step with {n} ticks")
    motion = found["motion"].data()[:, :n]
    f_act = found["f_act"].data()[0, :n]
    f_mea = found["f_mea"].data()[0, :n]
    if not (np.isfinite(motion).all() and np.isfinite(f_mea).all()):
        raise SimulationError("replay diverged (non-finite table motion or force)")
    return ReplayResult(
        params=params,
        time_s=h * np.arange(n),
        p_des_m=p.copy(),
        v_des_m_per_s=v.copy(),
        p_act_m=motion[0].copy(),
        v_act_m_per_s=motion[1].copy(),
        f_act_n=f_act.copy(),
        f_mea_n=f_mea.copy(),
        steps=simulator.get_num_steps_taken(),
    )


def _states_its_law(system, method: str, library: tuple[type, ...]) -> bool:
    """Whether ``system``'s law at the ticks (``method``) stands for its Drake
    system: one of the library's own systems, by exact type, or a class that
    states ``method`` in its own body (a user's, e.g. the backlash example's
    ``respond``). A subclass that only inherits it may compute something else
    in Drake, and replays on the diagram."""
    return type(system) in library or method in type(system).__dict__


def _law_replay(
    params: HybridLoopParams, physics: RigPhysics, p: np.ndarray, v: np.ndarray
) -> ReplayResult | None:
    """The replay without a simulator, where every part of the physics states
    its law at the ticks (:func:`_states_its_law`): a table with an exact
    sampled form (:meth:`~hybridtable.systems.table.SampledTable.respond`), a
    contact with a ``force_law`` and a sensor with ``readings``. The same
    systems' own coefficients and law functions, evaluated tick by tick as the
    discrete Drake diagram does; None where a part (a user's wrapped system
    without its law, a continuous sensor) has no such form, and the diagram
    replays."""
    h = params.sample_period_s
    table = physics.make_table(params)
    sampled = getattr(table, "sampled", None)
    table = sampled(h) if sampled is not None else None
    contact = physics.make_contact(params)
    sensor = physics.make_sensor(params)
    if not (
        _states_its_law(table, "respond", (SampledTable,))
        and _states_its_law(contact, "force_law", (ContactLaw, LawSystem))
        and _states_its_law(sensor, "readings", (ForceSensorDelay, MeasurementChain))
    ):
        return None
    law = getattr(contact, "force_law", None)
    if law is None:
        return None
    check_budget(params, len(p) * h, h, what="the replay", integrated=False)
    ic = params.initial_conditions()
    motion = table.respond(np.column_stack([p, v]), ic["p_act_m"], ic["v_act_m_per_s"])
    if getattr(contact, "force_law_elementwise", False):
        f_act = np.asarray(law(motion[:, 0], motion[:, 1], motion[:, 2]), dtype=float)
    elif getattr(contact, "force_law_unilateral", False):  # 0 p apart: the law in contact only
        f_act = 0.0 * motion[:, 0]
        touching = motion[:, 0] > 0.0
        f_act[touching] = [law(*row) for row in motion[touching].tolist()]
    else:
        f_act = np.array([law(*row) for row in motion.tolist()], dtype=float)
    f_mea = sensor.readings(f_act)
    if f_mea is None:
        return None
    if not (np.isfinite(motion).all() and np.isfinite(f_mea).all()):
        raise SimulationError("replay diverged (non-finite table motion or force)")
    return ReplayResult(
        params=params,
        time_s=h * np.arange(len(p)),
        p_des_m=p.copy(),
        v_des_m_per_s=v.copy(),
        p_act_m=motion[:, 0].copy(),
        v_act_m_per_s=motion[:, 1].copy(),
        f_act_n=f_act,
        f_mea_n=np.asarray(f_mea, dtype=float),
        steps=0,
    )


def replay(
    run: Run,
    physics: RigPhysics | None = None,
    integrator: str = "runge_kutta3",
    accuracy: float = 1e-8,
) -> ReplayResult:
    """Replay a recorded run's command through the rig's physical part.

    See :func:`replay_command`; the parameters come from the run's JSON
    (:func:`hybridtable.measurement.rig.rig_params`).
    """
    params = rig_params(run.info, run.where("json"))
    return replay_command(
        params, run.p_des_m, run.v_des_m_per_s, physics, integrator=integrator, accuracy=accuracy
    )
