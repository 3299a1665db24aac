"""A long log of many contacts, split into contact events that are runs of their own.

A rig campaign often records one long log: the rig computer runs on, and
before each docking the operator resets the spacecraft model to a new start
(``x = -gap``, ``v = v_in``). The log's JSON holds the first start only. Each
reset breaks the computer's own arithmetic for one tick (format step 3:
``p_des[k] - p_des[k-1] = v_des[k] h`` and ``v_des[k] - v_des[k-1] =
-f_comp[k] h / m``), so :func:`reset_ticks` finds them in the record, and
:func:`split_events` cuts the log at them into contact events: each a
:class:`~hybridtable.measurement.run_format.Run` whose JSON is the log's with
the start the computer was reset to, which ``compare`` and ``diagnose`` treat
like any recorded run (and can work on in parallel).

An event starts at its reset tick: the spacecraft model from the state it was
reset to (solved from the tick's own arithmetic), the table from steady
tracking of the command it followed before the reset (the JSON extra
``table_initial_state``, :data:`hybridtable.measurement.rig.TABLE_START_KEY`),
so the table's transient after the reset is part of the event and of the
model. A log without resets is one run and is returned as it is, however
many contacts it holds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from hybridtable.errors import MeasurementError
from hybridtable.measurement.phases import true_runs
from hybridtable.measurement.rig import TABLE_START_KEY
from hybridtable.measurement.run_format import Run
from hybridtable.systems.table import TableParams

__all__ = ["EventSplit", "reset_ticks", "split_events", "split_runs"]

#: A tick breaks the computer's arithmetic when its command step or its
#: velocity step is off by more than this fraction of the typical step (the
#: median |v_des h|) or velocity (the median |v_des|): CSV rounding is far
#: below, a reset far above.
_RESET_FRACTION = 0.25

#: Fewest ticks in a row with a compensated force that make a contact.
_CONTACT_TICKS = 3


@dataclass(frozen=True)
class EventSplit:
    """How one log was split: its run id, the reset ticks and the events' tick ranges."""

    run_id: str
    resets: tuple[int, ...]
    events: tuple[tuple[int, int], ...]
    times_s: tuple[tuple[float, float], ...]

    def to_dict(self) -> dict:
        """The split for ``--json``: the log, its reset times and every event's span."""
        return {
            "run_id": self.run_id,
            "reset_ticks": list(self.resets),
            "events": [
                {
                    "run_id": f"{self.run_id}-contact{i + 1:02d}",
                    "first_tick": s,
                    "last_tick": e - 1,
                    "start_s": t0,
                    "end_s": t1,
                }
                for i, ((s, e), (t0, t1)) in enumerate(zip(self.events, self.times_s, strict=True))
            ],
        }

    def sentence(self) -> str:
        """``"run1: a long log of 20 contacts (resets at t = 5.000 ... 95.000 s), taken as
        20 contact events"``."""
        shown = ", ".join(f"{self.times_s[i][0]:.3f}" for i in range(min(3, len(self.events))))
        more = ", ..." if len(self.events) > 3 else ""
        return (
            f"{self.run_id}: a long log of {len(self.events)} contacts (the model was reset "
            f"{len(self.resets)} times; events from t = {shown}{more} s), taken as "
            f"{len(self.events)} contact events"
        )


def reset_ticks(run: Run) -> list[int]:
    """Ticks at which the rig computer's spacecraft model was reset: its command
    or velocity step breaks the format's arithmetic (see the module)."""
    h = run.sample_period_s
    m = run.info.spacecraft_mass_kg
    v = run.v_des_m_per_s
    r_p = np.diff(run.p_des_m) - v[1:] * h
    r_v = np.diff(v) + run.f_comp_n[1:] * h / m
    typical_v = float(np.median(np.abs(v)))
    if typical_v <= 0.0:
        return []
    tol_p = _RESET_FRACTION * typical_v * h
    tol_v = _RESET_FRACTION * typical_v
    broken = (np.abs(r_p) > tol_p) | (np.abs(r_v) > tol_v)
    return [int(k) + 1 for k in np.flatnonzero(broken)]


def _contact_ticks(run: Run) -> np.ndarray:
    """Ticks where the model felt a contact: a compensated force on at least
    :data:`_CONTACT_TICKS` ticks in a row (a lone noisy reading above the
    deadband is no contact)."""
    ticks = [np.arange(a, b + 1) for a, b in true_runs(run.f_comp_n != 0.0)]
    ticks = [t for t in ticks if t.size >= _CONTACT_TICKS]
    return np.concatenate(ticks) if ticks else np.zeros(0, dtype=int)


