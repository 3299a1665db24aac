"""Run the 6-DoF docking loop through one contact and collect its record."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from pydrake.systems.analysis import Simulator

from hybridtable._plugins import simulation_failure
from hybridtable.errors import SimulationError
from hybridtable.laws.separation import SeparationRule
from hybridtable.six_dof.builder import LOG_LAYOUT, DockingLoop, build_docking_loop
from hybridtable.six_dof.drogue import floor_depth_m, probe_force_n, throat_depth_m
from hybridtable.six_dof.metrics import CAPTURE_SPEED_RATIO, DockingMetrics, docking_metrics
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.physics6 import DockingPhysics
from hybridtable.six_dof.pose import rotation_exp

__all__ = [
    "MAX_TICKS",
    "DockingRun",
    "simulate6",
    "contact_potential_j",
    "expected_end_s",
    "peak_force_n",
    "captured_in_drogue",
    "probe_centres_m",
]

#: Simulated time between checks of the record (s).
_CHUNK_S = 0.02

#: The most rig-computer ticks one 6-DoF run may take (each a Python tick of
#: the rig computer's systems, about 0.1 ms): 10 s at 10 kHz.
MAX_TICKS = 100_000


@dataclass
class DockingRun:
    """The record of one 6-DoF run: every block of the log at each tick.

    Attributes
    ----------
    params : DockingLoopParams
    time_s : ndarray (N,)
    log : dict of ndarray (N, size)
        ``commanded_state``, ``table_state``, ``contact_wrench``,
        ``measured_wrench``, ``compensated_wrench``, ``body_state`` (see
        :data:`~hybridtable.six_dof.builder.LOG_LAYOUT`).
    metrics : DockingMetrics
    wall_time_s : float
    """

    params: DockingLoopParams
    time_s: np.ndarray
    log: dict[str, np.ndarray]
    metrics: DockingMetrics | None = None
    wall_time_s: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def port_velocity_m_per_s(self) -> np.ndarray:
        """Velocity of the docking port (N, 3)."""
        return self.log["commanded_state"][:, 6:9]

    @property
    def kinetic_energy_j(self) -> np.ndarray:
        """Translational plus rotational kinetic energy of the model (N,)."""
        return self.translational_energy_j + self.rotational_energy_j

    @property
    def translational_energy_j(self) -> np.ndarray:
        v = self.log["body_state"][:, 3:6]
        return 0.5 * self.params.spacecraft.mass_kg * np.einsum("ij,ij->i", v, v)

    @property
    def rotational_energy_j(self) -> np.ndarray:
        w = self.log["body_state"][:, 15:18]
        return 0.5 * np.einsum("ij,jk,ik->i", w, self.params.spacecraft.inertia, w)

    @property
    def total_energy_j(self) -> np.ndarray:
        """Kinetic energy plus the contact's potential at the table's pose (N,)
        (:func:`contact_potential_j`: the pads only)."""
        return self.kinetic_energy_j + contact_potential_j(self.params, self.log["table_state"])


def probe_centres_m(params: DockingLoopParams, table_state: np.ndarray) -> np.ndarray:
    """The probe head's centre at each table pose (N, 3; m, W)."""
    c = params.contact.probe_centre_m
    return np.array([x[:3] + rotation_exp(x[3:6]) @ c for x in table_state])


def contact_potential_j(params: DockingLoopParams, table_state: np.ndarray) -> np.ndarray:
    """Elastic energy ``sum k_i delta_i^2 / 2`` of the pads at each table pose (J).

    Raises
    ------
    ValueError
        For the probe and drogue: Drake's meshed probe follows its smooth law
        only to 6-28 % (:mod:`~hybridtable.six_dof.drogue`), so there is no
        potential to state in closed form.
    """
    c = params.contact
    if c.is_cone:
        raise ValueError(
            "the probe's hydroelastic contact has no closed-form potential: judge a drogue "
            "docking by its kinetic energy before and after (energy_ratio)"
        )
    k_pad = c.contact_stiffness_n_per_m / c.pad_count
    out = np.zeros(len(table_state))
    for n, x in enumerate(table_state):
        R = rotation_exp(x[3:6])
        depth = x[2] + (c.pad_centres_m @ R.T)[:, 2] + c.pad_radius_m
        depth = depth[depth > 0.0]
        out[n] = 0.5 * k_pad * float(depth @ depth)
    return out


def expected_end_s(params: DockingLoopParams, through_drogue: bool = True) -> float:
    """A generous bound on when the first contact has ended (s): the approach
    over twice the gap, plus ten undamped contact durations, plus 0.5 s; in a
    drogue (``through_drogue``), plus four times the way from its mouth to the
    socket's floor at the approach speed (the probe slides in, and out again;
    :func:`simulate6` caps this part at its tick budget)."""
    a = params.approach
    half_period = 0.5 / params.contact_frequency_hz
    end = 2.0 * a.initial_gap_m / a.initial_velocity_m_per_s + 10.0 * half_period + 0.5
    if params.contact.is_cone and through_drogue:
        end += 4.0 * floor_depth_m(params.contact) / a.initial_velocity_m_per_s
    return end


