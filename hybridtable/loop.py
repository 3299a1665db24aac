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

import math
from dataclasses import dataclass, replace

from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import LogVectorOutput, Multiplexer, VectorLogSink

from hybridtable._validation import (
    check_choice,
    check_nonnegative,
    check_positive,
    check_positive_or_inf,
)
from hybridtable.compensator import CompensatorParams, compensator_names, make_compensator
from hybridtable.contact import ContactParams, UnilateralSpringContact
from hybridtable.sensor import ForceSensorDelay, SensorParams, continuous_delay_period
from hybridtable.spacecraft import Spacecraft, SpacecraftParams
from hybridtable.table import SecondOrderTable, TableParams

__all__ = [
    "TABLE_INITIAL_STATES",
    "HybridLoopParams",
    "HybridLoop",
    "add_hybrid_loop",
    "build_hybrid_loop",
    "LOGGED",
]

TABLE_INITIAL_STATES: tuple[str, ...] = ("tracking", "command", "rest")

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


@dataclass(frozen=True)
class HybridLoopParams:
    """Every parameter of one hybrid-loop run, SI units.

    Parameters
    ----------
    spacecraft_mass_kg : float
        Spacecraft model mass m, > 0.
    contact_stiffness_n_per_m : float
        True contact stiffness k_con, > 0.
    contact_damping_n_s_per_m : float
        True contact damping, >= 0.
    sensor_delay_s : float
        Force-sensor delay T_fms, >= 0.
    table_response_hz : float
        Table response frequency f_resp, > 0, ``math.inf`` for an ideal table.
    table_damping_ratio : float
        Table damping ratio, >= 0.
    compensator : str
        A registered compensator (:func:`hybridtable.compensator.compensator_names`):
        the paper's "none", "SDC", "MDC", "SDMDC", or a plug-in.
    lead_time_s : float or None
        SDC lead time; ``None`` means ``sensor_delay_s`` (the paper's choice).
    compensator_stiffness_n_per_m, compensator_damping_n_s_per_m : float or None
        What the MDC believes; ``None`` means the true contact values.
    force_deadband_n : float
        Measured forces at or below this are "no contact".
    clamp_nonnegative : bool
        Clamp the compensated force at zero.
    contact_gate : {"measured_force", "table_position"}
        How the compensator tells contact (:mod:`hybridtable.compensator`).
    initial_velocity_m_per_s : float
        Approach velocity of the spacecraft model, > 0.
    initial_gap_m : float
        Gap between the devices at t = 0, >= 0.
    table_initial_state : {"tracking", "command", "rest"}
        ``"tracking"``: the table starts in steady tracking of the approach
        ramp (lag ``2 zeta / omega`` behind the command, same velocity), so the
        contact sees no start-up transient. ``"command"``: at the initial
        command position with the approach velocity (a rig that starts its
        record while already moving). ``"rest"``: at the initial command, at
        rest.
    sample_rate_hz : float or None
        ``None``: continuous rig computer. Otherwise the rate of the rig's
        computer loop.
    time_step_s : float
        Continuous mode: the largest integration step and delay-line period.
    passivity : bool
        Guard the compensator with the time-domain passivity observer and
        controller (:mod:`hybridtable.plugins.passivity`).
    """

    spacecraft_mass_kg: float
    contact_stiffness_n_per_m: float
    contact_damping_n_s_per_m: float = 0.0
    sensor_delay_s: float = 0.0
    table_response_hz: float = math.inf
    table_damping_ratio: float = 0.8
    compensator: str = "none"
    lead_time_s: float | None = None
    compensator_stiffness_n_per_m: float | None = None
    compensator_damping_n_s_per_m: float | None = None
    force_deadband_n: float = 0.0
    clamp_nonnegative: bool = False
    contact_gate: str = "measured_force"
    initial_velocity_m_per_s: float = 0.1
    initial_gap_m: float = 0.001
    table_initial_state: str = "tracking"
    sample_rate_hz: float | None = None
    time_step_s: float | None = None
    passivity: bool = False

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "spacecraft_mass_kg", check_positive("spacecraft_mass_kg", self.spacecraft_mass_kg))
        for name in ("contact_stiffness_n_per_m", "initial_velocity_m_per_s"):
            s(self, name, check_positive(name, getattr(self, name)))
        if self.time_step_s is not None:
            s(self, "time_step_s", check_positive("time_step_s", self.time_step_s))
        for name in (
            "contact_damping_n_s_per_m",
            "sensor_delay_s",
            "table_damping_ratio",
            "force_deadband_n",
            "initial_gap_m",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        s(
            self,
            "table_response_hz",
            check_positive_or_inf("table_response_hz", self.table_response_hz),
        )
        check_choice("compensator", self.compensator, compensator_names())
        check_choice("table_initial_state", self.table_initial_state, TABLE_INITIAL_STATES)
        for name in (
            "lead_time_s",
            "compensator_stiffness_n_per_m",
            "compensator_damping_n_s_per_m",
        ):
            if getattr(self, name) is not None:
                s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.sample_rate_hz is not None:
            s(self, "sample_rate_hz", check_positive("sample_rate_hz", self.sample_rate_hz))
            # Raises a clear error when the delay is not a whole number of ticks.
            from hybridtable.sensor import delay_samples

            delay_samples(self.sensor_delay_s, self.sample_period_s)

    # -- derived quantities ------------------------------------------------
    @classmethod
    def from_contact_frequency(
        cls, contact_frequency_hz: float, contact_stiffness_n_per_m: float, **kwargs
    ) -> HybridLoopParams:
        """Parameters with the mass that gives the contact natural frequency
        ``f_con = sqrt(k / m) / (2 pi)`` (how the paper specifies its runs)."""
        f = check_positive("contact_frequency_hz", contact_frequency_hz)
        k = check_positive("contact_stiffness_n_per_m", contact_stiffness_n_per_m)
        return cls(
            spacecraft_mass_kg=k / (2.0 * math.pi * f) ** 2, contact_stiffness_n_per_m=k, **kwargs
        )

    @property
    def contact_frequency_hz(self) -> float:
        """Undamped contact natural frequency sqrt(k/m) / 2 pi."""
        return math.sqrt(self.contact_stiffness_n_per_m / self.spacecraft_mass_kg) / (2 * math.pi)

    @property
    def step_s(self) -> float:
        """The continuous mode's step: ``time_step_s`` or its default."""
        if self.time_step_s is not None:
            return self.time_step_s
        return min(2e-4, 1.0 / (5000.0 * self.contact_frequency_hz))

    @property
    def sample_period_s(self) -> float | None:
        """1 / sample_rate_hz, or None for a continuous loop."""
        return None if self.sample_rate_hz is None else 1.0 / self.sample_rate_hz

    @property
    def effective_delay_s(self) -> float:
        """tau_eff = T_fms + 2 zeta / omega_resp, the loop's low-frequency delay."""
        return self.sensor_delay_s + self.table().ramp_lag_s

    def with_(self, **changes) -> HybridLoopParams:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def spacecraft(self) -> SpacecraftParams:
        return SpacecraftParams(mass_kg=self.spacecraft_mass_kg)

    def table(self) -> TableParams:
        return TableParams(self.table_response_hz, self.table_damping_ratio)

    def contact(self) -> ContactParams:
        return ContactParams(self.contact_stiffness_n_per_m, self.contact_damping_n_s_per_m)

    def sensor(self) -> SensorParams:
        return SensorParams(self.sensor_delay_s)

    def compensator_params(self) -> CompensatorParams:
        def pick(value, default):
            return default if value is None else value

        return CompensatorParams(
            kind=self.compensator,
            lead_time_s=pick(self.lead_time_s, self.sensor_delay_s),
            stiffness_n_per_m=pick(
                self.compensator_stiffness_n_per_m, self.contact_stiffness_n_per_m
            ),
            damping_n_s_per_m=pick(
                self.compensator_damping_n_s_per_m, self.contact_damping_n_s_per_m
            ),
            force_deadband_n=self.force_deadband_n,
            clamp_nonnegative=self.clamp_nonnegative,
            contact_gate=self.contact_gate,
        )

    def initial_conditions(self) -> dict[str, float]:
        """Initial spacecraft and table states."""
        x0 = -self.initial_gap_m
        v0 = self.initial_velocity_m_per_s
        if self.table_initial_state == "rest":
            pa, va = x0, 0.0
        elif self.table_initial_state == "command":
            pa, va = x0, v0
        else:
            pa, va = x0 - self.table().ramp_lag_s * v0, v0
        return {"p_des_m": x0, "v_des_m_per_s": v0, "p_act_m": pa, "v_act_m_per_s": va}


@dataclass
class HybridLoop:
    """Handles to the systems and the logger that :func:`add_hybrid_loop` added."""

    params: HybridLoopParams
    spacecraft: Spacecraft
    table: System
    contact: System
    sensor: ForceSensorDelay
    compensator: System
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
        sc = self.diagram.GetMutableSubsystemContext(self.spacecraft, root_context)
        self.spacecraft.set_initial_state(sc, ic["p_des_m"], ic["v_des_m_per_s"])
        # Any table back-end with a set_initial_state(context, p, v) method.
        if hasattr(self.table, "set_initial_state"):
            tc = self.diagram.GetMutableSubsystemContext(self.table, root_context)
            self.table.set_initial_state(tc, ic["p_act_m"], ic["v_act_m_per_s"])


def add_hybrid_loop(
    builder: DiagramBuilder,
    params: HybridLoopParams,
    table: System | None = None,
    contact: System | None = None,
    compensator: System | None = None,
    log: bool = True,
    sensor: System | None = None,
) -> HybridLoop:
    """Add the hybrid loop's systems to ``builder``, wire them, and return them.

    Parameters
    ----------
    builder : DiagramBuilder
    params : HybridLoopParams
    table, contact : System, optional
        Swappable back-ends (default: :class:`SecondOrderTable`,
        :class:`UnilateralSpringContact`). They must have the ports described
        in :mod:`hybridtable.loop`; they are added to the builder here.
    compensator : System, optional
        A compensator with the ports of :class:`~hybridtable.compensator.Compensator`
        (default: the one registered under ``params.compensator``); wrapped in the
        passivity guard when ``params.passivity``.
    log : bool
        Add a ``VectorLogSink`` for every signal in :data:`LOGGED`.
    sensor : System, optional
        A force-measurement back-end with the ports of
        :class:`~hybridtable.sensor.ForceSensorDelay` (input ``force``, output
        ``measured_force``); default: the delay of ``params`` (sampled at the
        sample rate, or the continuous delay line).
    """
    sensor_backend = sensor
    h_sample = params.sample_period_s
    if h_sample is None:
        if params.sensor_delay_s > 0.0:
            h_computer, _ = continuous_delay_period(params.sensor_delay_s, params.step_s)
        else:
            h_computer = params.step_s
        sensor = ForceSensorDelay(params.sensor(), "continuous", params.step_s)
        spacecraft = Spacecraft(params.spacecraft())
    else:
        h_computer = h_sample
        sensor = ForceSensorDelay(params.sensor(), "sampled", h_sample)
        spacecraft = Spacecraft(params.spacecraft(), sample_period_s=h_sample)
    spacecraft = builder.AddNamedSystem("spacecraft", spacecraft)
    table = builder.AddNamedSystem("table", table or SecondOrderTable(params.table()))
    contact = builder.AddNamedSystem(
        "contact", contact or UnilateralSpringContact(params.contact())
    )
    sensor = builder.AddNamedSystem("force_sensor", sensor_backend or sensor)
    compensator = builder.AddNamedSystem(
        "compensator", make_compensator(params, h_computer, compensator)
    )
    builder.Connect(spacecraft.GetOutputPort("state"), table.GetInputPort("commanded_state"))
    builder.Connect(table.GetOutputPort("motion"), contact.GetInputPort("motion"))
    builder.Connect(contact.GetOutputPort("force"), sensor.GetInputPort("force"))
    builder.Connect(
        sensor.GetOutputPort("measured_force"), compensator.GetInputPort("measured_force")
    )
    builder.Connect(table.GetOutputPort("motion"), compensator.GetInputPort("table_motion"))
    builder.Connect(spacecraft.GetOutputPort("state"), compensator.GetInputPort("commanded_state"))
    builder.Connect(
        compensator.GetOutputPort("compensated_force"), spacecraft.GetInputPort("force")
    )
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
