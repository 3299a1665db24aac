"""A long log split at the model's resets into contact events: the resets found
exactly, each event's start state recovered from the record, and the model
matching every event within the noise. The logs come from the independent
generator of rig campaigns, ``tests/generators/longlog.py``."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.events import reset_ticks, split_events, split_runs
from hybridtable.measurement.run_reader import read_run
from tests.generators.longlog import shortest_period_s, simulate_log, write_log
from tests.generators.rigsim import NOMINAL, simulate_record, write_run

STARTS = [(0.004, 0.08), (0.003, 0.05), (0.005, 0.12), (0.004, 0.1)]


def _log(tmp_path, starts=STARTS, period_s=None):
    info = {**NOMINAL, "run_id": "log", "compensator": "SDMDC"}
    period = period_s or shortest_period_s(info, starts)
    log = simulate_log(info, starts, period, seed=3)
    return read_run(write_log(tmp_path, "log", info, log)), log


def test_resets_are_found_exactly_and_nowhere_else(tmp_path):
    run, log = _log(tmp_path)
    assert reset_ticks(run) == [int(k) for k in log["reset_ticks"][1:]]


def test_each_event_starts_from_the_state_the_model_was_reset_to(tmp_path):
    run, log = _log(tmp_path)
    events, split = split_events(run)
    assert len(events) == len(STARTS) and split.resets == tuple(log["reset_ticks"][1:])
    assert [e.run_id for e in events] == [f"log-contact{i:02d}" for i in range(1, 5)]
    h = run.sample_period_s
    for i, (event, (gap, v)) in enumerate(zip(events, STARTS, strict=True)):
        # The reset state, solved from the reset tick's own arithmetic (the
        # CSV keeps 10 digits).
        assert event.info.initial_gap_m == pytest.approx(gap, rel=1e-8)
        assert event.info.initial_velocity_m_per_s == pytest.approx(v, rel=1e-8)
        assert event.time_s[0] == 0.0
        np.testing.assert_allclose(np.diff(event.time_s), h, rtol=1e-9)
        start, end = split.events[i]
        np.testing.assert_array_equal(event.f_mea_n, run.f_mea_n[start:end])
        assert event.where("csv").endswith(
            f"(contact event {i + 1} of 4, t = {run.time_s[start]:.3f}-{run.time_s[end - 1]:.3f} s)"
        )
    assert events[0].info.initial_gap_m == run.info.initial_gap_m  # the log's JSON
    assert "table_initial_state" not in events[0].info.extra  # the log's own start
    assert "table_initial_state" in events[1].info.extra


def test_the_model_matches_every_event_within_the_noise(tmp_path):
    # Also where the reset's jump is large and the table is still moving to the
    # new command when the contact comes: the event starts the model's table in
    # steady tracking of the command it followed before the reset.
    run, _ = _log(tmp_path, period_s=0.8)
    events, _ = split_events(run)
    for event in events:
        c = compare_run(event)
        assert c.within_noise("f_mea_n") and c.within_noise("p_act_m"), (
            event.run_id,
            c.error_to_noise("f_mea_n"),
            c.error_to_noise("p_act_m"),
        )
        assert abs(c.cor_model - c.cor_measured) < 0.002


def test_a_tail_keeps_a_given_time_after_the_contact(tmp_path):
    run, log = _log(tmp_path, period_s=2.0)
    events, split = split_events(run, tail_s=0.25)
    full, _ = split_events(run)
    for i, event in enumerate(events):
        last_contact = int(log["contact_end_ticks"][i])
        start, end = split.events[i]
        assert event.f_comp_n[-1] == 0.0  # the contact has ended in the event
        assert end - 1 <= last_contact + 250 + 20 and end < full[i].n + start
        np.testing.assert_array_equal(event.v_des_m_per_s, full[i].v_des_m_per_s[: end - start])


def test_a_run_without_resets_is_left_whole(tmp_path):
    info = {**NOMINAL, "run_id": "one"}
    run = read_run(write_run(tmp_path, "one", info, simulate_record(info)))
    events, split = split_events(run)
    assert events == [run] and split is None
    assert split_runs([run]) == ([run], [])


def test_a_reset_that_leads_to_no_contact_is_refused(tmp_path):
    # The second start is 0.5 m away: no contact before the log ends.
    run, _ = _log(tmp_path, starts=[(0.004, 0.08), (0.5, 0.08)], period_s=1.5)
    with pytest.raises(MeasurementError, match="no contact between t = 1.500 s and 2.999 s"):
        split_events(run)


def test_events_of_one_log_share_one_noise_floor(tmp_path):
    # At the shortest period each event has only a few quiet ticks; pooled over
    # the log, the floor is the generator's noise (2 N, 2 um) and the right model
    # matches every event.
    from hybridtable.measurement.comparison import pool_noise_floors

    run, _ = _log(tmp_path, starts=STARTS * 3)
    events, _ = split_events(run)
    comparisons = [compare_run(e) for e in events]
    pool_noise_floors(comparisons)
    assert len({c.noise_rms["p_act_m"] for c in comparisons}) == 1
    assert comparisons[0].noise_rms["p_act_m"] == pytest.approx(2e-6, rel=0.15)
    assert comparisons[0].noise_rms["f_mea_n"] == pytest.approx(2.0, rel=0.15)
    assert all(c.within_noise("f_mea_n") and c.within_noise("p_act_m") for c in comparisons)
    assert all("pooled over the 12 contact events" in c.notes[-1] for c in comparisons)