def captured_in_drogue(params: DockingLoopParams, table_state: np.ndarray) -> bool:
    """Whether the probe head's centre passed the drogue's throat (its
    widest section past the latches' plane) at any pose of the record."""
    depth = throat_depth_m(params.contact)
    return bool(np.any(probe_centres_m(params, table_state)[:, 2] > depth))


def peak_force_n(params: DockingLoopParams) -> float:
    """The undamped head-on peak force (N): the pads' ``k v0 / omega``, the
    probe's force at its peak press."""
    c = params.contact
    if c.is_cone:
        return float(probe_force_n(c, params.peak_press_m))
    omega = 2.0 * math.pi * params.contact_frequency_hz
    return c.contact_stiffness_n_per_m * params.approach.initial_velocity_m_per_s / omega


def _held_in_socket(params: DockingLoopParams, data: np.ndarray, ticks: int) -> bool:
    """The probe head stays in the socket: over the record's last ``ticks``
    its centre is past the throat, and both its port's speed along the axis
    and the contact's force along it are at most
    :data:`~hybridtable.six_dof.metrics.CAPTURE_SPEED_RATIO` of the
    approach's speed and of the undamped head-on peak force (a bounce's
    turning point, still, is pressed hard). It may rattle across the socket."""
    if data.shape[1] < ticks:
        return False
    window = _split(data[:, -ticks:])
    ratio = CAPTURE_SPEED_RATIO
    axial_speed = window["commanded_state"][:, 8]
    if np.max(np.abs(axial_speed)) > ratio * params.approach.initial_velocity_m_per_s:
        return False
    if np.max(np.abs(window["contact_wrench"][:, 5])) > ratio * peak_force_n(params):
        return False
    centres = probe_centres_m(params, window["table_state"])
    return bool(np.all(centres[:, 2] > throat_depth_m(params.contact)))


def _split(data: np.ndarray) -> dict[str, np.ndarray]:
    out, row = {}, 0
    for name, size in LOG_LAYOUT.items():
        out[name] = data[row : row + size].T.copy()
        row += size
    return out


