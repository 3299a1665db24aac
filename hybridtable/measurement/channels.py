"""Checks that a record's channels agree with each other before anything is fitted.

A run can be well formed (numbers in every cell, the right columns and
times) and still hold no physics to explain: a dead force sensor, a
sign-flipped channel, a record that starts in contact. No physical effect can
explain such a record, so fitting one to it answers a question nobody asked.
:func:`check_channels` refuses it as a data problem, in one line naming the
file, the channel and the figures, with
:class:`~hybridtable.errors.MeasurementError` (exit code 2).

What is checked, in order, on run ``r`` with period ``h`` and the JSON's
stiffness ``k``, mass ``m`` and velocity ``v0``:

1. every value inside its channel's plausible range (:data:`hybridtable.limits.LIMITS`);
2. the rig computer's kinematics: ``p_des[k] - p_des[k-1] = v_des[k] h``
   (format step 3); a median ratio far from 1 means a sign-flipped or
   mislabelled ``p_des_m`` or ``v_des_m_per_s`` (the median ignores the few
   ticks where a long log's model was reset);
3. the table follows its command: the slope of ``p_act`` on ``p_des``
   (levels) is near 1; near 0 or negative means a dead or sign-flipped
   position channel;
4. a contact is in the record: penetration (``p_act`` above its noise) or a
   force reading above the noise and the deadband;
5. the record starts apart (not with both penetration and force);
6. where ``p_act`` shows penetration, the force sensor reads it: some
   reading above its noise (else a dead sensor), and not a clearly negative
   one (else a sign-flipped force; compression reads positive).

Noise levels are robust estimates from second differences (a smooth motion
has almost none), floored at 1e-3 of the JSON's undamped peak force
``v0 sqrt(k m)`` and deflection ``v0 sqrt(m / k)``, so a noiseless record is
checked too. Thresholds are five noise levels: a real rig's noise does not
reach them by chance over a record.
"""

from __future__ import annotations

import math

import numpy as np

from hybridtable.errors import MeasurementError
from hybridtable.limits import LIMITS
from hybridtable.measurement.run_format import RUN_COLUMNS, Run

__all__ = ["NOISE_MULTIPLE", "noise_level", "noise_level_of_differences", "check_channels"]

#: A signal counts as present when it exceeds this many noise levels.
NOISE_MULTIPLE = 5.0

#: Noise floor as a fraction of the JSON's undamped peak force / deflection.
_FLOOR = 1e-3

#: Accepted slopes of the kinematic check (2) and of the table's tracking (3).
_KINEMATIC_SLOPE = (0.5, 2.0)
_TRACKING_SLOPE = (0.25, 4.0)


def noise_level(x: np.ndarray) -> float:
    """Robust noise standard deviation of ``x`` from its second differences:
    ``1.4826 median|d2 x| / sqrt(6)`` (white noise of std s gives s)."""
    if len(x) < 3:
        return 0.0
    return noise_level_of_differences(np.diff(x, 2))


def noise_level_of_differences(d2: np.ndarray) -> float:
    """:func:`noise_level` of a series whose second differences are ``d2``
    (some of them: a window, the ticks out of contact)."""
    if len(d2) == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2)) / math.sqrt(6.0))


def _where(run: Run, k: int) -> str:
    return f"{run.where('csv')} row {k + 1} (t = {run.time_s[k]:.6g} s)"


