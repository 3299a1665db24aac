"""An independent generator of long rig logs holding many contacts, for test data.

Plain Python and numpy, no Drake and nothing of ``hybridtable``: the physics
of :mod:`tests.generators.rigsim` (the rig computer of ``hybridtable-run/1``
at the sample rate, the sensor delay, noisy readings the computer uses, any
contact law ``f(p, v)``) run on for a whole campaign. Every ``period_s``
seconds from t = 0 the operator resets the spacecraft model at a tick to
``x = -gap_i``, ``v = v_i`` (contact ``i``): at that tick the computer's step 3
starts from the reset state instead of the previous one, so the log's only
breaks of the format's arithmetic are the reset ticks. The table is never
reset: it follows the new command with its second-order response.

The table between ticks is rigsim's classical Runge-Kutta 4 with
``substeps`` steps per tick, applied as its exact amplification matrix (the
table is linear and its command held over a tick, so ``substeps`` RK4 steps
are one 2x2 matrix): the same numbers as rigsim's loop to float rounding, a
hundred times faster, which a 1e5-tick log needs.

The reset's command jump is the distance the model flew since the previous
reset: a few mm when the period only just covers the contact and the table's
settling (:func:`shortest_period_s`), but ``|v_out| (period - t_contact)``
otherwise (0.4 m after 5 s at 0.1 m/s). A second-order table with damping
below 1 overshoots a jump that large by ``exp(-pi zeta / sqrt(1 - zeta^2))``
of it (4.6 % at zeta 0.7: about 20 mm), so on such a log the table strikes the
contact before the spacecraft model reaches it; the truth's
``p_des_at_touch_m`` shows it (negative: the model was still apart).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tests.generators.rigsim import compensate, spring, write_run

__all__ = ["shortest_period_s", "simulate_log", "truth", "write_log"]

#: Names of the format's columns, in the CSV's order.
COLUMNS = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")


def _table_step(info: dict, substeps: int) -> tuple[float, float, float, float]:
    """The table's error ``(p - cmd, v)`` over one tick with the command held:
    ``substeps`` classical RK4 steps of ``e' = A e`` as one matrix
    ``R(dt A) ** substeps`` (entries m00, m01, m10, m11)."""
    h_s = 1.0 / info["sample_rate_hz"]
    w_rad_per_s = 2.0 * math.pi * info["table_natural_frequency_hz"]
    z = info["table_damping_ratio"]
    a = np.array([[0.0, 1.0], [-(w_rad_per_s**2), -2.0 * z * w_rad_per_s]]) * (h_s / substeps)
    eye = np.eye(2)
    rk4 = eye + a @ (eye + a @ (eye / 2.0 + a @ (eye / 6.0 + a / 24.0)))
    m = np.linalg.matrix_power(rk4, substeps)
    return float(m[0, 0]), float(m[0, 1]), float(m[1, 0]), float(m[1, 1])


def simulate_log(
    info: dict,
    contacts: list[tuple[float, float]],
    period_s: float,
    contact: Callable[[float, float], float] | None = None,
    noise_f_n: float = 2.0,
    noise_p_m: float = 2e-6,
    seed: int = 0,
    substeps: int = 40,
) -> dict[str, np.ndarray]:
    """One ``hybridtable-run/1`` record of a rig campaign of several contacts.

    Parameters
    ----------
    info : dict
        The rig's nominal parameters (the keys of the format's JSON; its
        ``initial_gap_m`` and ``initial_velocity_m_per_s`` are not used: the
        first contact's are).
    contacts : list of (float, float)
        ``(gap_i [m], v_i [m/s])`` of each contact: the model's reset state
        ``x = -gap_i``, ``v = v_i`` at ``t = i period_s``.
    period_s : float
        Time between resets [s]; the log holds ``len(contacts) * period_s *
        sample_rate_hz`` ticks (rounded).
    contact : callable, optional
        The true contact force ``f(p [m], v [m/s]) -> [N]`` (default the
        nominal unilateral spring).
    noise_f_n, noise_p_m : float
        Standard deviations of the force [N] and position [m] readings
        (drawn per tick in rigsim's order: position, then force).
    seed : int
        Seed of the noise.
    substeps : int
        RK4 steps of the table per tick.

    Returns
    -------
    dict of str to ndarray
        The six columns of the format, ``f_act_n`` (true force at each tick
        [N]), and the truth per contact: ``reset_ticks``, ``reset_gap_m``,
        ``reset_velocity_m_per_s``, ``contact_start_ticks`` and
        ``contact_end_ticks`` (first and last tick with a true force > 0),
        ``v_in_m_per_s`` (the model's velocity before the true contact),
        ``v_out_m_per_s`` (after the computer read the contact's last force),
        ``cor`` (``|v_out / v_in|`` [1]), ``reset_jump_m`` (the command's jump
        at the reset [m]) and ``p_des_at_touch_m`` (the model's position when
        the table first touched [m]: >= 0 when the model led the table into the
        contact, < 0 when the table struck first). :func:`truth` makes a
        small JSON-ready dict of them.
    """
    if not contacts:
        raise ValueError("simulate_log needs at least one contact")
    rng = np.random.default_rng(seed)
    h_s = 1.0 / info["sample_rate_hz"]
    mass_kg = info["spacecraft_mass_kg"]
    delay = round(info["sensor_delay_s"] / h_s)
    contact = contact or spring(info["contact_stiffness_n_per_m"])
    m00, m01, m10, m11 = _table_step(info, substeps)
    n = int(round(len(contacts) * period_s / h_s))
    resets = [int(round(i * period_s / h_s)) for i in range(len(contacts))]
    if resets[-1] >= n or len(set(resets)) != len(resets):
        raise ValueError("period_s is shorter than a tick")
    reset_at = dict(zip(resets, contacts, strict=True))

    x, v = -contacts[0][0], contacts[0][1]
    p, pv = x, v  # table starts at the command, moving with the approach velocity (rigsim)
    cmd_prev, f_prev = x, 0.0
    f_true = np.zeros(n)
    rows = np.zeros((n, 6))
    jumps = []
    for i in range(n):
        f_true[i] = contact(p, pv)
        p_read = p + noise_p_m * rng.standard_normal()
        f_read = (f_true[i - delay] if i >= delay else 0.0) + noise_f_n * rng.standard_normal()
        f_comp = compensate(info, f_read, f_prev, p_read, cmd_prev)
        if i in reset_at:  # the operator's reset: step 3 starts from the new state
            jumps.append(abs(x + reset_at[i][0]))
            x, v = -reset_at[i][0], reset_at[i][1]
        v -= f_comp / mass_kg * h_s
        x += v * h_s
        rows[i] = (i * h_s, x, p_read, f_read, f_comp, v)
        e_p = p - x  # the table over one tick, command x held (RK4 as one matrix)
        p, pv = x + m00 * e_p + m01 * pv, m10 * e_p + m11 * pv
        cmd_prev, f_prev = x, f_read
    out = {name: rows[:, j].copy() for j, name in enumerate(COLUMNS)}
    out["f_act_n"] = f_true
    out.update(_truth_arrays(out, resets, contacts, delay))
    out["reset_jump_m"] = np.array(jumps)
    return out


def _truth_arrays(
    cols: dict[str, np.ndarray], resets: list[int], contacts: list, delay: int
) -> dict[str, np.ndarray]:
    """Per contact: where the true force starts and ends, the model's velocity
    before and after, the CoR and the model's position at the first touch."""
    n = cols["time_s"].size
    v_des = cols["v_des_m_per_s"]
    starts, ends, v_in, v_out, at_touch = [], [], [], [], []
    for a, b in zip(resets, [*resets[1:], n], strict=True):
        touching = np.flatnonzero(cols["f_act_n"][a:b] > 0.0)
        if touching.size == 0:
            starts.append(-1)
            ends.append(-1)
            v_in.append(float(v_des[a]))
            v_out.append(float(v_des[b - 1]))
            at_touch.append(math.nan)
            continue
        c0, c1 = a + int(touching[0]), a + int(touching[-1])
        starts.append(c0)
        ends.append(c1)
        v_in.append(float(v_des[c0 - 1]) if c0 > a else float(v_des[a]))
        v_out.append(float(v_des[min(c1 + delay, b - 1)]))
        # f_act[c0] is the force of the table's state at tick c0, set by the
        # command p_des[c0 - 1] the table followed.
        at_touch.append(float(cols["p_des_m"][max(c0 - 1, 0)]))
    v_in_a, v_out_a = np.array(v_in), np.array(v_out)
    return {
        "reset_ticks": np.array(resets, dtype=int),
        "reset_gap_m": np.array([g for g, _ in contacts], dtype=float),
        "reset_velocity_m_per_s": np.array([u for _, u in contacts], dtype=float),
        "contact_start_ticks": np.array(starts, dtype=int),
        "contact_end_ticks": np.array(ends, dtype=int),
        "v_in_m_per_s": v_in_a,
        "v_out_m_per_s": v_out_a,
        "cor": np.abs(v_out_a / v_in_a),
        "p_des_at_touch_m": np.array(at_touch),
    }


def truth(log: dict[str, np.ndarray]) -> dict:
    """The truth of a log of :func:`simulate_log` as a small JSON-ready dict:
    the reset ticks and, per contact, its reset state, CoR and touch."""
    keys = (
        "reset_gap_m",
        "reset_velocity_m_per_s",
        "cor",
        "v_in_m_per_s",
        "v_out_m_per_s",
        "reset_jump_m",
        "p_des_at_touch_m",
    )
    h_s = float(log["time_s"][1] - log["time_s"][0])
    per_contact = []
    for i, tick in enumerate(log["reset_ticks"]):
        entry = {"reset_tick": int(tick), "reset_time_s": round(int(tick) * h_s, 9)}
        entry.update({key: float(log[key][i]) for key in keys})
        entry["contact_start_tick"] = int(log["contact_start_ticks"][i])
        entry["contact_end_tick"] = int(log["contact_end_ticks"][i])
        per_contact.append(entry)
    return {"reset_ticks": [int(t) for t in log["reset_ticks"]], "contacts": per_contact}


def shortest_period_s(
    info: dict, contacts: list[tuple[float, float]], settle_time_constants: float = 8.0
) -> float:
    """A period [s] that lets every contact of ``contacts`` separate and the
    table settle before the next reset, so the reset's command jump is a few mm.

    The longest approach ``gap / v``, plus the undamped contact's half period
    ``pi sqrt(m / k)`` and the sensor delay, plus ``settle_time_constants``
    decay times ``1 / (zeta omega)`` of the table (after the separation; and
    again for the jump before the next contact, which the caller keeps apart
    by gaps that take that long to close), rounded up to 10 ms.
    """
    mass_kg = info["spacecraft_mass_kg"]
    k_n_per_m = info["contact_stiffness_n_per_m"]
    w_rad_per_s = 2.0 * math.pi * info["table_natural_frequency_hz"]
    decay_s = 1.0 / (info["table_damping_ratio"] * w_rad_per_s)
    approach_s = max(g / u for g, u in contacts)
    t_s = (
        approach_s
        + math.pi * math.sqrt(mass_kg / k_n_per_m)
        + info["sensor_delay_s"]
        + settle_time_constants * decay_s
    )
    return math.ceil(t_s * 100.0) / 100.0


def write_log(folder: Path, stem: str, info: dict, columns: dict[str, np.ndarray]) -> Path:
    """Write ``stem.csv`` and ``stem.json`` (the format's six columns, cells
    ``%.10g``); the JSON is ``info`` with the FIRST contact's
    ``initial_gap_m`` and ``initial_velocity_m_per_s`` (when ``columns`` is a
    log of :func:`simulate_log`) and ``run_id`` = ``stem`` unless given.
    Returns the CSV path."""
    info = dict(info)
    if "reset_gap_m" in columns:
        info["initial_gap_m"] = float(columns["reset_gap_m"][0])
        info["initial_velocity_m_per_s"] = float(columns["reset_velocity_m_per_s"][0])
    info.setdefault("run_id", stem)
    return write_run(Path(folder), stem, info, columns)
