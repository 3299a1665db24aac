"""The 1-D hybrid simulation loop of the paper as a Drake diagram.

::

    spacecraft --state--> table --motion--> contact --force--> sensor delay
        ^                   |                                      |
        |                   +--table_motion--+                     |
        +--compensated_force-- compensator <-+---measured_force----+
                               ^--commanded_state-- spacecraft

The table and the contact are swappable back-ends with fixed ports: any table
takes ``commanded_state`` (2) and gives ``motion`` (3); any contact takes
``motion`` and gives ``force`` (1) and ``force_rate`` (1).

The rig computer (spacecraft model, compensator, sensor sampling) runs either
continuously (the paper's simulations; ``sample_rate_hz=None``) or at a sample
rate with a zero-order-held command and sampled sensors.
"""

from __future__ import annotations

from dataclasses import dataclass

from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import LogVectorOutput, Multiplexer, VectorLogSink

from hybridtable._components import Block, add_component
from hybridtable.compensators.registry import make_compensator
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.wiring import LOOP_WIRING, connect
from hybridtable.systems.contact import UnilateralSpringContact
from hybridtable.systems.sensor import ForceSensorDelay, continuous_delay_period
from hybridtable.systems.spacecraft import Spacecraft
from hybridtable.systems.table import SecondOrderTable

__all__ = [
    "HybridLoop",
    "add_hybrid_loop",
    "default_sensor",
    "build_hybrid_loop",
    "LOGGED",
    "LOG_ROWS",
]


#: Rows of the loop's log, in order.
LOG_ROWS: tuple[str, ...] = (
    "p_des_m",
    "v_des_m_per_s",
    "p_act_m",
    "v_act_m_per_s",
    "a_act_m_per_s2",
    "f_act_n",
    "f_mea_n",
    "f_comp_n",
)


#: Signals logged by the loop, name -> (unit, description).
LOGGED: dict[str, tuple[str, str]] = {
    "p_des_m": ("m", "spacecraft position = table command"),
    "v_des_m_per_s": ("m/s", "spacecraft velocity"),
    "p_act_m": ("m", "table position (penetration when > 0)"),
    "v_act_m_per_s": ("m/s", "table velocity"),
    "f_act_n": ("N", "actual contact force"),
    "f_mea_n": ("N", "measured (delayed) force"),
    "f_comp_n": ("N", "compensated force fed to the spacecraft"),
}


@dataclass
class HybridLoop:
    """Handles to the systems and the logger that :func:`add_hybrid_loop` added."""

    params: HybridLoopParams
    #: Each part is a whole system, or the :class:`~hybridtable._components.Block`
    #: of a component added flat (the same named ports).
    spacecraft: Spacecraft | Block
    table: System | Block
    contact: System | Block
    sensor: ForceSensorDelay | Block
    compensator: System | Block
    #: Logs ``[p_des, v_des, p_act, v_act, a_act, f_act, f_mea, f_comp]``
    #: (rows of :data:`LOG_ROWS`).
    logger: VectorLogSink | None = None
    diagram: Diagram | None = None
    #: Period of the rig computer's discrete events (sample period, or the
    #: continuous mode's delay-line period).
    computer_period_s: float = 0.0

    def set_initial_conditions(self, root_context) -> None:
        """Write the initial states of :attr:`params` into a root context."""
        ic = self.params.initial_conditions()
        self._set_state(self.spacecraft, root_context, ic["p_des_m"], ic["v_des_m_per_s"])
        # Any table back-end with a set_initial_state(context, p, v) method.
        self._set_state(self.table, root_context, ic["p_act_m"], ic["v_act_m_per_s"])

    def _set_state(self, part: System | Block, root_context, *state: float) -> None:
        if isinstance(part, Block):
            part.set_initial_state(root_context, *state)
        elif hasattr(part, "set_initial_state"):
            sub = part.GetMyMutableContextFromRoot(root_context)
            part.set_initial_state(sub, *state)


def default_sensor(params: HybridLoopParams) -> ForceSensorDelay:
    """The loop's sensor when none is given: the delay of ``params``, sampled at the
    rig computer's rate, or the continuous delay line of a continuous computer."""
    if params.sample_period_s is None:
        return ForceSensorDelay(params.rig.sensor, "continuous", params.step_s)
    return ForceSensorDelay(params.rig.sensor, "sampled", params.sample_period_s)


