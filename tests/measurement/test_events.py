"""A long log split at the model's resets into contact events: the resets found
exactly, each event's start state recovered from the record, its CoR kept. The
log is built from runs of the independent rig simulator (tests/generators/rigsim.py),
each started from its own state as an operator's reset would."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.measurement.audit import audit_run
from hybridtable.measurement.events import reset_ticks, split_events, split_runs
from hybridtable.measurement.run_reader import read_run
from tests.generators.rigsim import NOMINAL, simulate_record, write_run

STARTS = [(0.004, 0.08), (0.003, 0.05), (0.005, 0.12), (0.004, 0.1)]


def _log(tmp_path, starts=STARTS, duration_s=1.5):
    parts, infos = [], []
    for i, (gap, v) in enumerate(starts):
        info = {**NOMINAL, "run_id": "log", "initial_gap_m": gap, "initial_velocity_m_per_s": v}
        parts.append(simulate_record(info, duration_s=duration_s, seed=i))
        infos.append(info)
    cols = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    cols["time_s"] = np.arange(len(cols["time_s"])) / NOMINAL["sample_rate_hz"]
    path = write_run(tmp_path, "log", infos[0], cols)
    joins = list(np.cumsum([len(p["time_s"]) for p in parts])[:-1])
    return read_run(path), parts, joins


def test_resets_are_found_at_the_joins_and_nowhere_else(tmp_path):
    run, _, joins = _log(tmp_path)
    assert reset_ticks(run) == joins


def test_each_event_keeps_its_contact_and_starts_from_the_computers_state(tmp_path):
    run, parts, joins = _log(tmp_path)
    events, split = split_events(run)
    assert len(events) == len(STARTS) and split.resets == tuple(joins)
    assert [e.run_id for e in events] == [f"log-contact{i:02d}" for i in range(1, 5)]
    h = run.sample_period_s
    for i, (event, part) in enumerate(zip(events, parts, strict=True)):
        # The same contact: the event's channels are its part's, from its start on.
        offset = split.events[i][0] - (joins[i - 1] if i else 0)
        for name in ("p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s"):
            np.testing.assert_allclose(
                getattr(event, name), part[name][offset:], rtol=1e-9, atol=1e-12
            )  # the CSV keeps 10 digits
        # Its time starts at 0 on the format's ticks.
        assert event.time_s[0] == 0.0
        np.testing.assert_allclose(np.diff(event.time_s), h, rtol=1e-9)
        # The start state reproduces the record: the audit finds the format's
        # arithmetic, from the initial gap and velocity, in every event.
        _, findings = audit_run(event)
        keys = {f.key for f in findings}
        assert not keys & {"initial_gap_m", "initial_velocity_m_per_s", "sample_rate_hz"}, keys
        assert event.where("csv").endswith(
            f"(contact event {i + 1} of 4, t = "
            f"{run.time_s[split.events[i][0]]:.3f}-"
            f"{run.time_s[split.events[i][1] - 1]:.3f} s)"
        )
    # The first event is the log's start; the others start after the table settled.
    assert split.events[0][0] == 0 and events[0].info.initial_gap_m == STARTS[0][0]
    for (start, _), join in zip(split.events[1:], joins, strict=True):
        assert join < start <= join + 40


def test_a_run_without_resets_is_left_whole(tmp_path):
    info = {**NOMINAL, "run_id": "one"}
    run = read_run(write_run(tmp_path, "one", info, simulate_record(info)))
    events, split = split_events(run)
    assert events == [run] and split is None
    assert split_runs([run]) == ([run], [])


def test_a_reset_that_leads_to_no_contact_is_refused(tmp_path):
    # The last start is 0.5 m away: no contact before the log ends.
    run, _, _ = _log(tmp_path, starts=[(0.004, 0.08), (0.5, 0.08)])
    with pytest.raises(MeasurementError, match="no contact between t = 1.501 s and 3.001 s"):
        split_events(run)
