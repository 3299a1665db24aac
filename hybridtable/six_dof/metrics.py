"""Metrics of one 6-DoF docking contact: CoR along the normal, energy, peaks."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["CAPTURE_SPEED_RATIO", "ENERGY_MATCH_TOLERANCE", "DockingMetrics", "docking_metrics"]

#: A docking whose energy ratio is within this of the ideal rig's (no delay,
#: an ideal table) is energy-honest: the rig returned the energy the contact
#: alone would have.
ENERGY_MATCH_TOLERANCE = 0.02

#: A port that ends touching the target is at rest against it (captured) when
#: its speed along the docking axis is at most this fraction of its approach
#: speed; faster, the contact was cut, or neither separates nor settles.
CAPTURE_SPEED_RATIO = 0.05


@dataclass(frozen=True)
class DockingMetrics:
    """Metrics of the first contact of a 6-DoF run.

    Attributes
    ----------
    cor_normal : float
        ``|v_out| / |v_in|`` of the docking port's velocity along the contact
        normal (the docking axis z) [1].
    v_in_m_per_s, v_out_m_per_s : float
        That velocity at the last tick before the model first felt a wrench,
        and just after the last wrench it felt (at separation: a turning
        body's port keeps changing its normal velocity afterwards).
    energy_ratio : float
        Kinetic energy (translation and rotation) of the spacecraft model at
        the end over before the contact [1].
    energy_gain_j : float
        The same as a difference (J; > 0: the loop created energy).
    rotational_energy_j : float
        Rotational kinetic energy at the end (J): how much of the motion the
        contact turned into tumbling.
    peak_force_n, peak_moment_n_m : float
        Largest norm of the actual contact force, and of its moment about the
        port origin.
    contact_duration_s : float
        Time the devices touched (ticks with a contact force times the tick).
    lateral_velocity_m_per_s : float
        Norm of the port's velocity across the docking axis at the end.
    peak_compensated_force_n : float
        Largest norm of the force the compensator fed the model: above the
        contact's peak, the compensator itself pushes the model (a stiffness
        model that overshoots off axis).
    lateral_drift_m : float
        How far the port moved across the docking axis from the tick before
        the model first felt a wrench to separation (m): the docking's slide
        across the target.
    captured : bool
        On a plate: the record ends with the devices touching and the port at
        rest against the target: its speed along the docking axis at most
        :data:`CAPTURE_SPEED_RATIO` times its approach speed ``|v_in|``. The
        contact held the spacecraft instead of returning it; CoR and energy
        ratio are then taken at the record's end. (A record of a given
        duration that ends in contact with the port still moving is not a
        capture: it was cut mid-contact.) In a drogue: the probe head's
        centre passed the throat, where the drogue's latches would close
        behind it (they are not modelled: the record goes on until the probe
        has left the mouth or is held in the socket).
    """

    cor_normal: float
    v_in_m_per_s: float
    v_out_m_per_s: float
    energy_ratio: float
    energy_gain_j: float
    rotational_energy_j: float
    peak_force_n: float
    peak_moment_n_m: float
    contact_duration_s: float
    lateral_velocity_m_per_s: float
    peak_compensated_force_n: float = 0.0
    lateral_drift_m: float = 0.0
    captured: bool = False

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @property
    def spin_note(self) -> str | None:
        """Words on a CoR along the normal that the body's spin makes: the
        port's normal velocity exceeds what the kinetic energy after the
        contact allows a translating body (``CoR^2 <= energy ratio`` without
        spin, the approach being a pure translation), so the CoR describes the
        port's swing, not the bounce. ``None`` otherwise."""
        bound = math.sqrt(max(self.energy_ratio, 0.0))
        if not self.cor_normal > 1.05 * bound:
            return None
        return (
            f"cor_normal {self.cor_normal:.4g} is the port's normal velocity, which the body's "
            f"spin makes after the contact: a translating body with the energy left (energy "
            f"ratio {self.energy_ratio:.4g}) leaves at most at CoR {bound:.4g}"
        )


def docking_metrics(
    time_s: np.ndarray,
    port_velocity_m_per_s: np.ndarray,
    kinetic_energy_j: np.ndarray,
    rotational_energy_j: np.ndarray,
    contact_wrench: np.ndarray,
    compensated_wrench: np.ndarray,
    port_position_m: np.ndarray | None = None,
    captured: bool | None = None,
) -> DockingMetrics:
    """Metrics of the first contact in a record (arrays over the ticks;
    velocities and positions (N, 3), wrenches (N, 6); without the port's
    positions the lateral drift is NaN). ``captured``: the target's own
    capture test, when it has one (a drogue's: the probe passed its throat);
    None: the port at rest against the target at the end (see
    :attr:`DockingMetrics.captured`).

    Raises
    ------
    ValueError
        If the devices never touched or the model never felt the contact.
    """
    t = np.asarray(time_s, dtype=float)
    force = np.linalg.norm(contact_wrench[:, 3:], axis=1)
    moment = np.linalg.norm(contact_wrench[:, :3], axis=1)
    felt = np.flatnonzero(np.any(compensated_wrench != 0.0, axis=1))
    if not (force > 0).any():
        raise ValueError("no contact in this record: the devices never touched")
    if felt.size == 0:
        raise ValueError("the model never felt the contact: the compensated wrench stayed 0")
    i_in = max(int(felt[0]) - 1, 0)
    v_in = float(port_velocity_m_per_s[i_in, 2])
    # A turning body's port keeps changing its normal velocity after the
    # contact: take it at separation, just after the last wrench the model felt.
    i_out = min(int(felt[-1]) + 1, len(t) - 1)
    v_out = float(port_velocity_m_per_s[i_out, 2])
    e_in = float(kinetic_energy_j[i_in])
    e_out = float(kinetic_energy_j[-1])
    h = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    drift = math.nan
    if port_position_m is not None:
        drift = float(np.linalg.norm(port_position_m[i_out, :2] - port_position_m[i_in, :2]))
    return DockingMetrics(
        cor_normal=abs(v_out) / abs(v_in),
        v_in_m_per_s=v_in,
        v_out_m_per_s=v_out,
        energy_ratio=e_out / e_in,
        energy_gain_j=e_out - e_in,
        rotational_energy_j=float(rotational_energy_j[-1]),
        peak_force_n=float(force.max()),
        peak_moment_n_m=float(moment.max()),
        contact_duration_s=float(np.count_nonzero(force > 0) * h),
        lateral_velocity_m_per_s=float(np.linalg.norm(port_velocity_m_per_s[-1, :2])),
        peak_compensated_force_n=float(np.linalg.norm(compensated_wrench[:, 3:], axis=1).max()),
        lateral_drift_m=drift,
        captured=(
            bool(force[-1] > 0.0)
            and abs(float(port_velocity_m_per_s[-1, 2])) <= CAPTURE_SPEED_RATIO * abs(v_in)
        )
        if captured is None
        else bool(captured),
    )
