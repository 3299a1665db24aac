"""An independent simulation of a hybrid-simulation rig, for test data.

Plain Python and numpy, no Drake: the rig computer of ``hybridtable-run/1``
(read, compensate, semi-implicit Euler, send) at the sample rate, and between
ticks the second-order table integrated by fixed-step classical Runge-Kutta 4
with ``substeps`` steps per tick (the model under test uses Drake's adaptive
RK3). The contact is any function ``f(p, v)``, so a run can hold a physical
effect the model lacks; the readings carry Gaussian noise, which the rig
computer uses, as a real one would.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

NOMINAL = {
    "format": "hybridtable-run/1",
    "run_id": "synthetic",
    "sample_rate_hz": 1000,
    "spacecraft_mass_kg": 675.475,
    "contact_stiffness_n_per_m": 60000.0,
    "sensor_delay_s": 0.004,
    "table_natural_frequency_hz": 30.0,
    "table_damping_ratio": 0.7,
    "compensator": "SDMDC",
    "lead_time_s": 0.004,
    "initial_gap_m": 0.002,
    "initial_velocity_m_per_s": 0.08,
    "force_deadband_n": 6.0,
}


def compensate(info: dict, f_read: float, f_prev: float, p_read: float, cmd_prev: float) -> float:
    """The rig computer's compensated force at one tick, as
    ``docs/run-format.md`` defines it (written out independently of the
    package's Compensator)."""
    if f_read <= info["force_deadband_n"]:
        return 0.0
    h = 1.0 / info["sample_rate_hz"]
    f_comp = f_read
    if info["compensator"] in ("SDC", "SDMDC"):
        f_comp += info["lead_time_s"] * (f_read - f_prev) / h
    if info["compensator"] in ("MDC", "SDMDC"):
        f_comp += info["contact_stiffness_n_per_m"] * (cmd_prev - p_read)
    return max(f_comp, 0.0)


def spring(k: float) -> Callable[[float, float], float]:
    """The nominal unilateral spring."""
    return lambda p, v: k * p if p > 0.0 else 0.0


def damped_spring(k: float, c: float) -> Callable[[float, float], float]:
    """Unilateral spring with viscous damping (never pulls)."""

    def f(p: float, v: float) -> float:
        return max(k * p + c * v, 0.0) if p > 0.0 else 0.0

    return f


def simulate_record(
    info: dict,
    contact: Callable[[float, float], float] | None = None,
    duration_s: float = 0.9,
    noise_f_n: float = 2.0,
    noise_p_m: float = 2e-6,
    substeps: int = 40,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """Columns of one run of the rig with the nominal parameters ``info`` and
    the true contact ``contact(p, v)`` (default: the nominal spring)."""
    rng = np.random.default_rng(seed)
    h = 1.0 / info["sample_rate_hz"]
    m = info["spacecraft_mass_kg"]
    k_nom = info["contact_stiffness_n_per_m"]
    delay = round(info["sensor_delay_s"] / h)
    w = 2.0 * math.pi * info["table_natural_frequency_hz"]
    z = info["table_damping_ratio"]
    contact = contact or spring(k_nom)

    x, v = -info["initial_gap_m"], info["initial_velocity_m_per_s"]
    p, pv = x, v  # table starts at the command, moving with the approach velocity
    cmd_prev, f_prev = x, 0.0
    n = int(round(duration_s / h)) + 1
    f_true = np.zeros(n)
    rows = np.zeros((n, 6))
    dt = h / substeps

    def deriv(p_: float, v_: float, cmd: float) -> tuple[float, float]:
        return v_, w * w * (cmd - p_) - 2.0 * z * w * v_

    for i in range(n):
        f_true[i] = contact(p, pv)
        p_read = p + noise_p_m * rng.standard_normal()
        f_read = (f_true[i - delay] if i >= delay else 0.0) + noise_f_n * rng.standard_normal()
        f_comp = compensate(info, f_read, f_prev, p_read, cmd_prev)
        v -= f_comp / m * h
        x += v * h
        rows[i] = (i * h, x, p_read, f_read, f_comp, v)
        for _ in range(substeps):  # classical RK4, command held
            k1 = deriv(p, pv, x)
            k2 = deriv(p + 0.5 * dt * k1[0], pv + 0.5 * dt * k1[1], x)
            k3 = deriv(p + 0.5 * dt * k2[0], pv + 0.5 * dt * k2[1], x)
            k4 = deriv(p + dt * k3[0], pv + dt * k3[1], x)
            p += dt / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            pv += dt / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        cmd_prev, f_prev = x, f_read
    names = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")
    out = {name: rows[:, j] for j, name in enumerate(names)}
    out["f_act_n"] = f_true
    return out


def write_run(folder: Path, stem: str, info: dict, columns: dict[str, np.ndarray]) -> Path:
    """Write ``stem.csv`` and ``stem.json`` in the format; returns the CSV path."""
    folder.mkdir(parents=True, exist_ok=True)
    names = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")
    lines = [",".join(names)]
    for row in zip(*(columns[c] for c in names), strict=True):
        lines.append(",".join(f"{x:.10g}" for x in row))
    csv_path = folder / f"{stem}.csv"
    csv_path.write_text("\n".join(lines) + "\n")
    (folder / f"{stem}.json").write_text(json.dumps(info, indent=2) + "\n")
    return csv_path