def _check_ranges(run: Run) -> None:
    for name in RUN_COLUMNS:
        if name == "time_s":
            continue
        limit = LIMITS[name]
        x = getattr(run, name)
        bad = np.flatnonzero((x < limit.low) | (x > limit.high))
        if bad.size:
            k = int(bad[0])
            raise MeasurementError(
                f"{_where(run, k)}, column {name}: {x[k]:g} {limit.unit} is outside its "
                f"plausible range {limit.words()}"
            )


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of ``y`` on ``x`` through the origin (nan if x is 0)."""
    sxx = float(np.dot(x, x))
    return float(np.dot(x, y)) / sxx if sxx > 0.0 else math.nan


def _check_kinematics(run: Run) -> None:
    # The median tick ratio, not a least-squares slope: the resets of a long
    # log (measurement.events) break the arithmetic on a few ticks by a lot.
    step = run.v_des_m_per_s[1:] * run.sample_period_s
    moving = np.abs(step) > 0.0
    if not moving.any():
        return
    slope = float(np.median(np.diff(run.p_des_m)[moving] / step[moving]))
    low, high = _KINEMATIC_SLOPE
    if not low <= slope <= high:
        what = (
            "moves against"
            if slope < 0.0
            else ("does not follow" if abs(slope) < low else "runs away from")
        )
        raise MeasurementError(
            f"{run.where('csv')}: p_des_m {what} v_des_m_per_s "
            f"(p_des[k] - p_des[k-1] = {slope:.3g} x v_des[k] h on the median tick, the "
            "format's computer gives 1): a sign-flipped or mislabelled column, or another "
            "sample rate"
        )


def _check_tracking(run: Run) -> None:
    p_des = run.p_des_m - run.p_des_m.mean()
    p_act = run.p_act_m - run.p_act_m.mean()
    slope = _slope(p_des, p_act)
    low, high = _TRACKING_SLOPE
    if not low <= slope <= high:
        what = "moves against" if slope < 0.0 else "does not follow"
        raise MeasurementError(
            f"{run.where('csv')}: p_act_m {what} the command p_des_m (slope {slope:.3g}, a "
            "table gives about 1): a sign-flipped, dead or mislabelled position channel"
        )


def check_channels(run: Run) -> None:
    """Refuse a record whose channels contradict each other (see the module).

    Raises
    ------
    MeasurementError
        One line naming the file, the channel and the figures.
    """
    _check_ranges(run)
    _check_kinematics(run)
    _check_tracking(run)

    info = run.info
    k, m = info.contact_stiffness_n_per_m, info.spacecraft_mass_kg
    v0 = info.initial_velocity_m_per_s
    f_scale, p_scale = v0 * math.sqrt(k * m), v0 * math.sqrt(m / k)
    sigma_f = max(noise_level(run.f_mea_n), _FLOOR * f_scale)
    sigma_p = max(noise_level(run.p_act_m), _FLOOR * p_scale)
    thr_f = max(info.force_deadband_n, NOISE_MULTIPLE * sigma_f)
    thr_p = NOISE_MULTIPLE * sigma_p
    pressed = run.p_act_m > thr_p
    loaded = run.f_mea_n > thr_f
    where = run.where("csv")

    if not pressed.any() and not loaded.any():
        raise MeasurementError(
            f"{where}: no contact in the record: p_act_m never exceeds {thr_p:.3g} m "
            f"(5 noise levels) and f_mea_n never exceeds {thr_f:.3g} N (the deadband or 5 "
            f"noise levels; largest reading {run.f_mea_n.max():.3g} N)"
        )

    first = slice(0, min(3, run.n))
    if np.median(run.p_act_m[first]) > thr_p and np.median(run.f_mea_n[first]) > thr_f:
        raise MeasurementError(
            f"{where}: the record starts in contact (p_act_m = {run.p_act_m[0]:.3g} m, "
            f"f_mea_n = {run.f_mea_n[0]:.3g} N at t = 0): a run starts apart, "
            f"initial_gap_m = {info.initial_gap_m:g} m before the contact"
        )

    if pressed.sum() >= 3:
        f_in = run.f_mea_n[pressed]
        peak_p = float(run.p_act_m[pressed].max())
        if np.median(f_in) < -thr_f:
            raise MeasurementError(
                f"{where}: f_mea_n is negative while p_act_m shows penetration (median "
                f"{np.median(f_in):.3g} N over {pressed.sum()} ticks): compression reads "
                "positive in the format; a sign-flipped force channel"
            )
        if k * peak_p > 2.0 * thr_f and not (f_in > thr_f).any():
            raise MeasurementError(
                f"{where}: f_mea_n reads no contact force (at most {f_in.max():.3g} N) over "
                f"the {pressed.sum()} ticks where p_act_m shows penetration up to "
                f"{peak_p:.3g} m (k p = {k * peak_p:.3g} N by the JSON's stiffness): a dead "
                "or disconnected force sensor"
            )
