"""Margins of the 6-DoF loop in contact: the linearized MIMO loop at one tick.

The loop is linearized about the docked pose (:meth:`DockingLoopParams.nominal_pose`,
every pad pressed; the contact's K and C from Drake's contact) with the
spacecraft's rigid body, the table model, the F/T delay (``M`` ticks, and a
reading between ticks mixed from its two neighbouring samples) and
the compensator, as the map of one rig-computer tick ``x[k+1] = A x[k]``
(state: the body's pose and twist deviations, the table's state, the delay
line, the compensator's stored wrench). Its eigenvalues ``lambda`` give the
modes in contact, ``s = ln(lambda) / h``: a mode with ``Re s > 0`` grows, i.e.
the loop pumps energy into it. Eigenvalues at 1 are the free directions the
frictionless contact does not hold (lateral translation, spin about the
axis), left out. The critical delay is the shortest sensor delay whose loop
has a growing mode (the SDC's lead following the delay unless the scenario
states one, as in the 1-D loop's margins).

The Stewart table is linearized as the table model at its legs' reference
response (``table_response_hz``: that model's on the Stewart table).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridtable.analysis.critical import critical_delay
from hybridtable.errors import ParameterError
from hybridtable.loop.params import believed
from hybridtable.six_dof.compensator import stiffness_model_of
from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.physics6 import DockingPhysics
from hybridtable.six_dof.pose import skew
from hybridtable.six_dof.registry import linear_law
from hybridtable.six_dof.table import pose_table_tick
from hybridtable.systems.measurement_chain import low_pass_system, mount_system
from hybridtable.systems.resonant_table import StructuralModeParams
from hybridtable.systems.sensor import sample_taps

__all__ = [
    "ContactModes",
    "contact_modes",
    "critical_delay_s",
    "mdc_stiffness_of",
    "tick_matrix",
]

#: Eigenvalues closer than this to 1 are free directions (not modes in contact).
_FREE = 1e-6
#: How many of the slowest modes are reported (the contact's; the table's and
#: the delay line's are far faster).
_REPORTED = 6
#: A growth rate below this (1/s) counts as neutral (round-off of marginal modes).
_NEUTRAL_PER_S = 1e-6


@dataclass(frozen=True)
class ContactModes:
    """The modes of the linearized loop in contact.

    Attributes
    ----------
    frequencies_hz : tuple of float
        Damped frequency ``|Im s| / 2 pi`` of each of the six slowest modes
        (one per complex pair), slowest first.
    growth_rates_per_s : tuple of float
        ``Re s`` of each (> 0: the mode grows).
    damping_ratios : tuple of float
        ``-Re s / |s|`` of each.
    max_growth_rate_per_s : float
        Over every mode of the loop in contact: the slowest are the
        contact's; a faster one that grows is one the rig computer cannot
        integrate at its rate (a body too light or too stiffly held for its
        tick), reported among the modes above in place of the fastest of them.
    stable : bool
        No mode of the loop in contact grows.
    critical_delay_s : float
        The shortest sensor delay at which a mode grows (``math.inf``: none
        up to the scan's end; 0: it grows without delay).
    spectral_radius : float
        Largest ``|lambda|`` over the modes in contact.
    """

    frequencies_hz: tuple[float, ...]
    growth_rates_per_s: tuple[float, ...]
    damping_ratios: tuple[float, ...]
    max_growth_rate_per_s: float
    stable: bool
    critical_delay_s: float
    spectral_radius: float

    def to_dict(self) -> dict:
        return {
            "frequencies_hz": list(self.frequencies_hz),
            "growth_rates_per_s": list(self.growth_rates_per_s),
            "damping_ratios": list(self.damping_ratios),
            "max_growth_rate_per_s": self.max_growth_rate_per_s,
            "stable": self.stable,
            "critical_delay_s": self.critical_delay_s,
            "spectral_radius": self.spectral_radius,
        }


def tick_matrix(
    params: DockingLoopParams,
    K: np.ndarray,
    C: np.ndarray,
    delay_ticks: float | None = None,
    physics: DockingPhysics | None = None,
    mdc_stiffness: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``A`` of the linearized loop over one tick (see the module docstring),
    with the contact's ``K``, ``C`` (6x6) and a delay of ``delay_ticks`` ticks
    (default: the scenario's), which the SDC's lead follows unless the
    scenario states one (:func:`~hybridtable.loop.params.believed`, as in the
    1-D loop). A delay between ticks reads the two neighbouring samples mixed,
    as the sensor does (:func:`~hybridtable.systems.sensor.sample_taps`). The
    MDC's ``K`` and ``C`` are its own stiffness model's
    (:func:`~hybridtable.six_dof.compensator.stiffness_model_of`: the contact
    it believes, or its given matrix) at the docked pose; ``sdmdc-online``'s
    the contact's, where its estimate converges.

    ``physics``: the rig as an effect model says it is
    (:class:`~hybridtable.six_dof.physics6.DockingPhysics`): its table, delay
    and contact (``K``, ``C`` are then of :meth:`DockingPhysics.apply
    <hybridtable.six_dof.physics6.DockingPhysics.apply>`'s contact), the
    table's gain and structural mode, the sensor's gain, low pass and mount
    (the diagram's Drake primitives, as matrices), and the rig computer of
    :meth:`DockingPhysics.computer
    <hybridtable.six_dof.physics6.DockingPhysics.computer>`; a delay scanned is
    the scenario's, the rig's being that plus what the model adds.
    ``mdc_stiffness``: the MDC's ``(K, C)`` found once by a caller that scans
    the delay (:func:`mdc_stiffness_of`)."""
    h = params.sample_period_s
    delay_s = None if delay_ticks is None else float(delay_ticks) * h
    plant = computer = params
    if physics is not None:
        stated = params if delay_s is None else params.with_(sensor_delay_s=delay_s)
        plant, computer = physics.apply(stated), physics.computer(stated)
    if delay_ticks is None or physics is not None:
        M, alpha = plant.delay_taps
    else:
        M, alpha = sample_taps(float(delay_ticks), 1.0)
    L = M + (1 if alpha else 0)  # samples the delay line holds
    body = computer.spacecraft
    m = body.mass_kg
    r = body.port_position_m  # attitude deviations about the aligned pose
    I_inv = np.linalg.inv(body.inertia)
    mode = None if physics is None or physics.table_mode is None else physics.table_mode
    tick = pose_table_tick(
        plant.plant.table.response, h, None if mode is None else StructuralModeParams(*mode)
    )
    T = None if physics is None or physics.table_gain is None else np.array(physics.table_gain)
    chain = _sensor_chain(physics, h)
    linear = linear_law(computer.compensator)
    if linear is None:
        raise ParameterError(
            f"compensator {computer.compensator!r} declares no linear law "
            "(register_wrench_compensator(..., linear=LinearLaw(...))): no linear model"
        )
    kind = linear.law
    lead = believed(computer, "lead_time_s", delay_s) if kind in ("SDC", "SDMDC") else 0.0
    mdc = kind in ("MDC", "SDMDC")
    K_c, C_c = mdc_stiffness or mdc_stiffness_of(params, K, C, physics)
    n_state = 0 if tick is None else tick[0].shape[0]
    sizes = {
        "body": 12,
        "table": 6 * n_state,
        "chain": sum(a.shape[0] for a, *_ in chain),
        "delay": 6 * L,
        "prev": 6,
    }
    n = sum(sizes.values())
    start = {}
    i = 0
    for name, size in sizes.items():
        start[name] = i
        i += size
    # The port's pose and twist as linear maps of the body state [p, th, v, w].
    G = np.zeros((12, 12))
    G[0:3, 0:3] = np.eye(3)
    G[0:3, 3:6] = -skew(r)
    G[3:6, 3:6] = np.eye(3)
    G[6:9, 6:9] = np.eye(3)
    G[6:9, 9:12] = -skew(r)
    G[9:12, 9:12] = np.eye(3)

    def step(x: np.ndarray) -> np.ndarray:
        b = x[0:12]
        command = G @ b
        seen = command if T is None else np.concatenate([T @ command[:6], T @ command[6:]])
        out = np.zeros(n)
        if tick is None:
            table = seen
        else:
            Phi, Gamma = tick
            s = x[start["table"] : start["table"] + 6 * n_state].reshape(6, n_state)
            y = s @ Phi.T + np.outer(seen[:6], Gamma[:, 0])
            if Gamma.shape[1] > 1:  # a structural mode reads the command's rate too
                y = y + np.outer(seen[6:], Gamma[:, 1])
            table = np.concatenate([y[:, n_state - 2], y[:, n_state - 1]])
            out[start["table"] : start["table"] + 6 * n_state] = y.ravel()
        w_act = -K @ table[:6] - C @ table[6:]
        j = start["chain"]
        for a, bm, c, d in chain:  # the sensor's gain (no state), low pass and mount
            z = x[j : j + a.shape[0]]
            out[j : j + a.shape[0]] = a @ z + bm @ w_act
            w_act = c @ z + d @ w_act
            j += a.shape[0]
        # line[j] is the contact's wrench of tick k - L + j
        line = x[start["delay"] : start["delay"] + 6 * L].reshape(L, 6) if L else None
        w_mea = w_act if M == 0 else line[L - M]
        if alpha:
            w_mea = (1.0 - alpha) * w_mea + alpha * line[L - M - 1]
        if L:
            shifted = np.vstack([line[1:], w_act[None, :]])
            out[start["delay"] : start["delay"] + 6 * L] = shifted.ravel()
        prev = x[start["prev"] : start["prev"] + 6]
        w = w_mea + (lead / h) * (w_mea - prev)
        if mdc:
            w = w - K_c @ (command[:6] - table[:6]) - C_c @ (command[6:] - table[6:])
        out[start["prev"] : start["prev"] + 6] = w_mea
        f, tau = w[3:], w[:3] + np.cross(r, w[3:])
        v = b[6:9] + h * f / m
        om = b[9:12] + h * (I_inv @ tau)
        out[0:3] = b[0:3] + h * v
        out[3:6] = b[3:6] + h * om
        out[6:9] = v
        out[9:12] = om
        return out

    return np.column_stack([step(e) for e in np.eye(n)])


def mdc_stiffness_of(
    params: DockingLoopParams,
    K: np.ndarray,
    C: np.ndarray,
    physics: DockingPhysics | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The ``K`` and ``C`` of the MDC term at the docked pose: its own
    stiffness model's (:func:`~hybridtable.six_dof.compensator.stiffness_model_of`
    of the rig computer), or an online identifier's, the contact's ``K``,
    ``C`` (where its estimate converges)."""
    linear = linear_law(params.compensator)
    if linear is None or linear.law not in ("MDC", "SDMDC") or linear.identifies_stiffness:
        return K, C
    plant = params if physics is None else physics.apply(params)
    computer = params if physics is None else physics.computer(params)
    if computer.stiffness_model == "linearized" and computer.believed_contact == plant.contact:
        return K, C  # the same contact at the same pose
    return stiffness_model_of(computer)(plant.nominal_pose(), None)


def _sensor_chain(physics: DockingPhysics | None, h: float) -> list[tuple]:
    """The F/T sensor's parts before its delay, in the diagram's order
    (:func:`~hybridtable.six_dof.builder.add_rig_part`): its gain, low pass
    and mount, each ``(A, B, C, D)`` of a discrete system with feedthrough
    (a gain has no state)."""
    if physics is None:
        return []
    chain = []
    if physics.sensor_gain is not None:
        none = np.zeros((0, 0))
        chain.append((none, np.zeros((0, 6)), np.zeros((6, 0)), np.array(physics.sensor_gain)))
    if physics.sensor_time_constant_s > 0.0:
        chain.append(low_pass_system(physics.sensor_time_constant_s, h, channels=6))
    if physics.sensor_mount is not None:
        chain.append(mount_system(*physics.sensor_mount, h, channels=6))
    return chain


def _modes(A: np.ndarray, h: float):
    lam = np.linalg.eigvals(A)
    lam = lam[np.abs(lam - 1.0) > _FREE]
    lam = lam[np.abs(lam) > 1e-12]
    s = np.log(lam.astype(complex)) / h
    keep = s.imag >= 0.0
    return lam[keep], s[keep]


def critical_delay_s(
    params: DockingLoopParams,
    K: np.ndarray,
    C: np.ndarray,
    max_delay_s: float = 0.05,
    physics: DockingPhysics | None = None,
    mdc_stiffness: tuple[np.ndarray, np.ndarray] | None = None,
) -> float:
    """The shortest sensor delay (up to ``max_delay_s``) at which the
    linearized loop is not asymptotically stable (a mode whose growth rate is
    above -1e-6 /s: round-off of a neutral mode counts, as in the 1-D loop's
    :func:`~hybridtable.analysis.margins.critical_sensor_delay`, so an
    undamped contact's is 0). The 1-D loop's search
    (:func:`~hybridtable.analysis.critical.critical_delay`) on this loop's
    fastest mode: whole ticks scanned, the tick of the crossing refined (the
    rig computer reads a delay between ticks as the mix of its neighbours).
    With ``physics`` (:func:`tick_matrix`) the delay scanned is the
    scenario's: the rig's is that plus what the model adds."""
    h = params.sample_period_s
    mdc = mdc_stiffness or mdc_stiffness_of(params, K, C, physics)

    def growth(delay_s: float) -> float:
        _, s = _modes(tick_matrix(params, K, C, delay_s / h, physics, mdc), h)
        return float(np.max(s.real)) if s.size else -math.inf

    return critical_delay(growth, max_delay_s, h, tolerance=_NEUTRAL_PER_S)


def contact_modes(
    params: DockingLoopParams, max_delay_s: float = 0.05, physics: DockingPhysics | None = None
) -> ContactModes:
    """The modes of the loop linearized in contact, and its critical delay;
    with ``physics``, of the rig as an effect model says it is (its contact
    linearized at its own docked pose: :func:`tick_matrix`)."""
    plant = params if physics is None else physics.apply(params)
    K, C = DockingContact(plant.contact).stiffness(plant.nominal_pose())
    h = params.sample_period_s
    mdc = mdc_stiffness_of(params, K, C, physics)
    lam, s = _modes(tick_matrix(params, K, C, None, physics, mdc), h)
    growth = float(s.real.max()) if s.size else 0.0
    # Modes of the contact, not of the table or the delay line: below the
    # Nyquist rate and among the slowest; and the fastest-growing, if it grows.
    order = list(np.argsort(np.abs(s))[:_REPORTED])
    fastest = int(np.argmax(s.real)) if s.size else None
    if fastest is not None and growth > _NEUTRAL_PER_S and fastest not in order:
        order[-1] = fastest
    s = s[order]
    lam_all, lam = lam, lam[order]
    return ContactModes(
        frequencies_hz=tuple(float(abs(v.imag)) / (2 * math.pi) for v in s),
        growth_rates_per_s=tuple(float(v) for v in s.real),
        damping_ratios=tuple(float(-v.real / abs(v)) if abs(v) > 0 else 0.0 for v in s),
        max_growth_rate_per_s=growth,
        stable=bool(growth <= _NEUTRAL_PER_S),
        critical_delay_s=critical_delay_s(params, K, C, max_delay_s, physics, mdc),
        spectral_radius=float(np.abs(lam_all).max()) if lam_all.size else 1.0,
    )