def _event(run: Run, start: int, end: int, index: int, total: int) -> Run:
    """The run of ticks ``[start, end)``. ``start == 0``: the log's own JSON.
    Otherwise ``start`` is a reset tick: the spacecraft starts from the state the
    computer was reset to (solved from the tick's own arithmetic), the table
    from steady tracking of the command it followed before the reset."""
    info = run.info
    where = (
        f"contact event {index} of {total}, t = {run.time_s[start]:.3f}-{run.time_s[end - 1]:.3f} s"
    )
    if start > 0:
        h, m = run.sample_period_s, info.spacecraft_mass_kg
        v0 = float(run.v_des_m_per_s[start] + run.f_comp_n[start] * h / m)
        x0 = float(run.p_des_m[start] - run.v_des_m_per_s[start] * h)
        if x0 > 0.0 or v0 <= 0.0:
            raise MeasurementError(
                f"{run.where('csv')} ({where}): the model was reset to p = {x0:.4g} m, "
                f"v = {v0:.4g} m/s, not to an approach (p <= 0, v > 0)"
            )
        # Steady tracking of the ramp held before the reset: the held command
        # p_des[start - 1], half a tick on, less the table's ramp lag 2 zeta / omega.
        v_old = float(run.v_des_m_per_s[start - 1])
        table = TableParams(info.table_natural_frequency_hz, info.table_damping_ratio)
        p_table = float(run.p_des_m[start - 1]) + v_old * (0.5 * h - table.ramp_lag_s)
        info = replace(
            info,
            initial_gap_m=-x0,
            initial_velocity_m_per_s=v0,
            extra={
                **info.extra,
                TABLE_START_KEY: {"position_m": p_table, "velocity_m_per_s": v_old},
            },
        )
    info = replace(
        info,
        run_id=f"{run.info.run_id}-contact{index:02d}",
        extra={**info.extra, "event_of": run.info.run_id, "event_ticks": [start, end - 1]},
    )
    cols = {name: values[start:end].copy() for name, values in run.columns().items()}
    cols["time_s"] = cols["time_s"] - run.time_s[start]
    return Run(
        info=info,
        csv_path=run.csv_path,
        json_path=run.json_path,
        part=where,
        skipped_columns=run.skipped_columns,
        **cols,
    )


def split_events(run: Run, tail_s: float | None = None) -> tuple[list[Run], EventSplit | None]:
    """The contact events of a long log (see the module), or ``[run]`` and
    ``None`` when the model was never reset.

    ``tail_s``: keep at most this long [s] of each event after its last
    contact tick (the free flight that follows holds little of the contact
    and most of the ticks); ``None`` keeps it all, up to the next reset.

    Raises
    ------
    MeasurementError
        When a segment between resets holds no contact, or its spacecraft is
        not approaching where its event starts.
    """
    resets = reset_ticks(run)
    if not resets:
        return [run], None
    bounds = [0, *resets, run.n]
    contact = _contact_ticks(run)
    spans: list[tuple[int, int]] = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        inside = contact[(contact >= a) & (contact < b)]
        if inside.size == 0:
            raise MeasurementError(
                f"{run.where('csv')}: no contact between t = {run.time_s[a]:.3f} s and "
                f"{run.time_s[b - 1]:.3f} s, where the model was reset (a long log's every "
                "reset must lead to a contact)"
            )
        if tail_s is not None:
            end = min(b, int(inside[-1]) + 1 + math.ceil(tail_s / run.sample_period_s))
            while end < b and run.f_comp_n[end - 1] != 0.0:  # end with no force
                end += 1
            b = end
        spans.append((a, b))
    events = [_event(run, s, e, i + 1, len(spans)) for i, (s, e) in enumerate(spans)]
    times = tuple((float(run.time_s[s]), float(run.time_s[e - 1])) for s, e in spans)
    return events, EventSplit(run.run_id, tuple(resets), tuple(spans), times)


def split_runs(
    runs: Sequence[Run], tail_s: float | None = None
) -> tuple[list[Run], list[EventSplit]]:
    """Every run split into its contact events (:func:`split_events`, with
    ``tail_s``), in order, and the splits that happened."""
    out: list[Run] = []
    splits: list[EventSplit] = []
    for run in runs:
        events, split = split_events(run, tail_s)
        out.extend(events)
        if split is not None:
            splits.append(split)
    ids = [r.run_id for r in out]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        raise MeasurementError(
            f"run id {twice[0]!r} names two runs (a run and a contact event of a long log); "
            "rename one"
        )
    return out, splits
