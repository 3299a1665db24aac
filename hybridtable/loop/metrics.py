"""Contact metrics of a run: CoR, contact duration, peak force, energy gained and created."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["ContactMetrics", "contact_metrics", "contact_intervals"]


@dataclass(frozen=True)
class ContactMetrics:
    """Metrics of one contact (one bounce).

    Attributes
    ----------
    cor : float
        Coefficient of restitution |v_out| / |v_in| of the spacecraft model.
    v_in_m_per_s, v_out_m_per_s : float
        Spacecraft velocity before and after the contact.
    contact_duration_s : float
        Time the physical contact force was non-zero.
    peak_force_n : float
        Largest actual contact force.
    peak_compensated_force_n : float
        Largest force fed to the spacecraft model.
    energy_gain_j : float
        Kinetic energy of the spacecraft model after minus before the contact
        (positive: the loop created energy).
    energy_created : float
        The largest excess of the spacecraft model's kinetic energy over its
        value before the contact, at any sample of the record, relative to it
        [1] (> 0: the loop created energy at some instant, even if it took it
        back; a passive contact never does).
    """

    cor: float
    v_in_m_per_s: float
    v_out_m_per_s: float
    contact_duration_s: float
    peak_force_n: float
    peak_compensated_force_n: float
    energy_gain_j: float
    energy_created: float = 0.0

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def contact_intervals(time_s: np.ndarray, active: np.ndarray) -> list[tuple[float, float]]:
    """Start and end times of the runs of ``active`` samples."""
    active = np.asarray(active, dtype=bool)
    if not active.any():
        return []
    edges = np.diff(np.concatenate([[0], active.astype(int), [0]]))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return [(float(time_s[a]), float(time_s[b])) for a, b in zip(starts, ends, strict=True)]


def contact_metrics(
    time_s: np.ndarray,
    velocity_m_per_s: np.ndarray,
    f_act_n: np.ndarray,
    f_comp_n: np.ndarray,
    mass_kg: float,
) -> ContactMetrics:
    """Metrics of the first contact in a run.

    ``v_in`` is the spacecraft velocity at the last sample before the model
    first felt a force; ``v_out`` the velocity at the end of the record, which
    must come after the force has ended.

    Raises
    ------
    ValueError
        If the record holds no contact force.
    """
    t = np.asarray(time_s, dtype=float)
    v = np.asarray(velocity_m_per_s, dtype=float)
    f_act = np.asarray(f_act_n, dtype=float)
    f_comp = np.asarray(f_comp_n, dtype=float)
    model_force = np.flatnonzero(f_comp != 0.0)
    if not (f_act > 0).any():
        raise ValueError("no contact in this record: the devices never touched")
    if model_force.size == 0:
        raise ValueError("the model never felt the contact: the compensated force stayed 0")
    i_in = max(model_force[0] - 1, 0)
    v_in = float(v[i_in])
    v_out = float(v[-1])
    dt = np.diff(t)
    # Duration: sum of the steps over which the contact force was on (a
    # step counts half when on at only one end; exact for a linear crossing).
    on = (f_act > 0).astype(float)
    duration = float(np.sum(dt * 0.5 * (on[:-1] + on[1:])))
    return ContactMetrics(
        cor=abs(v_out) / abs(v_in),
        v_in_m_per_s=v_in,
        v_out_m_per_s=v_out,
        contact_duration_s=duration,
        peak_force_n=float(f_act.max()),
        peak_compensated_force_n=float(f_comp.max()),
        energy_gain_j=0.5 * mass_kg * (v_out**2 - v_in**2),
        energy_created=max(0.0, float(np.max(v * v)) - v_in**2) / v_in**2,
    )
