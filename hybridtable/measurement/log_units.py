"""Which unit a log holds each channel in, checked against the run's JSON.

A channel read in the wrong unit (time in ms read as s, forces in kN read as
N) would otherwise be refused far from its cause ("a dead force sensor") or,
worse, read. Each channel is compared with an anchor that does not depend on
its unit, in an order where every anchor is already checked:

1. ``v_des_m_per_s`` at tick 0 against the JSON's ``initial_velocity_m_per_s``
   (the record starts apart: no force has acted);
2. ``p_des_m`` at tick 0 against ``-initial_gap_m + v_des[0] h``;
3. ``f_comp_n`` during the contact against the velocity's steps, ``-m dv / h``
   (the computer's own arithmetic, format step 3);
4. ``p_act_m`` against ``p_des_m`` (the table follows its command: slope 1);
5. ``f_mea_n`` against ``f_comp_n`` during the contact (the compensator adds
   terms to the reading, it does not scale it).

A channel is refused only if it is off by more than :data:`OFF` and a unit of
:data:`~hybridtable.measurement.log_layout.UNITS` brings it within
:data:`FITS` of its anchor: the message names the column, the unit it was
read in and the unit that fits. Anything else (a sign, a dead channel) is left
to :mod:`~hybridtable.measurement.channels`, whose checks name it.
"""

from __future__ import annotations

import math

import numpy as np

from hybridtable.errors import MeasurementError
from hybridtable.measurement.log_layout import UNITS, LogLayout
from hybridtable.measurement.run_format import RUN_COLUMNS, Run

__all__ = ["OFF", "FITS", "fitting_unit", "time_unit_hint", "check_units"]

#: A channel is suspect when its ratio to its anchor is off 1 by more than this factor.
OFF = 5.0

#: ... and a unit fits when it brings that ratio within this factor of 1.
FITS = 2.0


def fitting_unit(ratio: float, column: str, layout: LogLayout) -> str | None:
    """The unit in which ``column`` would be ``ratio`` times smaller than read
    (its anchor's value), if ``ratio`` is off by more than :data:`OFF` and a
    unit brings it within :data:`FITS`; else ``None``."""
    if not (math.isfinite(ratio) and ratio > 0.0) or abs(math.log(ratio)) <= math.log(OFF):
        return None
    units = UNITS[RUN_COLUMNS[column]]
    old = units[layout.columns[column].unit]
    off = {u: abs(math.log(ratio * f / old)) for u, f in units.items()}
    best = min(off, key=off.__getitem__)
    return best if off[best] < math.log(FITS) else None


def time_unit_hint(ratio: float, layout: LogLayout) -> str:
    """The end of the sample-rate message when ``time_s``, read ``ratio``
    times the JSON's period, fits another unit; else ``""``."""
    unit = fitting_unit(ratio, "time_s", layout)
    if unit is None:
        return ""
    return f": {layout.read_as('time_s')} looks like {unit}; {layout.unit_advice({'time_s': unit})}"


def _median_ratio(x: np.ndarray, y: np.ndarray) -> float:
    """``median(x) / median(y)`` (nan if the latter is 0)."""
    den = float(np.median(y))
    return float(np.median(x)) / den if den != 0.0 else math.nan


def check_units(run: Run, layout: LogLayout) -> None:
    """Refuse the channels that fit another unit than they were read in (see
    the module); a channel found in another unit is taken in that unit as the
    anchor of the next, so one message names every such channel.

    Raises
    ------
    MeasurementError
        One line naming the file, each column at fault, the unit it was read
        in and the unit that fits.
    """
    info, h = run.info, run.sample_period_s
    col = {name: getattr(run, name) for name in RUN_COLUMNS}
    found: list[tuple[str, str, float, str]] = []

    def check(name: str, ratio: float, anchor: str) -> None:
        unit = fitting_unit(ratio, name, layout)
        if unit is not None:
            found.append((name, unit, ratio, anchor))
            units = UNITS[RUN_COLUMNS[name]]
            col[name] = col[name] * (units[unit] / units[layout.columns[name].unit])

    v0 = info.initial_velocity_m_per_s
    check("v_des_m_per_s", col["v_des_m_per_s"][0] / v0, "the JSON's initial_velocity_m_per_s")
    v = col["v_des_m_per_s"]
    start = -info.initial_gap_m + v[0] * h
    if start != 0.0:
        check("p_des_m", col["p_des_m"][0] / start, "the JSON's start -initial_gap_m + v_des h")
    f_comp = col["f_comp_n"]
    top = float(f_comp.max())
    on = np.flatnonzero(f_comp[1:] > 0.1 * top) + 1 if top > 0.0 else np.zeros(0, dtype=int)
    if on.size:
        pushed = -info.spacecraft_mass_kg * (v[on] - v[on - 1]) / h
        check("f_comp_n", _median_ratio(f_comp[on], pushed), "the force of the velocity's steps")
    p = col["p_des_m"] - col["p_des_m"].mean()
    sxx = float(np.dot(p, p))
    if sxx > 0.0:
        slope = float(np.dot(p, col["p_act_m"] - col["p_act_m"].mean())) / sxx
        check("p_act_m", slope, "p_des_m (the table's tracking)")
    if on.size:
        ratio = _median_ratio(col["f_mea_n"][on], col["f_comp_n"][on])
        check("f_mea_n", ratio, "f_comp_n during the contact")
    if not found:
        return
    what = "; ".join(
        f"{layout.read_as(name)} is {ratio:.4g} times {anchor}, like {unit}"
        for name, unit, ratio, anchor in found
    )
    advice = layout.unit_advice({n: u for n, u, _, _ in found})
    if len(found) == 1:
        raise MeasurementError(f"{run.where('csv')}: {what}: {advice}")
    # the fix first: a long line is cut at its end
    raise MeasurementError(
        f"{run.where('csv')}: {len(found)} columns fit other units than they were read "
        f"in: {advice}; {what}"
    )
