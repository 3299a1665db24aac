"""CoR tables: an independent generator of measured coefficient-of-restitution tables.

Written from the seed paper's loop alone (nothing here imports ``hybridtable``
or the other generators of this folder), to test ``hybridtable explain``: a
table of CoR per compensator and condition, measured on a rig whose TRUE
physics differs from what the lab believes by a hidden effect. Every row
carries the STATED conditions (what the lab believes); its CoR comes from the
TRUE rig.

The loop (one tick of the rig computer, period ``h = 1 / sample_rate_hz``)
--------------------------------------------------------------------------
- **Table**: a second-order servo ``p'' = w^2 (u - p) - 2 zeta w p'`` (``w =
  2 pi f_t``), the command ``u = p_des[k]`` held from tick k to k+1, stepped
  exactly (matrix exponential). ``f_t = inf`` is an ideal table: ``p(t_{k+1})
  = p_des[k]``. At ``t = 0`` the table is in steady tracking of the approach
  (the sampled tracking error of a held ramp, solved exactly), so no start
  transient reaches the contact.
- **Contact**: the other device is fixed at 0; the penetration is the table
  position ``p``; force ``k p`` for ``p > 0`` (plus the hidden contact laws
  below), never pulling.
- **Force sensor**: ``f_mea[k] = f(t_k - D)``, ``D`` whole ticks (0 before t = 0).
- **Rig computer**: ``f_comp = 0`` when ``f_mea <= 0``; otherwise ``f_mea``,
  plus ``L (f_mea[k] - f_mea[k-1]) / h`` (SDC, SDMDC), plus ``k_c (p_des[k-1] -
  p_act[k])`` (MDC, SDMDC; the lab believes the contact has no damper, so the
  MDC has no damping term); not clamped (the paper's loop: after the model
  separates, the compensated force may pull while a force is still read,
  which balances the force the gate misses at onset; ``clamp_nonnegative``
  clamps it at 0 as the run format's computer does, SDMDC then ends at
  1.0046 instead of 1.0000 at Table 1). Then the spacecraft model (mass
  ``m``) by semi-implicit Euler: ``v -= f_comp / m h``, ``x += v h``,
  ``p_des[k] = x``.
- **CoR** ``= -v_out / v_in``: the model's velocity once the contact, the
  delayed reading and the table's transient are over.

Stated conditions (row columns, SI units; missing keys take the paper's Table
1 point :data:`TABLE1`, the lead defaults to the stated delay) and the model
mass ``m = k / (2 pi f_con)^2``. In the nominal loop the CoR depends on
``f_con``, ``D``, ``L``, ``f_t``, ``zeta_t`` and ``h`` only (not on ``k`` at a
given ``f_con``, nor on the velocity: the loop is linear and homogeneous).

Hidden effects (:data:`HIDDEN_EFFECTS`; name -> its parameters)
-----------------------------------------------------------------
In the loop model (what ``explain`` may name):

- ``extra_delay`` {extra_delay_s}: true delay = stated + extra (whole ticks);
  the SDC keeps the stated lead.
- ``lead_time_error`` {lead_time_s}: the lead the SDC actually used.
- ``table_response`` {table_response_hz}: the true table bandwidth (the MDC
  reads the true ``p_act``).
- ``table_damping`` {table_damping_ratio}: the true table damping ratio.
- ``stiffness_error`` {compensator_stiffness_ratio}: the MDC uses ``k ratio``.
- ``contact_frequency_error`` {contact_frequency_ratio}: true ``f_con`` =
  stated ratio (the model is integrated with the mass ``m / ratio^2``).
- ``contact_damping`` {damping_n_s_per_m}: ``f = max(k p + c p', 0)``.
- ``contact_damping_ratio`` {contact_damping_ratio}: the same with ``c = 2 zeta
  sqrt(k m)`` of each row (true ``m``).

Outside the loop model (``explain`` should find them unexplained):

- ``hunt_crossley`` {alpha_s_per_m}: ``f = max(k p (1 + alpha p'), 0)``, a
  damper ``c = alpha k p``: the loss grows with the approach velocity, which
  the loop model's CoR does not depend on.
- ``coulomb_friction`` {friction_n}: ``f = max(k p + F sign(p'), 0)``: the loss
  scales as ``F / (v sqrt(k m))``; a stiffer spring at the same ``f_con``
  (larger peak force) or a faster approach gives a HIGHER CoR.
- ``series_compliance`` {compliance_m_per_n}: a rig compliance ``s`` in series
  with the contact spring, unknown to the lab and to the MDC: the true spring
  is ``k / (1 + k s)``, so the true ``f_con`` falls and the MDC over-corrects,
  both by ``k s``: a stiffer spring at the same stated ``f_con`` gives a
  LOWER CoR (the trend of the paper's Table 4). Only with an elastic contact.

Checked (``test_cortable.py``): an ideal loop keeps CoR 1 within 1e-8 at 1
kHz; ln CoR grows with the delay at 0.99996 pi^2 f_con (10 kHz); the Table 1
point gives 1.1606 / 1.1052 / 1.0503 / 1.0001 at 10 kHz (paper 1.1611 / 1.1057
/ 1.0508 / 0.9999); the compensator interaction of every loop effect is below
3e-4; clamped, it agrees with ``rigzoo`` (run format computer) within 1.5e-5.
A 4-row table takes about 1 ms at 1 kHz, 9 ms at 10 kHz.

Several effects may be hidden at once (``hidden`` holds several names), except
``series_compliance`` with another contact law.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

__all__ = [
    "COLUMNS",
    "COMPENSATORS",
    "CONDITION_KEYS",
    "HIDDEN_EFFECTS",
    "LOOP_EFFECTS",
    "OUTSIDE_EFFECTS",
    "TABLE1",
    "TrueRig",
    "first_order_ln_cor",
    "make_table",
    "simulate_cor",
    "table_lag_s",
    "true_rig",
    "write_csv",
]

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")
#: The table's columns, in the CSV's order.
COLUMNS = (
    "compensator",
    "cor",
    "cor_std",
    "contact_stiffness_n_per_m",
    "contact_frequency_hz",
    "initial_velocity_m_per_s",
    "sensor_delay_s",
    "lead_time_s",
    "table_response_hz",
    "sample_rate_hz",
    "table_damping_ratio",
)
#: Keys a condition may hold (the stated conditions).
CONDITION_KEYS = (
    "contact_stiffness_n_per_m",
    "contact_frequency_hz",
    "initial_velocity_m_per_s",
    "sensor_delay_s",
    "lead_time_s",
    "table_response_hz",
    "table_damping_ratio",
    "sample_rate_hz",
)
#: The paper's Table 1 point (the lead equals the delay).
TABLE1 = {
    "contact_stiffness_n_per_m": 1.0e5,
    "contact_frequency_hz": 1.0,
    "initial_velocity_m_per_s": 0.1,
    "sensor_delay_s": 0.005,
    "table_response_hz": 25.0,
    "table_damping_ratio": 0.8,
}
#: Hidden effect -> its parameters (SI units).
HIDDEN_EFFECTS: dict[str, tuple[str, ...]] = {
    "extra_delay": ("extra_delay_s",),
    "lead_time_error": ("lead_time_s",),
    "table_response": ("table_response_hz",),
    "table_damping": ("table_damping_ratio",),
    "stiffness_error": ("compensator_stiffness_ratio",),
    "contact_frequency_error": ("contact_frequency_ratio",),
    "contact_damping": ("damping_n_s_per_m",),
    "contact_damping_ratio": ("contact_damping_ratio",),
    "hunt_crossley": ("alpha_s_per_m",),
    "coulomb_friction": ("friction_n",),
    "series_compliance": ("compliance_m_per_n",),
}
OUTSIDE_EFFECTS = ("hunt_crossley", "coulomb_friction", "series_compliance")
LOOP_EFFECTS = tuple(n for n in HIDDEN_EFFECTS if n not in OUTSIDE_EFFECTS)

_TWO_PI = 2.0 * math.pi
_PHASE = 0.5  # contact onset half a tick after a tick


@dataclass(frozen=True)
class TrueRig:
    """The true physics of one condition (what the CoR is measured on).

    Attributes
    ----------
    sample_rate_hz : float
        Rig computer rate, Hz.
    mass_kg : float
        Mass the computer integrates the spacecraft model with, kg.
    stiffness_n_per_m : float
        True contact spring (after any series compliance), N/m.
    delay_ticks : int
        True force-sensor delay, ticks.
    lead_time_s : float
        Lead the SDC uses, s.
    table_hz, table_zeta : float
        True table natural frequency (Hz, ``inf`` = ideal) and damping ratio.
    compensator_stiffness_n_per_m : float
        Stiffness the MDC uses, N/m.
    damping_n_s_per_m : float
        Contact damper, N s/m.
    alpha_s_per_m : float
        Hunt-Crossley coefficient, s/m.
    friction_n : float
        Coulomb friction force, N.
    clamp_nonnegative : bool
        Clamp the compensated force at 0 (the run format's computer); False:
        the paper's loop, where a compensated force may pull while a force is
        read.
    """

    sample_rate_hz: float
    mass_kg: float
    stiffness_n_per_m: float
    delay_ticks: int
    lead_time_s: float
    table_hz: float
    table_zeta: float
    compensator_stiffness_n_per_m: float
    damping_n_s_per_m: float = 0.0
    alpha_s_per_m: float = 0.0
    friction_n: float = 0.0
    clamp_nonnegative: bool = False

    @property
    def contact_hz(self) -> float:
        """True contact frequency ``sqrt(k / m) / (2 pi)``, Hz."""
        return math.sqrt(self.stiffness_n_per_m / self.mass_kg) / _TWO_PI


def table_lag_s(table_response_hz: float, table_damping_ratio: float) -> float:
    """Ramp-tracking lag of a second-order table, ``2 zeta / (2 pi f_t)``, s (0 if ideal)."""
    if math.isinf(table_response_hz):
        return 0.0
    return 2.0 * table_damping_ratio / (_TWO_PI * table_response_hz)


def first_order_ln_cor(
    compensator: str,
    contact_frequency_hz: float,
    sensor_delay_s: float,
    table_response_hz: float,
    table_damping_ratio: float,
    lead_time_s: float | None = None,
    compensator_stiffness_ratio: float = 1.0,
    contact_damping_ratio: float = 0.0,
) -> float:
    """First-order (continuous-time, small-lag) ln CoR of the loop.

    ``ln CoR ~ pi^2 f_con (D + lag - L [SDC] - r lag [MDC]) - pi zeta_c`` with
    ``lag = 2 zeta_t / (2 pi f_t)`` and ``r`` the MDC's stiffness over the true
    one (the MDC removes ``r`` times the table lag).

    Parameters
    ----------
    compensator : str
        ``none``, ``SDC``, ``MDC`` or ``SDMDC``.
    contact_frequency_hz : float
        True contact frequency, Hz.
    sensor_delay_s : float
        True sensor delay, s.
    table_response_hz, table_damping_ratio : float
        True table natural frequency (Hz) and damping ratio.
    lead_time_s : float, optional
        Lead the SDC uses, s (default: the delay).
    compensator_stiffness_ratio : float
        MDC stiffness over the true stiffness, 1.
    contact_damping_ratio : float
        Contact damping ratio, 1.

    Returns
    -------
    float
        ln CoR, 1.
    """
    if compensator not in COMPENSATORS:
        raise ValueError(f"unknown compensator {compensator!r}")
    lead = sensor_delay_s if lead_time_s is None else lead_time_s
    lag = table_lag_s(table_response_hz, table_damping_ratio)
    eff = sensor_delay_s + lag
    if compensator in ("SDC", "SDMDC"):
        eff -= lead
    if compensator in ("MDC", "SDMDC"):
        eff -= compensator_stiffness_ratio * lag
    return math.pi**2 * contact_frequency_hz * eff - math.pi * contact_damping_ratio


def _ticks(seconds: float, sample_rate_hz: float, what: str) -> int:
    n = seconds * sample_rate_hz
    if n < -1e-9 or abs(n - round(n)) > 1e-6:
        raise ValueError(
            f"{what} {seconds} s is not a whole number of ticks at {sample_rate_hz} Hz"
        )
    return int(round(n))


def _stated(condition: dict, sample_rate_hz: float) -> dict:
    bad = set(condition) - set(CONDITION_KEYS)
    if bad:
        raise ValueError(f"unknown condition keys {sorted(bad)}; known: {CONDITION_KEYS}")
    st = {**TABLE1, "sample_rate_hz": sample_rate_hz, **condition}
    st.setdefault("lead_time_s", st["sensor_delay_s"])
    return {k: float(v) for k, v in st.items()}


def true_rig(
    condition: dict,
    hidden: dict | None = None,
    sample_rate_hz: float = 10000.0,
    clamp_nonnegative: bool = False,
) -> tuple[dict, TrueRig]:
    """The stated conditions (completed) and the true rig of one condition.

    Parameters
    ----------
    condition : dict
        Stated conditions (keys of :data:`CONDITION_KEYS`, SI units); missing
        keys take :data:`TABLE1` (lead: the stated delay; rate: ``sample_rate_hz``).
    hidden : dict, optional
        Hidden effects, name -> {parameter: value} (:data:`HIDDEN_EFFECTS`).
    sample_rate_hz : float
        Rig computer rate where the condition does not say, Hz.
    clamp_nonnegative : bool
        Clamp the compensated force at 0 (see :class:`TrueRig`).

    Returns
    -------
    tuple[dict, TrueRig]
        The stated conditions (all keys) and the true rig.
    """
    st = _stated(condition, sample_rate_hz)
    hidden = dict(hidden or {})
    for name, par in hidden.items():
        if name not in HIDDEN_EFFECTS:
            raise ValueError(f"unknown hidden effect {name!r}; known: {tuple(HIDDEN_EFFECTS)}")
        if set(par) != set(HIDDEN_EFFECTS[name]):
            raise ValueError(f"{name} takes {HIDDEN_EFFECTS[name]}, got {sorted(par)}")
    if "series_compliance" in hidden and (
        {"contact_damping", "contact_damping_ratio", "hunt_crossley", "coulomb_friction"}
        & set(hidden)
    ):
        raise ValueError("series_compliance is only supported with an elastic contact")
    fs = st["sample_rate_hz"]
    k = st["contact_stiffness_n_per_m"]
    m = k / (_TWO_PI * st["contact_frequency_hz"]) ** 2
    delay = _ticks(st["sensor_delay_s"], fs, "sensor delay")
    rig = TrueRig(
        sample_rate_hz=fs,
        mass_kg=m,
        stiffness_n_per_m=k,
        delay_ticks=delay,
        lead_time_s=st["lead_time_s"],
        table_hz=st["table_response_hz"],
        table_zeta=st["table_damping_ratio"],
        compensator_stiffness_n_per_m=k,
        clamp_nonnegative=bool(clamp_nonnegative),
    )

    def p(name: str) -> float:
        return float(hidden[name][HIDDEN_EFFECTS[name][0]])

    if "extra_delay" in hidden:
        rig = replace(rig, delay_ticks=delay + _ticks(p("extra_delay"), fs, "extra delay"))
    if "lead_time_error" in hidden:
        rig = replace(rig, lead_time_s=p("lead_time_error"))
    if "table_response" in hidden:
        rig = replace(rig, table_hz=p("table_response"))
    if "table_damping" in hidden:
        rig = replace(rig, table_zeta=p("table_damping"))
    if "stiffness_error" in hidden:
        rig = replace(rig, compensator_stiffness_n_per_m=k * p("stiffness_error"))
    if "contact_frequency_error" in hidden:
        rig = replace(rig, mass_kg=m / p("contact_frequency_error") ** 2)
    if "series_compliance" in hidden:
        rig = replace(rig, stiffness_n_per_m=k / (1.0 + k * p("series_compliance")))
    c = p("contact_damping") if "contact_damping" in hidden else 0.0
    if "contact_damping_ratio" in hidden:
        c += 2.0 * p("contact_damping_ratio") * math.sqrt(rig.stiffness_n_per_m * rig.mass_kg)
    rig = replace(rig, damping_n_s_per_m=c)
    if "hunt_crossley" in hidden:
        rig = replace(rig, alpha_s_per_m=p("hunt_crossley"))
    if "coulomb_friction" in hidden:
        rig = replace(rig, friction_n=p("coulomb_friction"))
    return st, rig


def _expm(a: np.ndarray) -> np.ndarray:
    """Matrix exponential of a small matrix (scaling and squaring of a Taylor
    series; ``scipy.linalg.expm`` takes milliseconds on a 3 x 3)."""
    norm = float(np.max(np.sum(np.abs(a), axis=1)))
    s = max(0, math.ceil(math.log2(norm)) + 4) if norm > 0.0 else 0
    x = a / 2.0**s
    term = np.eye(a.shape[0])
    out = term.copy()
    for i in range(1, 18):
        term = term @ x / i
        out = out + term
    for _ in range(s):
        out = out @ out
    return out


def _table_step(rig: TrueRig, h: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Exact step (Phi, Gamma) of the table over a tick with a held command (None: ideal)."""
    if math.isinf(rig.table_hz):
        return None
    w = _TWO_PI * rig.table_hz
    a = np.array([[0.0, 1.0, 0.0], [-w * w, -2.0 * rig.table_zeta * w, w * w], [0.0, 0.0, 0.0]])
    e = _expm(a * h)
    return e[:2, :2], e[:2, 2]


def simulate_cor(rig: TrueRig, compensator: str, initial_velocity_m_per_s: float) -> float:
    """CoR ``-v_out / v_in`` of one contact of the spacecraft model on ``rig``.

    Parameters
    ----------
    rig : TrueRig
        The true physics and the computer's settings.
    compensator : str
        ``none``, ``SDC``, ``MDC`` or ``SDMDC``.
    initial_velocity_m_per_s : float
        Approach velocity of the model, m/s (> 0).

    Returns
    -------
    float
        CoR, 1.
    """
    if compensator not in COMPENSATORS:
        raise ValueError(f"unknown compensator {compensator!r}")
    sdc = compensator in ("SDC", "SDMDC")
    mdc = compensator in ("MDC", "SDMDC")
    h = 1.0 / rig.sample_rate_hz
    v0 = float(initial_velocity_m_per_s)
    m, k = rig.mass_kg, rig.stiffness_n_per_m
    c, alpha, fr = rig.damping_n_s_per_m, rig.alpha_s_per_m, rig.friction_n
    lead, kc, nd = rig.lead_time_s, rig.compensator_stiffness_n_per_m, rig.delay_ticks
    clamp = rig.clamp_nonnegative
    step = _table_step(rig, h)
    # Start: model at -gap, table in steady tracking of the held ramp.
    if step is None:
        e_track, pd = 0.0, v0
        settle = 2
    else:
        phi, gam = step
        # (Phi - I) [-e, w] = [v0 h, 0] - Gamma v0 h  (the sampled error is constant)
        z = np.linalg.solve(phi - np.eye(2), np.array([v0 * h, 0.0]) - gam * v0 * h)
        e_track, pd = -float(z[0]), float(z[1])
        a11, a12, a21, a22 = (float(x) for x in phi.ravel())
        b1, b2 = float(gam[0]), float(gam[1])
        decay_s = 1.0 / (max(rig.table_zeta, 0.02) * _TWO_PI * rig.table_hz)
        settle = math.ceil(6.0 * decay_s / h) + 2
    gap = e_track + (5.0 + _PHASE) * v0 * h
    x, v = -gap, v0
    p = x - e_track
    u_prev = x
    fm_prev = 0.0
    fh: list[float] = []
    tail = nd + settle + 2
    t_contact = math.pi * math.sqrt(m / k)
    max_ticks = int((gap / v0 + 50.0 * t_contact + 1.0) / h) + tail
    f_big = 1e3 * v0 * math.sqrt(k * m) + 1e3 * fr
    started = False
    last = 0
    for n in range(max_ticks):
        if p > 0.0:
            f = k * p
            if alpha:
                f *= 1.0 + alpha * pd
            if c:
                f += c * pd
            if fr:
                f += fr if pd > 0.0 else (-fr if pd < 0.0 else 0.0)
            if f < 0.0:
                f = 0.0
        else:
            f = 0.0
        fh.append(f)
        fm = fh[n - nd] if n >= nd else 0.0
        if fm <= 0.0:
            fc = 0.0
        else:
            fc = fm
            if sdc:
                fc += lead * (fm - fm_prev) / h
            if mdc:
                fc += kc * (u_prev - p)
            if clamp and fc < 0.0:
                fc = 0.0
        v -= fc / m * h
        x += v * h
        if f > 0.0 or fm > 0.0 or fc != 0.0:
            started = True
            last = n
            if f > f_big:
                raise RuntimeError("the loop diverged")
        elif started and n - last > tail:
            return -v / v0
        if step is None:
            p, pd = x, (x - u_prev) / h
        else:
            p, pd = a11 * p + a12 * pd + b1 * x, a21 * p + a22 * pd + b2 * x
        u_prev = x
        fm_prev = fm
    raise RuntimeError("the contact did not end (or never began) within the run")


def make_table(
    conditions: Sequence[dict],
    compensators: Iterable[str] = COMPENSATORS,
    hidden: dict | None = None,
    sample_rate_hz: float = 10000.0,
    decimals: int | None = 4,
    repeats: int = 1,
    cor_noise_std: float = 0.0,
    seed=0,
    clamp_nonnegative: bool = False,
) -> list[dict]:
    """Rows of a measured CoR table (one per condition, compensator and repeat).

    Parameters
    ----------
    conditions : sequence of dict
        Stated conditions (keys of :data:`CONDITION_KEYS`, SI units; missing
        keys: :data:`TABLE1`, the lead defaults to the stated delay).
    compensators : iterable of str
        Compensators measured at each condition.
    hidden : dict, optional
        Hidden effects of the true rig, name -> {parameter: value}.
    sample_rate_hz : float
        Rig computer rate where a condition does not say, Hz.
    decimals : int or None
        CoR rounded to this many decimals (None: not rounded).
    repeats : int
        Rows per condition and compensator.
    cor_noise_std : float
        Std of gaussian noise added to each row's CoR, 1.
    seed
        numpy seed of the noise.
    clamp_nonnegative : bool
        Clamp the compensated force at 0 (the run format's computer; default:
        the paper's loop, see :class:`TrueRig`).

    Returns
    -------
    list of dict
        Rows with the keys of :data:`COLUMNS` except ``cor_std`` (stated
        conditions; the CoR measured on the true rig).
    """
    comps = tuple(compensators)
    for comp in comps:
        if comp not in COMPENSATORS:
            raise ValueError(f"unknown compensator {comp!r}")
    if repeats < 1:
        raise ValueError("repeats must be >= 1")
    rng = np.random.default_rng(seed)
    rows = []
    for cond in conditions:
        st, rig = true_rig(cond, hidden, sample_rate_hz, clamp_nonnegative)
        for comp in comps:
            cor = simulate_cor(rig, comp, st["initial_velocity_m_per_s"])
            for _ in range(repeats):
                val = cor + (float(rng.normal(0.0, cor_noise_std)) if cor_noise_std else 0.0)
                if decimals is not None:
                    val = round(val, decimals)
                row = {"compensator": comp, "cor": val}
                row.update({key: st[key] for key in COLUMNS if key in st})
                rows.append(row)
    return rows


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        if math.isfinite(value) and value == int(value) and abs(value) < 1e15:
            return str(int(value))
        return repr(value)
    return str(value)


def write_csv(rows: Sequence[dict], path) -> Path:
    """Write ``rows`` as a CoR table CSV: the columns of :data:`COLUMNS` present
    in any row, in that order; an empty cell where a row lacks a value.

    Parameters
    ----------
    rows : sequence of dict
        Rows as from :func:`make_table`.
    path : str or Path
        CSV file to write.

    Returns
    -------
    Path
        The file written.
    """
    extra = {key for row in rows for key in row} - set(COLUMNS)
    if extra:
        raise ValueError(f"columns not in a CoR table: {sorted(extra)}")
    cols = [c for c in COLUMNS if any(c in row for row in rows)]
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(cols)
        for row in rows:
            w.writerow([_cell(row.get(c)) for c in cols])
    return path
