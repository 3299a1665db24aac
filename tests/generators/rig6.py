"""An independent 6-DoF hybrid docking loop, for test data and cross-checks.

Plain numpy, no Drake and nothing from :mod:`hybridtable`: a rigid spacecraft
whose docking port carries a ring of ``N`` spherical pads pressed against the
flat target face z = 0, an ideal or second-order motion table (exact
zero-order-hold update per tick), a sensor delay of whole ticks and the
compensators none / SDC / MDC / SDMDC, where the MDC stiffness ``K = -dw/dq``
(and damping ``C = -dw/dqd``) comes from central finite differences of this
module's own wrench function at the table's actual pose.

Conventions: pose ``q = [p_P; theta]`` (port position, rotation vector), rate
``qd = [v_P; omega]`` (world frame), wrench ``w = [moment about the port origin;
force]`` on the chaser. Row k of every array is tick k: what the rig computer
read and computed, and the spacecraft state after its update (so ``q_des[k]``
is the command the table follows over the next tick).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

__all__ = ["log_so3", "exp_so3", "pad_ring", "wrench", "wrench_jacobians", "simulate_rig6"]

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")


def exp_so3(theta: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``theta`` [rad] (Rodrigues)."""
    x, y, z = theta
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:  # series, exact to double precision below 1e-6 rad
        s, c = 1.0 - a2 / 6.0, 0.5 - a2 / 24.0
    else:
        a = math.sqrt(a2)
        s, c = math.sin(a) / a, (1.0 - math.cos(a)) / a2
    hat = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * hat + c * (hat @ hat)


def log_so3(rot: np.ndarray) -> np.ndarray:
    """Rotation vector [rad] of the rotation matrix ``rot`` (angle below pi)."""
    w = 0.5 * np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    sin_a = math.sqrt(w @ w)
    angle = math.atan2(sin_a, 0.5 * (np.trace(rot) - 1.0))
    return w * (angle / sin_a if sin_a > 1e-12 else 1.0 + angle * angle / 6.0)


def pad_ring(pad_count: int, ring_radius_m: float, pad_radius_m: float) -> np.ndarray:
    """Pad centres in the port frame, ``(N, 3)`` [m]: a ring whose tops lie in z_P = 0."""
    phi = 2.0 * np.pi * np.arange(pad_count) / pad_count
    z = np.full(pad_count, -pad_radius_m)
    return np.column_stack([ring_radius_m * np.cos(phi), ring_radius_m * np.sin(phi), z])


def wrench(q, qd, pads, k_pad_n_per_m, d_s_per_m=0.0, pad_radius_m=0.01):
    """Contact wrench on the chaser at the port origin, and the pad penetrations.

    Parameters
    ----------
    q, qd : array (6,)
        Port pose ``[p_P (m); theta (rad)]`` and rate ``[v_P (m/s); omega (rad/s)]``.
    pads : array (N, 3)
        Pad centres in the port frame [m].
    k_pad_n_per_m, d_s_per_m, pad_radius_m : float
        Stiffness of one pad [N/m], Hunt-Crossley dissipation [s/m], pad radius [m].

    Returns
    -------
    w : array (6,)
        ``[moment (N m); force (N)]``.
    delta : array (N,)
        Penetration of each pad [m] (in contact where > 0).
    """
    b = pads @ exp_so3(q[3:]).T  # lever arms from the port origin, world frame
    delta = q[2] + b[:, 2] + pad_radius_m
    on = delta > 0.0
    fz = np.zeros(len(b))
    if on.any():
        om = qd[3:]
        rate = qd[2] + om[0] * b[on, 1] - om[1] * b[on, 0]  # (v_P + omega x b)_z
        fz[on] = -k_pad_n_per_m * delta[on] * np.maximum(1.0 + d_s_per_m * rate, 0.0)
    w = np.array([b[:, 1] @ fz, -(b[:, 0] @ fz), 0.0, 0.0, 0.0, fz.sum()])
    return w, delta


def wrench_jacobians(q, qd, *args, step=1e-7, damped=False):
    """``K = -dw/dq`` and ``C = -dw/dqd`` (6x6) by central differences of :func:`wrench`.

    ``args`` are those of :func:`wrench` after ``q, qd``; ``C`` is zero unless ``damped``.
    """
    jac = []
    for x, other, first in ((q, qd, True), (qd, q, False)):
        cols = []
        for j in range(6 if (first or damped) else 0):
            e = np.zeros(6)
            e[j] = step
            plus = wrench(*((x + e, other) if first else (other, x + e)), *args)[0]
            minus = wrench(*((x - e, other) if first else (other, x - e)), *args)[0]
            cols.append(-(plus - minus) / (2.0 * step))
        jac.append(np.column_stack(cols) if cols else np.zeros((6, 6)))
    return jac[0], jac[1]


