"""Replay a recorded 6-DoF run's commands through the model's table, contact
and F/T sensor: what the rig's physical part would have done with the
commands the rig computer sent.

The replay is the open loop of a run (the 1-D replay's counterpart,
:mod:`hybridtable.measurement.replay`): the logged command ``[q_des; qd_des]``
drives the scenario's table back-end (the table model or the Stewart
platform, :func:`~hybridtable.six_dof.builder.table_backend`) against the
docking contact, and the F/T sensor's delay line (without its noise) reads
the contact's wrench. Its measured pose and wrench are the model's
prediction of the record's ``q_act`` and ``w_mea``. The rig computer's noise
never reaches the replay, so it compares the physics without the closed
loop's drift (the F/T noise fed back through the compensator moves the
lateral friction by far more than the noise).

The diagram's spacecraft holds its command from the update at tick ``k`` on
(:mod:`~hybridtable.six_dof.run6`: the format's row ``k`` is that update's
result, which the diagram logs at ``k + 1``, before that tick's update): the
playback does the same with the logged rows. Before the first update it holds
the scenario's start (:func:`~hybridtable.six_dof.builder.initial_port_state`),
as the spacecraft does.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import LogVectorOutput, Multiplexer

from hybridtable._plugins import simulation_failure
from hybridtable.six_dof.builder import (
    add_rig_part,
    initial_port_state,
    set_initial_table,
    table_backend,
)
from hybridtable.six_dof.physics6 import DockingPhysics
from hybridtable.six_dof.run6 import Run6
from hybridtable.six_dof.spacecraft import RigidSpacecraft

__all__ = ["CommandPlayback", "Replay6", "replay_run6"]


class CommandPlayback(LeafSystem):
    """The logged commands, one a tick, held as the spacecraft holds its own.

    Ports
    -----
    Output ``commanded_state`` (12: m, rad, m/s, rad/s)
        ``[q_des; qd_des]``: row ``k`` of ``rows`` from the update at tick
        ``k`` on (the last row after the record's end).
    """

    def __init__(self, rows: np.ndarray, period_s: float, initial: np.ndarray) -> None:
        LeafSystem.__init__(self)
        self._rows = np.ascontiguousarray(rows, dtype=float)
        self._h = float(period_s)
        state = self.DeclareDiscreteState(BasicVector(np.asarray(initial, dtype=float)))
        self.DeclarePeriodicDiscreteUpdateEvent(self._h, 0.0, self._update)
        self.DeclareStateOutputPort("commanded_state", state)

    def _update(self, context, discrete_state) -> None:
        k = min(int(round(context.get_time() / self._h)), len(self._rows) - 1)
        discrete_state.get_mutable_vector(0).SetFromVector(self._rows[k])


class Replay6:
    """What the replay predicts at each of the record's ticks.

    Attributes
    ----------
    table_state : ndarray (N, 12)
        The table's ``[q_act; qd_act]``.
    measured_wrench : ndarray (N, 6)
        The F/T sensor's reading ``[moment; force]`` (its delay, no noise).
    """

    def __init__(self, table_state: np.ndarray, measured_wrench: np.ndarray) -> None:
        self.table_state = table_state
        self.measured_wrench = measured_wrench


def _commands(run: Run6) -> np.ndarray:
    """The command from each tick's update on (N, 12): the record's rows."""
    return np.hstack([run.pose("des"), run.blocks["v_des"], run.blocks["w_des"]])


def replay_run6(run: Run6, physics: DockingPhysics | None = None) -> Replay6:
    """Replay the run's commands (see the module) through the scenario's
    physical part, or through ``physics`` (the scenario with effects).

    Raises
    ------
    SimulationError
        If Drake's simulation fails (e.g. the Stewart platform leaves its workspace).
    """
    params = run.params
    true = physics.apply(params) if physics is not None else params
    h = params.sample_period_s
    commands = _commands(run)
    start, _ = initial_port_state(params, RigidSpacecraft(params.spacecraft, h))
    builder = DiagramBuilder()
    playback = builder.AddNamedSystem("playback", CommandPlayback(commands, h, start))
    backend = builder.AddNamedSystem("table_backend", table_backend(true, physics))
    measured, table = add_rig_part(
        builder, params, physics, playback.get_output_port(), backend, False
    )
    ports = [table, measured]
    mux = builder.AddNamedSystem("log_mux", Multiplexer([p.size() for p in ports]))
    for i, port in enumerate(ports):
        builder.Connect(port, mux.get_input_port(i))
    sink = LogVectorOutput(mux.get_output_port(), builder, h)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    set_initial_table(backend, context, params, start, physics)
    simulator.Initialize()
    try:
        simulator.AdvanceTo((run.n - 1) * h)
    except (Exception, SystemExit) as err:  # Drake's asserts, a system's callback
        raise simulation_failure(err, "the 6-DoF replay failed") from None
    data = sink.FindLog(context).data()[:, : run.n]
    return Replay6(data[:12].T.copy(), data[12:18].T.copy())
