"""Runs of a rig with a hidden physical effect, for the diagnose tests.

Plain Python and numpy, no Drake, independent of the model under test: the
rig computer of ``hybridtable-run/1`` at the sample rate and, between ticks,
the table (with an optional structural mode), a continuous force sensor
filter and the contact integrated by fixed-step classical Runge-Kutta 4 with
``substeps`` steps per tick (the model uses Drake's adaptive RK3 and a
first-order-hold filter). The contact law is evaluated as written (exact
``sign`` for friction, an implicit equation solved by bisection for a series
compliance), a fractional sensor delay is read from the force history at the
substep resolution, and the readings carry white or AR(1) noise of a given
marginal standard deviation.

``HIDDEN`` lists each effect with a default size (``sensor_gain`` stands for
an effect a user registers); ``"a+b"`` hides two effects at once (at most one
changing the elastic law); :func:`make_runs` writes a set of runs (two or
three approach velocities).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hybridtable.measurement.run_reader import read_run
from tests.generators.rigsim import NOMINAL, compensate, write_run

#: Hidden effects and their default sizes (the generator's own parameters).
HIDDEN: dict[str, dict[str, float]] = {
    "none": {},
    "contact_damping": {"c": 400.0},
    "hunt_crossley": {"alpha": 3.0},
    "nonlinear_stiffness": {"n": 1.3, "k_at_ref": 60000.0, "d_ref": 0.006},
    "stiffness_error": {"k": 52000.0},
    "series_compliance": {"s": 2.0e-6},
    "coulomb_friction": {"F": 15.0},
    "sensor_filter": {"tau": 0.002},
    "extra_delay": {"d": 0.0015},
    "table_resonance": {"f": 70.0, "zeta": 0.04},
    "force_bias": {"b": -4.0},
    "mass_error": {"ratio": 1.05},
    "sensor_gain": {"g": 1.06},
}


def _contact_law(info: dict, effects: set[str], size: dict[str, float]):
    k = info["contact_stiffness_n_per_m"]

    def law(p: float, v: float) -> float:
        if p <= 0.0:
            return 0.0
        if "nonlinear_stiffness" in effects:
            kk = size["k_at_ref"] * size["d_ref"] ** (1.0 - size["n"])
            f = kk * p ** size["n"]
        elif "stiffness_error" in effects:
            f = size["k"] * p
        elif "series_compliance" in effects:
            # f = k (p - s f) by bisection (not the closed form)
            lo, hi = 0.0, k * p
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                if mid - k * (p - size["s"] * mid) > 0.0:
                    hi = mid
                else:
                    lo = mid
            f = 0.5 * (lo + hi)
        else:
            f = k * p
        if "hunt_crossley" in effects:
            f *= 1.0 + size["alpha"] * v
        if "contact_damping" in effects:
            f += size["c"] * v
        if "coulomb_friction" in effects:
            f += size["F"] * (1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0)
        return max(f, 0.0)

    return law


def _noise(rng, n: int, sigma: float, phi: float) -> np.ndarray:
    """AR(1) noise with marginal standard deviation ``sigma`` (white if phi = 0)."""
    xi = rng.standard_normal(n)
    e = np.empty(n)
    e[0] = sigma * xi[0]
    s = sigma * math.sqrt(1.0 - phi * phi)
    for i in range(1, n):
        e[i] = phi * e[i - 1] + s * xi[i]
    return e


def simulate_hidden(
    info: dict,
    effect: str = "none",
    size: dict[str, float] | None = None,
    duration_s: float = 0.7,
    noise_f_n: float = 2.0,
    noise_p_m: float = 2e-6,
    noise_phi: float = 0.0,
    substeps: int = 20,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """Columns of one run of a rig with nominal parameters ``info`` whose
    physics holds ``effect`` of ``size`` (default: ``HIDDEN[effect]``)."""
    effects = set(effect.split("+"))
    if not effects <= set(HIDDEN):
        raise ValueError(f"unknown hidden effect {effect!r}")
    merged: dict[str, float] = {}
    for e in effects:
        merged.update(HIDDEN[e])
    size = dict(merged, **(size or {}))
    rng = np.random.default_rng(seed)
    h = 1.0 / info["sample_rate_hz"]
    n = int(round(duration_s / h)) + 1
    noise_f = _noise(rng, n, noise_f_n, noise_phi)
    noise_p = _noise(rng, n, noise_p_m, noise_phi)
    m_json = info["spacecraft_mass_kg"]
    m = m_json * (size["ratio"] if "mass_error" in effects else 1.0)
    delay = info["sensor_delay_s"] + (size["d"] if "extra_delay" in effects else 0.0)
    w = 2.0 * math.pi * info["table_natural_frequency_hz"]
    z = info["table_damping_ratio"]
    mode = "table_resonance" in effects
    wr = 2.0 * math.pi * size.get("f", 1.0)
    zr = size.get("zeta", 0.0)
    tau = size["tau"] if "sensor_filter" in effects else 0.0
    bias = size["b"] if "force_bias" in effects else 0.0
    gain = size["g"] if "sensor_gain" in effects else 1.0
    law = _contact_law(info, effects, size)

    x, v = -info["initial_gap_m"], info["initial_velocity_m_per_s"]
    # state: servo p, v; mode p, v (= servo without a mode); filter y
    s = np.array([x, v, x, v, 0.0])
    cmd_prev, f_prev = x, 0.0
    dt = h / substeps
    hist_t = [0.0]
    hist_f = [0.0]  # sensor-side force (after the filter) at every substep

    def contact_point(state):
        return (state[2], state[3]) if mode else (state[0], state[1])

    def deriv(state, cmd):
        ps, vs, pm, vm, y = state
        a_s = w * w * (cmd - ps) - 2.0 * z * w * vs
        if mode:
            a_m = wr * wr * (ps - pm) + 2.0 * zr * wr * (vs - vm)
        else:
            a_m = 0.0
        p, pv = contact_point(state)
        f = law(p, pv)
        dy = (f - y) / tau if tau > 0.0 else 0.0
        return np.array([vs, a_s, vm, a_m, dy])

    def sensed(state) -> float:
        if tau > 0.0:
            return state[4]
        return law(*contact_point(state))

    rows = np.zeros((n, 6))
    f_true = np.zeros(n)
    for i in range(n):
        t = i * h
        p, pv = contact_point(s)
        f_true[i] = law(p, pv)
        # reading: the sensed force at t - delay, from the substep history
        td = t - delay
        if td <= 0.0:
            f_sensed = 0.0
        else:
            j = td / dt
            j0 = int(math.floor(j + 1e-9))
            frac = j - j0
            f0 = hist_f[j0]
            f1 = hist_f[min(j0 + 1, len(hist_f) - 1)]
            f_sensed = f0 + (f1 - f0) * (frac if frac > 1e-9 else 0.0)
        p_read = p + noise_p[i]
        f_read = gain * f_sensed + bias + noise_f[i]
        f_comp = compensate(info, f_read, f_prev, p_read, cmd_prev)
        v -= f_comp / m * h
        x += v * h
        rows[i] = (t, x, p_read, f_read, f_comp, v)
        for _ in range(substeps):
            k1 = deriv(s, x)
            k2 = deriv(s + 0.5 * dt * k1, x)
            k3 = deriv(s + 0.5 * dt * k2, x)
            k4 = deriv(s + dt * k3, x)
            s = s + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            hist_t.append(hist_t[-1] + dt)
            hist_f.append(sensed(s))
        cmd_prev, f_prev = x, f_read
    names = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")
    out = {name: rows[:, j] for j, name in enumerate(names)}
    out["f_act_n"] = f_true
    return out


def make_runs(
    folder: Path,
    effect: str = "none",
    size: dict[str, float] | None = None,
    velocities: tuple[float, ...] = (0.05, 0.08, 0.12),
    noise_phi: float = 0.0,
    seed: int = 0,
    compensators: tuple[str, ...] = ("SDMDC", "none", "SDMDC"),
    info: dict | None = None,
    **kwargs,
):
    """Write one run per approach velocity with ``effect`` hidden; returns the Runs."""
    base = dict(info or NOMINAL)
    runs = []
    for i, v0 in enumerate(velocities):
        run_info = dict(
            base,
            run_id=f"{effect}-{i}",
            initial_velocity_m_per_s=v0,
            compensator=compensators[i % len(compensators)],
        )
        cols = simulate_hidden(
            run_info, effect, size, noise_phi=noise_phi, seed=seed * 100 + i, **kwargs
        )
        runs.append(read_run(write_run(Path(folder), run_info["run_id"], run_info, cols)))
    return runs