def _table_update(freq_hz: float, zeta: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """``Phi`` (2x2) and ``Gamma`` (2,) of one tick of ``x'' = w^2 (u - x) - 2 zeta w x'``."""
    w = 2.0 * math.pi * freq_hz
    e = expm(np.array([[0.0, 1.0, 0.0], [-w * w, -2.0 * zeta * w, w * w], [0.0, 0.0, 0.0]]) * h)
    return e[:2, :2], e[:2, 2]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def simulate_rig6(
    *,
    mass_kg: float = 2533.03,
    inertia_kg_m2=(1689.0, 1689.0, 1689.0),
    port_distance_m: float = 1.5,
    lateral_offset_m=(0.0, 0.0),
    misalignment_rad=(0.0, 0.0),
    contact_stiffness_n_per_m: float = 1e5,
    hunt_crossley_dissipation_s_per_m: float = 0.0,
    pad_count: int = 8,
    ring_radius_m: float = 0.3,
    pad_radius_m: float = 0.01,
    table_response_hz: float = math.inf,
    table_damping_ratio: float = 0.8,
    sample_rate_hz: float = 1000.0,
    sensor_delay_s: float = 0.0,
    compensator: str = "none",
    lead_time_s: float | None = None,
    force_deadband_n: float = 0.0,
    initial_velocity_m_per_s: float = 0.1,
    initial_gap_m: float = 0.001,
    duration_s: float | None = None,
    fd_step: float = 1e-7,
) -> dict:
    """One contact of the 6-DoF hybrid docking loop (SI units throughout).

    ``misalignment_rad = (roll, pitch)`` gives the initial attitude
    ``Ry(pitch) Rx(roll)``; the port starts on the docking axis, ``initial_gap_m``
    from the plane (measured at the pad nearest to it), moving at
    ``initial_velocity_m_per_s`` along +z, with no angular velocity.
    ``duration_s=None`` stops 0.05 s after the contact ends.

    Returns
    -------
    dict
        Arrays (one row per tick): ``t_s``, ``port_velocity_z_m_per_s``,
        ``kinetic_energy_j``, ``total_energy_j``, ``wrench_act`` and
        ``wrench_comp`` (N, 6), ``q_des`` and ``q_act`` (N, 6),
        ``com_position_m`` (N, 3), ``angular_momentum_n_m_s`` (N, 3, world frame,
        about the centre of mass); scalars ``cor_normal``, ``energy_ratio``,
        ``peak_force_n``, ``peak_moment_n_m``, ``contact_duration_s``.

    Raises
    ------
    ValueError
        If the sensor delay is not a whole number of ticks or the compensator is unknown.
    RuntimeError
        If no contact happens or it does not end within the default duration.
    """
    if compensator not in COMPENSATORS:
        raise ValueError(f"compensator must be one of {COMPENSATORS}, not {compensator!r}")
    h = 1.0 / sample_rate_hz
    delay = sensor_delay_s * sample_rate_hz
    n_delay = round(delay)
    if abs(delay - n_delay) > 1e-9 * max(1.0, delay):
        raise ValueError(f"sensor_delay_s {sensor_delay_s} is not a whole number of ticks of {h} s")
    lead = sensor_delay_s if lead_time_s is None else lead_time_s
    use_sdc, use_mdc = compensator in ("SDC", "SDMDC"), compensator in ("MDC", "SDMDC")
    m = float(mass_kg)
    inertia = np.asarray(inertia_kg_m2, dtype=float)
    inertia = np.diag(inertia) if inertia.ndim == 1 else inertia
    inertia_inv = np.linalg.inv(inertia)
    r_port = np.array([lateral_offset_m[0], lateral_offset_m[1], port_distance_m], dtype=float)
    pads = pad_ring(pad_count, ring_radius_m, pad_radius_m)
    k_pad, d = contact_stiffness_n_per_m / pad_count, hunt_crossley_dissipation_s_per_m
    args = (pads, k_pad, d, pad_radius_m)

    # initial state: the nearest pad top `initial_gap_m` from the plane, port on the axis
    roll, pitch = misalignment_rad
    rot = exp_so3(np.array([0.0, pitch, 0.0])) @ exp_so3(np.array([roll, 0.0, 0.0]))
    v0 = float(initial_velocity_m_per_s)
    z_port = -initial_gap_m - pad_radius_m - (pads @ rot.T)[:, 2].max()
    p = np.array([0.0, 0.0, z_port]) - rot @ r_port
    v = np.array([0.0, 0.0, v0])
    om_b = np.zeros(3)
    q_cmd = np.concatenate([p + rot @ r_port, log_so3(rot)])
    qd_cmd = np.concatenate([v, np.zeros(3)])

    ideal = math.isinf(table_response_hz)
    if not ideal:  # steady tracking of the approach ramp, held at tick -1
        phi, gam = _table_update(table_response_hz, table_damping_ratio, h)
        lag_s = 2.0 * table_damping_ratio / (2.0 * math.pi * table_response_hz)
        x_tab, xd_tab = q_cmd - lag_s * qd_cmd, qd_cmd.copy()

    t_contact = math.pi * math.sqrt(m / contact_stiffness_n_per_m)
    t_max = duration_s if duration_s is not None else initial_gap_m / v0 + 10 * t_contact + 1.0
    n_max = int(round(t_max / h)) + 1
    hold_ticks = int(math.ceil(0.05 / h))
    names = ("q_act", "q_des", "wrench_act", "wrench_comp", "port_velocity_z_m_per_s")
    names += ("kinetic_energy_j", "total_energy_j", "com_position_m", "angular_momentum_n_m_s")
    rows: dict[str, list] = {name: [] for name in names}
    in_contact = []
    history = np.zeros((n_delay + n_max, 6))  # history[k + n_delay] = w_act[k]
    w_prev = np.zeros(6)
    quiet, touched = 0, False
    for k in range(n_max):
        # 1. the table's pose under the command sent at tick k-1, and the contact wrench
        if ideal:
            q_act, qd_act = q_cmd, qd_cmd
        else:
            x_tab, xd_tab = (
                phi[0, 0] * x_tab + phi[0, 1] * xd_tab + gam[0] * q_cmd,
                phi[1, 0] * x_tab + phi[1, 1] * xd_tab + gam[1] * q_cmd,
            )
            q_act, qd_act = x_tab, xd_tab
        w_act, delta = wrench(q_act, qd_act, *args)
        history[k + n_delay] = w_act
        # 2. the sensor, 3. the compensator
        w_mea = history[k]
        w_c = np.zeros(6)
        if np.linalg.norm(w_mea[3:]) > force_deadband_n:
            w_c = w_mea.copy()
            if use_sdc:
                w_c += lead * (w_mea - w_prev) / h
            if use_mdc:
                K, C = wrench_jacobians(q_act, qd_act, *args, step=fd_step, damped=d > 0.0)
                w_c -= K @ (q_cmd - q_act) + C @ (qd_cmd - qd_act)
        w_prev = w_mea
        # 4. the spacecraft: semi-implicit Euler; its new port pose and rate are the command
        f = w_c[3:]
        tau = w_c[:3] + _cross(rot @ r_port, f)
        v = v + h * f / m
        p = p + h * v
        om_b = om_b + h * (inertia_inv @ (rot.T @ tau - _cross(om_b, inertia @ om_b)))
        rot = rot @ exp_so3(h * om_b)
        lever, om_w = rot @ r_port, rot @ om_b
        q_cmd = np.concatenate([p + lever, log_so3(rot)])
        qd_cmd = np.concatenate([v + _cross(om_w, lever), om_w])
        ke = 0.5 * m * (v @ v) + 0.5 * om_b @ inertia @ om_b
        own = wrench(q_cmd, qd_cmd, *args)[1]  # penetrations at the spacecraft's own pose
        pe = 0.5 * k_pad * np.sum(np.maximum(own, 0.0) ** 2)
        row = (q_act, q_cmd, w_act, w_c, qd_cmd[2], ke, ke + pe, p, rot @ inertia @ om_b)
        for name, value in zip(names, row, strict=True):
            rows[name].append(value)
        in_contact.append(bool((delta > 0.0).any()))
        touched = touched or in_contact[-1]
        busy = in_contact[-1] or w_c.any() or history[k + 1 : k + n_delay + 1].any()
        quiet = 0 if busy else quiet + 1
        if duration_s is None and touched and quiet >= hold_ticks:
            break
    else:
        if duration_s is None:
            raise RuntimeError(f"the contact did not end within {t_max:.3g} s")
    out = {name: np.array(rows[name]) for name in names}
    out["t_s"] = h * np.arange(len(in_contact))
    return out | _metrics(out, np.array(in_contact), h, v0, 0.5 * m * v0 * v0)


def _metrics(out: dict, in_contact: np.ndarray, h: float, v0: float, ke0: float) -> dict:
    """CoR, energy ratio (both against the last tick before the model felt a wrench),
    peak force and moment of w_act, contact time."""
    pushed = np.flatnonzero(np.any(out["wrench_comp"] != 0.0, axis=1))
    if not len(pushed) or not in_contact.any():
        raise RuntimeError("no contact happened")
    j = pushed[0] - 1  # the last tick before the compensated wrench is first non-zero
    v_in = out["port_velocity_z_m_per_s"][j] if j >= 0 else v0
    ke = out["kinetic_energy_j"]
    ke_in = ke[j] if j >= 0 else ke0
    w = out["wrench_act"]
    # The port's normal velocity keeps changing after the contact while the
    # body turns: take it just after the last wrench the model felt.
    v_out = out["port_velocity_z_m_per_s"][pushed[-1]]
    return {
        "cor_normal": abs(v_out) / abs(v_in),
        "energy_ratio": ke[-1] / ke_in,
        "peak_force_n": float(np.linalg.norm(w[:, 3:], axis=1).max()),
        "peak_moment_n_m": float(np.linalg.norm(w[:, :3], axis=1).max()),
        "contact_duration_s": float(in_contact.sum() * h),
    }