def add_hybrid_loop(
    builder: DiagramBuilder,
    params: HybridLoopParams,
    table: System | None = None,
    contact: System | None = None,
    compensator: System | None = None,
    log: bool = True,
    sensor: System | None = None,
    flat: bool = True,
) -> HybridLoop:
    """Add the hybrid loop's systems to ``builder``, wire them, and return them.

    Parameters
    ----------
    builder : DiagramBuilder
    params : HybridLoopParams
    table, contact : System, optional
        Swappable back-ends (default: :class:`SecondOrderTable`,
        :class:`UnilateralSpringContact`). They must have the ports described
        in :mod:`hybridtable.loop.builder`; they are added to the builder here.
    compensator : System, optional
        A compensator with the ports of :class:`~hybridtable.compensators.paper.Compensator`
        (default: the one registered under ``params.compensator``); wrapped in the
        passivity guard when ``params.passivity``.
    log : bool
        Add a ``VectorLogSink`` for every signal in :data:`LOGGED`.
    sensor : System, optional
        A force-measurement back-end with the ports of
        :class:`~hybridtable.systems.sensor.ForceSensorDelay` (input ``force``, output
        ``measured_force``); default: the delay of ``params`` (sampled at the
        sample rate, or the continuous delay line).
    flat : bool
        Add the library's components (:class:`~hybridtable._components.Component`:
        the spacecraft, table, sensor and compiled compensator) as their
        primitives, straight into ``builder`` (the handles are then
        :class:`~hybridtable._components.Block` s with the same ports): the
        simulator steps a flat diagram faster (a nested Table 1 run takes 1.3 to
        1.4 times as long). ``False`` adds each
        as its own diagram (one box a component in a drawing).
    """
    h_sample = params.sample_period_s
    if h_sample is None:
        if params.sensor_delay_s > 0.0:
            h_computer, _ = continuous_delay_period(params.sensor_delay_s, params.step_s)
        else:
            h_computer = params.step_s
        spacecraft = Spacecraft(params.plant.spacecraft)
    else:
        h_computer = h_sample
        spacecraft = Spacecraft(
            params.plant.spacecraft, sample_period_s=h_sample, integrator=params.rig.integrator
        )
    spacecraft = add_component(builder, "spacecraft", spacecraft, flat)
    table = add_component(builder, "table", table or SecondOrderTable(params.plant.table), flat)
    contact = add_component(
        builder, "contact", contact or UnilateralSpringContact(params.plant.contact), flat
    )
    sensor = add_component(builder, "force_sensor", sensor or default_sensor(params), flat)
    compensator = add_component(
        builder, "compensator", make_compensator(params, h_computer, compensator), flat
    )
    systems = dict(
        spacecraft=spacecraft,
        table=table,
        contact=contact,
        force_sensor=sensor,
        compensator=compensator,
    )
    connect(builder, systems, LOOP_WIRING)
    loop = HybridLoop(
        params, spacecraft, table, contact, sensor, compensator, computer_period_s=h_computer
    )
    if log:
        # One sink for all signals (one logger per step is cheaper than five).
        # Continuous: every integration step. Sampled: once per tick, before
        # the tick's discrete update (the values the rig computer reads).
        ports = [
            spacecraft.GetOutputPort("state"),
            table.GetOutputPort("motion"),
            contact.GetOutputPort("force"),
            sensor.GetOutputPort("measured_force"),
            compensator.GetOutputPort("compensated_force"),
        ]
        mux = builder.AddNamedSystem("log_mux", Multiplexer([p.size() for p in ports]))
        for i, port in enumerate(ports):
            builder.Connect(port, mux.get_input_port(i))
        sink = LogVectorOutput(
            mux.get_output_port(), builder, 0.0 if h_sample is None else h_sample
        )
        sink.set_name("log")
        loop.logger = sink
    return loop


def build_hybrid_loop(params: HybridLoopParams, **kwargs) -> HybridLoop:
    """Build the hybrid loop as a stand-alone diagram (see :func:`add_hybrid_loop`)."""
    builder = DiagramBuilder()
    loop = add_hybrid_loop(builder, params, **kwargs)
    loop.diagram = builder.Build()
    loop.diagram.set_name("hybrid_loop")
    return loop
