"""Phases of a contact in a record (approach, compression, restitution, free
flight), contact masks, and quantities of the contact: duration, CoR, loop energy.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "PHASES",
    "contact_mask",
    "phase_labels",
    "delayed_labels",
    "phase_breakdown",
    "cor_from_record",
    "contact_reading",
    "record_cor",
    "contact_duration",
    "loop_energy",
    "true_runs",
    "settle_ticks",
    "dilate",
    "QUIET_GUARD_TICKS",
    "quiet_ticks",
]


#: Phases of a contact record, in time order.
PHASES: tuple[str, ...] = ("approach", "compression", "restitution", "free_flight")


_APPROACH, _COMPRESSION, _RESTITUTION, _FREE = range(4)


#: Ticks of measured contact that a gap must exceed to split a contact (noise
#: near the zero crossing does not make two contacts).
MERGE_GAP_TICKS = 3


# -- phases --------------------------------------------------------------------
def settle_ticks(settling_time_s: float, h: float, n: int) -> int:
    """Ticks of period ``h`` [s] in ``settling_time_s`` [s], at most ``n`` (an
    undamped table's infinite settling time is the whole record)."""
    if not settling_time_s < n * h:
        return n
    return math.ceil(settling_time_s / h)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive index ranges of the True runs of ``mask``."""
    m = np.asarray(mask, dtype=bool)
    edges = np.diff(np.concatenate([[0], m.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1, strict=True))


def contact_mask(p_act_m: np.ndarray, merge_gap_ticks: int = MERGE_GAP_TICKS) -> np.ndarray:
    """Ticks of contact (penetration ``p_act > 0``), with gaps of at most
    ``merge_gap_ticks`` inside a contact filled."""
    on = np.asarray(p_act_m, dtype=float) > 0.0
    runs = true_runs(on)
    for (_, b), (c, _) in zip(runs[:-1], runs[1:], strict=True):
        if c - b - 1 <= merge_gap_ticks:
            on[b + 1 : c] = True
    return on


def phase_labels(p_act_m: np.ndarray) -> np.ndarray:
    """Phase index (into :data:`PHASES`) of every tick, from the penetration.

    Raises
    ------
    ValueError
        If the record holds no contact.
    """
    p = np.asarray(p_act_m, dtype=float)
    on = contact_mask(p)
    runs = true_runs(on)
    if not runs:
        raise ValueError("no contact in the record (p_act never > 0)")
    labels = np.full(len(p), _FREE, dtype=int)
    labels[: runs[0][0]] = _APPROACH
    for a, b in runs:
        peak = a + int(np.argmax(p[a : b + 1]))
        labels[a : peak + 1] = _COMPRESSION
        labels[peak + 1 : b + 1] = _RESTITUTION
    return labels


def delayed_labels(labels: np.ndarray, delay_ticks: int) -> np.ndarray:
    """Labels of readings delayed by ``delay_ticks``: tick ``k`` gets the label
    of tick ``k - delay_ticks`` (the first ticks that of tick 0)."""
    if delay_ticks <= 0:
        return labels.copy()
    return np.concatenate([np.full(delay_ticks, labels[0]), labels[:-delay_ticks]])


def phase_breakdown(residual: np.ndarray, labels: np.ndarray) -> dict[str, dict[str, float]]:
    """Per phase: RMS and mean of the residual, share of the squared error,
    number of ticks and fraction of the record."""
    e = np.asarray(residual, dtype=float)
    total = float(np.sum(e * e))
    out = {}
    for i, name in enumerate(PHASES):
        sel = labels == i
        n = int(sel.sum())
        sq = float(np.sum(e[sel] ** 2))
        out[name] = {
            "rms_error": math.sqrt(sq / n) if n else math.nan,
            "mean_error": float(e[sel].mean()) if n else math.nan,
            "share": sq / total if total > 0.0 else math.nan,
            "samples": n,
            "time_fraction": n / len(e),
        }
    return out


#: Ticks kept off each side of a contact when the noise is read out of it.
QUIET_GUARD_TICKS = 2


def quiet_ticks(
    on: np.ndarray, delay_ticks: int, settle: int, guard: int = QUIET_GUARD_TICKS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ticks out of the contact ``on`` whose readings hold noise alone:
    ``(force, position, position_short)``. The force's: ``guard`` ticks off
    the contact each side, delayed by the sensor's ``delay_ticks``; the
    position's: ``guard`` before and ``settle`` (the table's settling) after,
    without the record's first ``settle`` ticks (the table's start-up); the
    position's of a record too short for that: ``guard`` each side."""
    force = delayed_labels((~dilate(on, guard, guard)).astype(int), delay_ticks).astype(bool)
    settle = max(settle, guard)
    position = ~dilate(on, guard, settle)
    position[: min(settle, len(position))] = False
    return force, position, ~dilate(on, guard, guard)


def dilate(mask: np.ndarray, before: int, after: int) -> np.ndarray:
    """``mask`` with each True run widened by ``before`` and ``after`` ticks."""
    out = mask.copy()
    for a, b in true_runs(mask):
        out[max(a - before, 0) : b + after + 1] = True
    return out


# -- contact metrics -----------------------------------------------------------
def cor_from_record(
    v_des_m_per_s: np.ndarray,
    f_comp_n: np.ndarray,
    initial_velocity_m_per_s: float,
    reading: np.ndarray | None = None,
) -> tuple[float, float, float]:
    """CoR, ``v_in`` and ``v_out`` from a record's spacecraft velocity.

    The contact, as the model felt it, spans the ticks from the first to the
    last non-zero ``f_comp``, or, where ``reading`` is given (a mask of the
    ticks whose force reading shows the contact), from its first to its last
    tick, widened on each side over the ticks where ``f_comp`` stays non-zero.
    ``v_in`` is ``v_des`` at the tick before the contact (the initial
    velocity if that is tick 0), ``v_out`` at its last tick.

    Without ``reading`` (a deadband that gates the sensor's noise, and every
    noise-free model run), ``v_out`` is the last ``v_des``. Where noise passes
    the gate (a deadband of 0), ``f_comp`` is noise before and after the
    contact, and the model's velocity drifts under it: the readings find the
    contact (:func:`record_cor`), and the drift outside it is not counted.

    Raises
    ------
    ValueError
        If there is no contact, or it lasts to the last tick.
    """
    v = np.asarray(v_des_m_per_s, dtype=float)
    f = np.asarray(f_comp_n, dtype=float)
    on = np.flatnonzero(f != 0.0 if reading is None else np.asarray(reading, dtype=bool))
    if on.size == 0:
        if reading is not None:
            raise ValueError("the force reading never shows a contact above its noise")
        raise ValueError("f_comp is zero throughout: the model never felt a contact")
    zero = np.flatnonzero(f == 0.0)
    before, after = zero[zero < on[0]], zero[zero > on[-1]]
    if after.size == 0:
        raise ValueError("f_comp is still non-zero at the last tick: the contact has not ended")
    first = int(before[-1]) + 1 if before.size else 0
    last = int(after[0]) - 1
    v_in = float(v[first - 1]) if first > 0 else float(initial_velocity_m_per_s)
    v_out = float(v[last])
    return abs(v_out) / abs(v_in), v_in, v_out


def contact_reading(run) -> np.ndarray | None:
    """The ticks of recorded ``run`` (:class:`~hybridtable.measurement.run_format.Run`)
    whose force reading shows the contact, where the deadband lets the
    reading's noise through (it is below
    :data:`~hybridtable.measurement.channels.NOISE_MULTIPLE` robust noise
    levels): the readings above that many noise levels. ``None`` where the
    deadband gates the noise (``f_comp`` is then zero outside the contact)."""
    from hybridtable.measurement.channels import NOISE_MULTIPLE, noise_level

    above = NOISE_MULTIPLE * noise_level(np.asarray(run.f_mea_n, dtype=float))
    if run.info.force_deadband_n >= above:
        return None
    return np.asarray(run.f_mea_n) > above


def record_cor(run) -> tuple[float, float, float]:
    """:func:`cor_from_record` of a recorded ``run``, its contact found by
    :func:`contact_reading`."""
    return cor_from_record(
        run.v_des_m_per_s, run.f_comp_n, run.info.initial_velocity_m_per_s, contact_reading(run)
    )


def contact_duration(time_s: np.ndarray, p_act_m: np.ndarray) -> float:
    """Duration of the first contact, between the linearly interpolated zero
    crossings of the penetration (NaN without a contact)."""
    t = np.asarray(time_s, dtype=float)
    p = np.asarray(p_act_m, dtype=float)
    runs = true_runs(contact_mask(p))
    if not runs:
        return math.nan
    a, b = runs[0]

    def crossing(i: int, j: int) -> float:  # p[i] <= 0 < p[j] or the reverse
        return float(t[i] + (t[j] - t[i]) * (0.0 - p[i]) / (p[j] - p[i]))

    start = crossing(a - 1, a) if a > 0 else float(t[0])
    end = crossing(b, b + 1) if b + 1 < len(p) else float(t[-1])
    return end - start


def loop_energy(p_m: np.ndarray, f_n: np.ndarray, active: np.ndarray) -> float:
    """``sum f dp`` (trapezoid) over the ticks of ``active`` and one tick on
    each side: the energy absorbed by the contact over the loop, J."""
    p = np.asarray(p_m, dtype=float)
    f = np.asarray(f_n, dtype=float)
    idx = np.flatnonzero(active)
    if idx.size == 0:
        return math.nan
    a, b = max(idx[0] - 1, 0), min(idx[-1] + 1, len(p) - 1)
    ps, fs = p[a : b + 1], f[a : b + 1]
    return float(np.sum(0.5 * (fs[1:] + fs[:-1]) * np.diff(ps)))