def simulate6(
    params: DockingLoopParams,
    loop: DockingLoop | None = None,
    progress: Callable[[float, float], None] | None = None,
    on_loop: Callable[[DockingLoop], None] | None = None,
    physics: DockingPhysics | None = None,
) -> DockingRun:
    """Simulate the 6-DoF loop through its first contact.

    Runs ``params.duration_s``, or until the contact has ended and the
    compensated wrench has stayed zero for the sensor delay plus 20 ticks
    (:class:`~hybridtable.laws.separation.SeparationRule`: the 1-D loop's
    divergence stop and step budget too); in a drogue, until the probe has
    left its mouth that way, or is held in the socket: its head's centre past
    the throat, its speed and contact force along the axis at most
    :data:`~hybridtable.six_dof.metrics.CAPTURE_SPEED_RATIO` of the
    approach's speed and of the head-on peak force, for as long.

    Parameters
    ----------
    params : DockingLoopParams
    loop : DockingLoop, optional
        A loop already built (e.g. with a Meshcat visualizer).
    progress : callable, optional
        ``progress(t_s, t_end_s)`` after each chunk of simulated time.
    on_loop : callable, optional
        Called with the loop before the simulation starts.
    physics : DockingPhysics, optional
        The rig's physical part where it differs from ``params`` (hidden
        effects: :mod:`~hybridtable.six_dof.physics6`); ``params`` stay the
        rig computer's.

    Raises
    ------
    DivergenceError
        If the contact force grows past 100 times the undamped head-on peak
        (``k v0 / omega``; the probe's force at its peak press), or a state
        stops being finite.
    SimulationError
        If no contact happened, or it has not ended by :func:`expected_end_s`
        with the port still moving along the docking axis (a port at rest
        against the target there is a capture, :attr:`DockingMetrics.captured
        <hybridtable.six_dof.metrics.DockingMetrics.captured>`), or the run is
        over the step budget.
    """
    import time

    start = time.perf_counter()
    t_end = params.duration_s if params.duration_s is not None else expected_end_s(params)
    if params.duration_s is None and params.contact.is_cone:
        # The flight through a deep drogue at a slow approach may outlast the
        # budget: run to the budget (a run that has not ended by then raises).
        needed = expected_end_s(params, through_drogue=False)
        t_end = max(needed, min(t_end, MAX_TICKS / params.sample_rate_hz))
    ticks = t_end * params.sample_rate_hz
    if ticks > MAX_TICKS:
        raise SimulationError(
            f"too long to simulate: {ticks:.3g} ticks of the rig computer ({t_end:.3g} s at "
            f"{params.sample_rate_hz:g} Hz); at most {MAX_TICKS:g} (a lower sample_rate_hz or "
            "a shorter duration_s)"
        )
    loop = loop or build_docking_loop(params, physics=physics)
    if loop.diagram is None:
        raise ValueError(
            "simulate6: loop.diagram is None: the loop was added to a builder of yours; "
            "set loop.diagram = builder.Build() first"
        )
    if on_loop is not None:
        on_loop(loop)
    simulator = Simulator(loop.diagram)
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    simulator.Initialize()
    h = params.sample_period_s
    separating = params.duration_s is None
    quiet_ticks = params.delay_ticks + 20
    rule = SeparationRule(
        t_end,
        settle_s=(quiet_ticks - 0.5) * h,  # the contact has ended after quiet_ticks quiet ticks
        check_interval_s=_CHUNK_S,
        peak_force_n=peak_force_n(params),
        stop_at_separation=separating,
        end_tolerance_s=0.5 * h,
    )
    log = loop.logger.FindLog(context)
    seen = 0
    cone = params.contact.is_cone
    settled = False  # a probe held in the drogue's socket
    while True:
        t = rule.next_check_s
        try:
            simulator.AdvanceTo(t)
        except (Exception, SystemExit) as err:  # Drake's asserts (SystemExit), a system's callback
            raise simulation_failure(err, "the 6-DoF simulation failed") from None
        data = log.data()
        force = np.linalg.norm(data[27:30], axis=0)
        # The divergence stop reads every tick since the last check: the contact's
        # and the compensator's force, and the compensator's moment over the port's
        # lever arm (a compensator can diverge while the body flies off the contact).
        fresh = data[:, seen:]
        seen = data.shape[1]
        lever = max(params.spacecraft.port_distance_m, 1e-3)
        loudest = max(
            float(np.max(np.linalg.norm(fresh[27:30], axis=0), initial=0.0)),
            float(np.max(np.linalg.norm(fresh[39:42], axis=0), initial=0.0)),
            float(np.max(np.linalg.norm(fresh[36:39], axis=0), initial=0.0)) / lever,
        )
        quiet = (force == 0.0) & ~np.any(data[36:42] != 0.0, axis=0)
        if params.contact.is_cone:  # a probe between the drogue's walls has not left it
            quiet &= data[14] < 0.0  # the port (the probe's tip) back out of the mouth's plane
        loud = np.flatnonzero(~quiet)
        touched = bool(np.any(force > 0.0))  # the contact starts with a contact force
        ended = rule.check(
            simulator.get_num_steps_taken(),
            loudest,
            active=touched and bool(loud.size) and loud[-1] == data.shape[1] - 1,
            touched=touched,
            finite=bool(np.all(np.isfinite(data[:, -quiet_ticks:]))),
            # quiet for the record's last ticks, counted in ticks
            active_at_s=t - (data.shape[1] - 1 - loud[-1]) * h if touched and loud.size else None,
            # the contact's, the measured and the compensated force now (named if it never ends)
            forces_n=tuple(float(np.linalg.norm(data[a : a + 3, -1])) for a in (27, 33, 39)),
        )
        if progress is not None:
            progress(t, rule.t_max)
        if cone and separating:
            settled = _held_in_socket(params, data, quiet_ticks)
        if ended or settled:
            break
    unended = None  # a contact that has not ended: an error unless it is a capture
    if separating and not settled:  # a record of a given duration is returned as it is
        try:
            rule.verdict()
        except SimulationError as err:
            if not rule.started:
                raise
            last = _split(log.data()[:, -quiet_ticks:])
            drifting = (
                cone
                and not np.any(last["contact_wrench"][:, 3:])
                and not np.any(last["compensated_wrench"])
            )
            # A probe drifting through the drogue untouched at the bound has
            # ended its contact: only its slow way out is left.
            unended = None if drifting else err
    run = DockingRun(params, np.array(log.sample_times()), _split(log.data()))
    if loop.compensator.HasOutputPort("stiffness_scale"):  # an online identifier's estimate
        scale = loop.compensator.GetOutputPort("stiffness_scale")
        k = params.believed_contact.contact_stiffness_n_per_m
        run.extra["identified_stiffness_n_per_m"] = float(
            scale.Eval(loop.compensator.GetMyContextFromRoot(context))[0] * k
        )
    try:
        run.metrics = docking_metrics(
            run.time_s,
            run.port_velocity_m_per_s,
            run.kinetic_energy_j,
            run.rotational_energy_j,
            run.log["contact_wrench"],
            run.log["compensated_wrench"],
            run.log["commanded_state"][:, 0:3],
            captured=(
                captured_in_drogue(params, run.log["table_state"])
                if params.contact.is_cone
                else None
            ),
        )
    except ValueError as err:
        if params.duration_s is None:
            raise SimulationError(str(err)) from None
    if unended is not None and not (run.metrics is not None and run.metrics.captured):
        raise unended
    run.wall_time_s = time.perf_counter() - start
    return run
