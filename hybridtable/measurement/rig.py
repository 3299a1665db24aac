"""The rig of a recorded run as a model: parameters, physics back-ends, closed loop.

A recorded run (:mod:`hybridtable.measurement.run_format`) names the nominal parameters
the rig ran with. :func:`rig_params` maps them to a sampled
:class:`~hybridtable.loop.params.HybridLoopParams`: the rig computer at the run's
sample rate (zero-order-held command, sampled sensors, the compensator exactly
as ``hybridtable-run/1`` defines it, semi-implicit Euler spacecraft), the
nominal physics (second-order table, unilateral spring, pure sensor delay).

:class:`RigPhysics` holds optional factories for the physical part (table,
contact, force sensor) and parameter changes of the physics, so that a model
variant (a damped or nonlinear contact, another table, a sensor filter) is
compared with the same code: :func:`simulate_rig` (the closed loop) and
:func:`hybridtable.measurement.replay.replay` (the physical part driven by the recorded
command) both take one. The compensator always keeps the nominal parameters
of the run's JSON file: it is the rig's software, not physics.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from pydrake.systems.framework import DiagramBuilder, System

from hybridtable.errors import MeasurementError, ParameterError, SimulationError
from hybridtable.loop.builder import add_hybrid_loop, default_sensor
from hybridtable.loop.fast import fast_unsupported, record_fast
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import FIXED_STEP_INTEGRATORS, SimulationResult, run_loop
from hybridtable.measurement.run_format import Run, RunInfo
from hybridtable.systems.contact import UnilateralSpringContact
from hybridtable.systems.table import SecondOrderTable

__all__ = [
    "PHYSICS_PARAMS",
    "COMPUTER_PARAMS",
    "RigPhysics",
    "PhysicalPart",
    "rig_params",
    "computer_with_model_mass",
    "model_mass_kg",
    "run_with_model_mass",
    "add_physical_part",
    "build_rig_loop",
    "simulate_rig",
    "simulate_rig_contact",
    "set_table_initial_state",
    "TABLE_START_KEY",
]

#: HybridLoopParams fields that describe physics (what :class:`RigPhysics`
#: may change); every other field is the rig computer's.
PHYSICS_PARAMS: tuple[str, ...] = (
    "contact_stiffness_n_per_m",
    "contact_damping_n_s_per_m",
    "sensor_delay_s",
    "table_response_hz",
    "table_damping_ratio",
    "table_initial_state",
)

#: HybridLoopParams fields of the rig computer that :class:`RigPhysics` may
#: set to what an audit (:mod:`hybridtable.measurement.audit`) found it used.
COMPUTER_PARAMS: tuple[str, ...] = (
    "spacecraft_mass_kg",
    "compensator",
    "lead_time_s",
    "compensator_stiffness_n_per_m",
    "force_deadband_n",
    "computer_integrator",
)

SystemFactory = Callable[[HybridLoopParams], System]


@dataclass(frozen=True)
class RigPhysics:
    """The physical part of a rig model: nominal unless told otherwise.

    Parameters
    ----------
    table, contact, sensor : callable, optional
        Factories ``f(params) -> System`` returning a *new* Drake system each
        call (a model is built twice per run: replay and closed loop). Ports:
        a table takes ``commanded_state`` (2) and gives ``motion`` (3); a
        contact takes ``motion`` and gives ``force`` and ``force_rate``; a
        sensor takes ``force`` and gives ``measured_force``. A table with a
        ``set_initial_state(context, p, v)`` method gets the run's initial
        table state. ``None``: the nominal system for ``params``.
    changes : mapping, optional
        Changes of the physical parameters (names in :data:`PHYSICS_PARAMS`),
        e.g. ``{"contact_damping_n_s_per_m": 200.0}``. They change the
        physics only; the compensator keeps the run's nominal values.
    name : str
        A label for reports.
    computer : mapping, optional
        Changes of the rig computer (names in :data:`COMPUTER_PARAMS`).
    loop : tuple of callable, optional
        Changes of the loop's parameters ``change(params) -> params``, applied
        in order after the others (an effect's
        :attr:`~hybridtable.effects.spec.ModelSpec.loop`).
    """

    table: SystemFactory | None = None
    contact: SystemFactory | None = None
    sensor: SystemFactory | None = None
    changes: Mapping[str, Any] = field(default_factory=dict)
    name: str = "nominal"
    computer: Mapping[str, Any] = field(default_factory=dict)
    loop: tuple[Callable[[HybridLoopParams], HybridLoopParams], ...] = ()

    def __post_init__(self) -> None:
        bad = [k for k in self.changes if k not in PHYSICS_PARAMS]
        if bad:
            raise ParameterError(
                f"RigPhysics.changes: {', '.join(bad)} not physical parameters "
                f"(one of {', '.join(PHYSICS_PARAMS)})"
            )
        bad = [k for k in self.computer if k not in COMPUTER_PARAMS]
        if bad:
            raise ParameterError(
                f"RigPhysics.computer: {', '.join(bad)} not rig-computer parameters "
                f"(one of {', '.join(COMPUTER_PARAMS)})"
            )

    def apply(self, params: HybridLoopParams) -> HybridLoopParams:
        """``params`` with :attr:`changes` applied, the compensator believing
        what it did before them
        (:meth:`~hybridtable.loop.params.HybridLoopParams.with_physics`), then
        :attr:`computer`, then each change of :attr:`loop` in order."""
        if not self.changes and not self.computer and not self.loop:
            return params
        if self.changes or self.computer:
            params = params.with_physics(**dict(self.changes)).with_(**dict(self.computer))
        for change in self.loop:
            params = change(params)
        return params

    def make_table(self, params: HybridLoopParams) -> System:
        return self.table(params) if self.table else SecondOrderTable(params.plant.table)

    def make_contact(self, params: HybridLoopParams) -> System:
        return (
            self.contact(params) if self.contact else UnilateralSpringContact(params.plant.contact)
        )

    def make_sensor(self, params: HybridLoopParams) -> System:
        if self.sensor:
            return self.sensor(params)
        return default_sensor(params)


def rig_params(info: RunInfo, source: str | None = None) -> HybridLoopParams:
    """The sampled hybrid-loop parameters of a run's rig (nominal physics).

    The table starts at the initial command with the approach velocity
    (``table_initial_state="command"``: the record starts while the rig is
    already moving; a contact event of a long log gives its own, under the
    extra key :data:`TABLE_START_KEY`), the compensated force is clamped at zero and gated by the
    measured force, the MDC uses the JSON stiffness and no damping.

    Raises
    ------
    MeasurementError
        If the JSON values do not make a model (e.g. a sensor delay that is
        not a whole number of sample periods), naming ``source``.
    """
    try:
        return HybridLoopParams(
            spacecraft_mass_kg=info.spacecraft_mass_kg,
            contact_stiffness_n_per_m=info.contact_stiffness_n_per_m,
            contact_damping_n_s_per_m=0.0,
            sensor_delay_s=info.sensor_delay_s,
            table_response_hz=info.table_natural_frequency_hz,
            table_damping_ratio=info.table_damping_ratio,
            compensator=info.compensator,
            lead_time_s=info.lead_time_s,
            compensator_stiffness_n_per_m=info.contact_stiffness_n_per_m,
            compensator_damping_n_s_per_m=0.0,
            force_deadband_n=info.force_deadband_n,
            clamp_nonnegative=True,
            contact_gate="measured_force",
            initial_velocity_m_per_s=info.initial_velocity_m_per_s,
            initial_gap_m=info.initial_gap_m,
            sample_rate_hz=info.sample_rate_hz,
            **_table_start(info),
        )
    except ParameterError as err:
        raise MeasurementError(f"{source or 'run ' + info.run_id}: {err}") from None


def model_mass_kg(stated_mass_kg: float, mass_ratio: float = 1.0) -> float:
    """The mass the rig computer's spacecraft model integrates with, kg:
    ``mass_ratio`` times the stated one.

    ``stated_mass_kg`` is the spacecraft's mass as stated (a run's JSON
    ``spacecraft_mass_kg``, or that of the loop a model is put on), kg;
    ``mass_ratio`` is the ``mass_error`` effect's ratio (1: the computer
    integrates with the stated mass). The physical part (table, contact,
    sensor) does not see it: only the closed loop does.
    """
    return stated_mass_kg * mass_ratio


def computer_with_model_mass(
    computer: Mapping[str, Any], stated_mass_kg: float, mass_ratio: float
) -> dict[str, Any]:
    """The rig computer's changes with the mass it integrates with, by one
    rule for every user (the closed loop, the linear models, ``--record``):
    the mass the audit found (``spacecraft_mass_kg`` already in ``computer``:
    the runs' own evidence) wins; else ``mass_ratio`` times the stated mass
    (:func:`model_mass_kg`); else none (the stated one)."""
    out = dict(computer)
    if mass_ratio != 1.0 and "spacecraft_mass_kg" not in out:
        out["spacecraft_mass_kg"] = model_mass_kg(stated_mass_kg, mass_ratio)
    return out


def run_with_model_mass(run: Run, mass_ratio: float) -> Run:
    """``run`` whose JSON mass is the one its rig computer integrates with
    (:func:`model_mass_kg`), for :func:`simulate_rig`; ``run`` itself for a
    ratio of 1. A ``spacecraft_mass_kg`` in the :attr:`RigPhysics.computer`
    the run is simulated with still replaces it."""
    if mass_ratio == 1.0:
        return run
    mass = model_mass_kg(run.info.spacecraft_mass_kg, mass_ratio)
    return replace(run, info=replace(run.info, spacecraft_mass_kg=mass))


#: The key of a run's JSON extras that gives its table's state at t = 0 (set by
#: :mod:`hybridtable.measurement.events` for a contact event of a long log).
TABLE_START_KEY = "table_initial_state"


def _table_start(info: RunInfo) -> dict:
    """The table's initial state of a run: ``"command"``, or the one its extras give."""
    given = info.extra.get(TABLE_START_KEY)
    if not isinstance(given, dict):
        return {"table_initial_state": "command"}
    return {
        "table_initial_state": "given",
        "table_initial_position_m": given.get("position_m"),
        "table_initial_velocity_m_per_s": given.get("velocity_m_per_s"),
    }


def _run_params(run: Run, physics: RigPhysics) -> HybridLoopParams:
    return physics.apply(rig_params(run.info, run.where("json")))


@dataclass
class PhysicalPart:
    """Handles to the table, contact and sensor that :func:`add_physical_part` added."""

    params: HybridLoopParams
    table: System
    contact: System
    sensor: System
    #: The table is a :class:`~hybridtable.systems.table.SampledTable`: its
    #: ``commanded_state`` takes the command sent at each tick, unheld.
    table_is_sampled: bool = False


def add_physical_part(
    builder: DiagramBuilder,
    params: HybridLoopParams,
    physics: RigPhysics | None = None,
    sampled_table_period_s: float | None = None,
) -> PhysicalPart:
    """Add the rig's physical part (table -> contact -> force sensor) and wire it.

    The table's ``commanded_state`` input is left for the caller to connect.
    With ``sampled_table_period_s``, a table with a ``sampled(h)`` method is
    replaced by its exact discretization when the contact and the sensor have
    no continuous state (they only see the table at the ticks then);
    :attr:`PhysicalPart.table_is_sampled` says whether it was.
    """
    physics = physics or RigPhysics()
    table_system = physics.make_table(params)
    contact_system = physics.make_contact(params)
    sensor_system = physics.make_sensor(params)
    sampled = False
    if (
        sampled_table_period_s is not None
        and hasattr(table_system, "sampled")
        and contact_system.num_continuous_states() == 0
        and sensor_system.num_continuous_states() == 0
    ):
        discrete = table_system.sampled(sampled_table_period_s)
        if discrete is not None:
            table_system, sampled = discrete, True
    table = builder.AddNamedSystem("table", table_system)
    contact = builder.AddNamedSystem("contact", contact_system)
    sensor = builder.AddNamedSystem("force_sensor", sensor_system)
    builder.Connect(table.GetOutputPort("motion"), contact.GetInputPort("motion"))
    builder.Connect(contact.GetOutputPort("force"), sensor.GetInputPort("force"))
    return PhysicalPart(params, table, contact, sensor, sampled)


def set_table_initial_state(table: System, context, params: HybridLoopParams) -> None:
    """Give ``table`` (in its own ``context``) the initial state of ``params``,
    if it has a ``set_initial_state(context, p, v)`` method."""
    setter = getattr(table, "set_initial_state", None)
    if setter is not None:
        ic = params.initial_conditions()
        setter(context, ic["p_act_m"], ic["v_act_m_per_s"])


def build_rig_loop(run: Run, physics: RigPhysics | None = None, noise=None):
    """The closed loop of a run's rig as a built :class:`~hybridtable.loop.builder.HybridLoop`.

    With ``noise`` (a :class:`~hybridtable.systems.noise.MeasurementNoiseParams`),
    the rig computer reads the force and the table position through it; the
    loop's log keeps the noise-free signals.
    """
    physics = physics or RigPhysics()
    params = _run_params(run, physics)
    builder = DiagramBuilder()
    compensator = None
    if noise is not None:
        from hybridtable.compensators.registry import make_compensator
        from hybridtable.systems.noise import with_measurement_noise

        h = params.sample_period_s
        compensator = with_measurement_noise(make_compensator(params, h), noise, h)
    loop = add_hybrid_loop(
        builder,
        params,
        table=physics.make_table(params),
        contact=physics.make_contact(params),
        sensor=physics.make_sensor(params),
        compensator=compensator,
    )
    loop.diagram = builder.Build()
    loop.diagram.set_name(f"rig_loop_{run.run_id}")
    return loop


def simulate_rig(
    run: Run,
    physics: RigPhysics | None = None,
    integrator: str = "runge_kutta3",
    accuracy: float = 1e-8,
    noise=None,
) -> SimulationResult:
    """Re-run the rig's whole loop from the run's initial state, for the
    record's full duration, and return one row per recorded tick.

    Row ``k`` has the ``hybridtable-run/1`` meaning (what the computer read at
    tick ``k``, the force it computed, the spacecraft state after the tick).
    ``noise``: as in :func:`build_rig_loop` (the rows hold the noise-free
    readings; :func:`~hybridtable.systems.noise.noise_series` adds what the
    computer read).

    The nominal systems (``physics`` changes parameters only), no noise, and a
    loop the fast engine models run on it
    (:func:`~hybridtable.loop.fast.record_fast`: exact at the ticks, a hundred
    times faster); anything else, and a fixed-step ``integrator``
    (:data:`~hybridtable.loop.simulation.FIXED_STEP_INTEGRATORS`), on the
    Drake diagram.

    Raises
    ------
    SimulationError
        If the model diverges or never touches.
    MeasurementError
        If the run's parameters do not make a model.
    """
    fast = _fast_record(run, physics or RigPhysics(), integrator, noise)
    if fast is not None:
        return fast
    loop = build_rig_loop(run, physics, noise)
    h = run.sample_period_s
    # Logs at ticks 0 .. n (the last one gives the state after tick n - 1).
    result = run_loop(
        loop,
        t_max_s=(run.n + 0.5) * h,
        integrator=integrator,
        accuracy=accuracy,
        stop_at_separation=False,
    )
    n = run.n
    if len(result.time_s) < n:
        raise SimulationError(
            f"rig model of {run.run_id} stopped after {len(result.time_s)} of {n} ticks"
        )
    for name in result.signals():
        setattr(result, name, getattr(result, name)[:n])
    if not np.allclose(result.time_s, h * np.arange(n), rtol=0.0, atol=1e-6 * h):
        raise SimulationError(f"rig model of {run.run_id}: ticks out of step with the record")
    return result


def _fast_record(run: Run, physics: RigPhysics, integrator: str, noise) -> SimulationResult | None:
    """:func:`simulate_rig` on the fast engine, or None where it does not apply."""
    nominal = physics.table is None and physics.contact is None and physics.sensor is None
    if noise is not None or not nominal or integrator in FIXED_STEP_INTEGRATORS:
        return None
    params = _run_params(run, physics)
    if fast_unsupported(params) is not None:
        return None
    return record_fast(params, run.n)


def simulate_rig_contact(
    info: RunInfo,
    physics: RigPhysics | None = None,
    noise=None,
    accuracy: float = 1e-8,
) -> SimulationResult:
    """One contact of the rig of ``info`` (its sampled computer, the physics
    of ``physics``), from the approach until the spacecraft has separated;
    the result's ``metrics`` hold its CoR, peak force and energy gain.

    Raises
    ------
    SimulationError
        If the model diverges or never separates.
    """
    empty = np.zeros(1)
    frame = Run(info, empty, empty, empty, empty, empty, empty)
    return run_loop(build_rig_loop(frame, physics, noise), accuracy=accuracy)
