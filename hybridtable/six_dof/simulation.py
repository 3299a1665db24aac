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
from hybridtable.six_dof.drogue import probe_force_n, profile, throat_depth_m
from hybridtable.six_dof.metrics import CAPTURE_SPEED_RATIO, DockingMetrics, docking_metrics
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.pose import rotation_exp

__all__ = [
    "MAX_TICKS",
    "DockingRun",
    "simulate6",
    "contact_potential_j",
    "expected_end_s",
    "captured_in_drogue",
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
        (:func:`contact_potential_j`; the probe's from the record's wrench)."""
        return self.kinetic_energy_j + contact_potential_j(
            self.params, self.log["table_state"], self.log["contact_wrench"]
        )


def probe_centres_m(params: DockingLoopParams, table_state: np.ndarray) -> np.ndarray:
    """The probe head's centre at each table pose (N, 3; m, W)."""
    c = params.contact.probe_centre_m
    return np.array([x[:3] + rotation_exp(x[3:6]) @ c for x in table_state])


def contact_potential_j(
    params: DockingLoopParams, table_state: np.ndarray, contact_wrench: np.ndarray | None = None
) -> np.ndarray:
    """Elastic energy of the contact at each table pose (J): the pads'
    ``sum k_i delta_i^2 / 2``; the probe's, the work the device did against
    the contact since the record's start, ``-integral w . dq`` over the
    record's ``contact_wrench`` (trapezoids; the rotation vector's
    differences: small turns between ticks), since Drake's meshed probe
    follows its smooth law only to a few per cent
    (:mod:`~hybridtable.six_dof.drogue`)."""
    c = params.contact
    if c.is_cone:
        if contact_wrench is None:
            raise ValueError("the probe's potential needs the record's contact_wrench")
        w = np.asarray(contact_wrench, dtype=float)
        dq = np.diff(np.asarray(table_state, dtype=float)[:, :6], axis=0)
        mean = 0.5 * (w[1:] + w[:-1])
        work = np.einsum("ij,ij->i", mean[:, [3, 4, 5, 0, 1, 2]], dq)
        return np.concatenate([[0.0], -np.cumsum(work)])
    k_pad = c.contact_stiffness_n_per_m / c.pad_count
    out = np.zeros(len(table_state))
    for n, x in enumerate(table_state):
        R = rotation_exp(x[3:6])
        depth = x[2] + (c.pad_centres_m @ R.T)[:, 2] + c.pad_radius_m
        depth = depth[depth > 0.0]
        out[n] = 0.5 * k_pad * float(depth @ depth)
    return out


def expected_end_s(params: DockingLoopParams) -> float:
    """A generous bound on when the first contact has ended (s): the approach
    over twice the gap, plus ten undamped contact durations, plus 0.5 s; in a
    drogue, plus four times the way from its mouth to the socket's floor at
    the approach speed (the probe slides in, and out again)."""
    a = params.approach
    half_period = 0.5 / params.contact_frequency_hz
    end = 2.0 * a.initial_gap_m / a.initial_velocity_m_per_s + 10.0 * half_period + 0.5
    if params.contact.is_cone:
        end += 4.0 * float(profile(params.contact)[-1, 1]) / a.initial_velocity_m_per_s
    return end


def captured_in_drogue(params: DockingLoopParams, table_state: np.ndarray) -> bool:
    """Whether the probe head's centre passed the drogue's throat (its
    widest section past the latches' plane) at any pose of the record."""
    depth = throat_depth_m(params.contact)
    return bool(np.any(probe_centres_m(params, table_state)[:, 2] > depth))


def _peak_force_n(params: DockingLoopParams) -> float:
    """The undamped head-on peak force (N): the pads' ``k v0 / omega``, the
    probe's force at its peak press."""
    c = params.contact
    if c.is_cone:
        return float(probe_force_n(c, params.peak_press_m))
    omega = 2.0 * math.pi * params.contact_frequency_hz
    return c.contact_stiffness_n_per_m * params.approach.initial_velocity_m_per_s / omega


def _centre_z_m(params: DockingLoopParams, rows: np.ndarray) -> np.ndarray:
    """The probe head's centre's z at the log's ``rows`` (columns of
    :data:`~hybridtable.six_dof.builder.LOG_LAYOUT`'s blocks): the port's z
    less the probe's radius times ``R_zz`` of the table's rotation vector."""
    theta = rows[15:18]
    angle = np.sqrt(np.sum(theta * theta, axis=0))
    c = np.cos(angle)
    safe = np.where(angle > 0.0, angle, 1.0)
    r_zz = c + (1.0 - c) * (theta[2] / safe) ** 2
    return rows[14] - params.contact.probe_radius_m * r_zz


def _held_in_socket(params: DockingLoopParams, data: np.ndarray, ticks: int) -> bool:
    """The probe head stays in the socket: its centre past the throat over
    the record's last ``ticks``, and its port's speed along the axis at most
    :data:`~hybridtable.six_dof.metrics.CAPTURE_SPEED_RATIO` of the approach's
    (it may rattle across the socket, it does not leave)."""
    if data.shape[1] < ticks:
        return False
    window = data[:, -ticks:]
    inside = np.all(_centre_z_m(params, window) > throat_depth_m(params.contact))
    axial = np.max(np.abs(window[8]))
    return bool(inside and axial <= CAPTURE_SPEED_RATIO * params.approach.initial_velocity_m_per_s)


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
) -> DockingRun:
    """Simulate the 6-DoF loop through its first contact.

    Runs ``params.duration_s``, or until the contact has ended and the
    compensated wrench has stayed zero for the sensor delay plus 20 ticks
    (:class:`~hybridtable.laws.separation.SeparationRule`: the 1-D loop's
    divergence stop and step budget too); in a drogue, until the probe has
    left its mouth that way, or is held in the socket: its head's centre past
    the throat and its speed along the axis at most
    :data:`~hybridtable.six_dof.metrics.CAPTURE_SPEED_RATIO` of the
    approach's, for as long.

    Parameters
    ----------
    params : DockingLoopParams
    loop : DockingLoop, optional
        A loop already built (e.g. with a Meshcat visualizer).
    progress : callable, optional
        ``progress(t_s, t_end_s)`` after each chunk of simulated time.
    on_loop : callable, optional
        Called with the loop before the simulation starts.

    Raises
    ------
    DivergenceError
        If the contact force grows past 100 times the undamped peak
        ``k v0 / omega``, or a state stops being finite.
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
    ticks = t_end * params.sample_rate_hz
    if ticks > MAX_TICKS:
        raise SimulationError(
            f"too long to simulate: {ticks:.3g} ticks of the rig computer ({t_end:.3g} s at "
            f"{params.sample_rate_hz:g} Hz); at most {MAX_TICKS:g} (a lower sample_rate_hz or "
            "a shorter duration_s)"
        )
    loop = loop or build_docking_loop(params)
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
        expected_end_s(params) if separating else params.duration_s,
        settle_s=(quiet_ticks - 0.5) * h,  # the contact has ended after quiet_ticks quiet ticks
        check_interval_s=_CHUNK_S,
        peak_force_n=_peak_force_n(params),
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
            unended = err
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
