"""Records whose channels contradict each other are data problems, refused in one
line; records of real physics (any noise, a hidden effect) pass. The runs come
from the independent rig simulator of ``tests/generators/rigsim.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.measurement.channels import check_channels, noise_level
from hybridtable.measurement.run_reader import read_run, read_runs
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record, write_run


def _write(tmp_path, change=None, info=None, contact=None, stem="run1", **kw):
    info = {**NOMINAL, "run_id": stem, **(info or {})}
    cols = simulate_record(info, contact=contact, **kw)
    if change is not None:
        change(cols)
    return write_run(tmp_path, stem, info, cols)


def _refused(path) -> str:
    with pytest.raises(MeasurementError) as exc:
        read_runs([path])
    text = str(exc.value)
    assert "\n" not in text and str(path) in text
    return text


def test_noise_level_of_white_noise_on_a_smooth_motion():
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 1.0, 20001)
    x = 0.3 * np.sin(2 * math.pi * 2.0 * t) + 0.01 * rng.standard_normal(t.size)
    assert noise_level(x) == pytest.approx(0.01, rel=0.03)


@pytest.mark.parametrize("noise_f_n, noise_p_m", [(0.0, 0.0), (2.0, 2e-6), (30.0, 5e-5)])
def test_records_of_real_physics_pass(tmp_path, noise_f_n, noise_p_m):
    # Noiseless, typical, and noisy records; a damped contact the JSON does not know.
    path = _write(
        tmp_path, contact=damped_spring(60000.0, 800.0), noise_f_n=noise_f_n, noise_p_m=noise_p_m
    )
    check_channels(read_run(path))


def test_a_record_with_a_force_bias_passes(tmp_path):
    # A biased sensor is physics (diagnose's force_bias), not a data problem.
    def bias(c):
        c["f_mea_n"] += 5.0

    check_channels(read_run(_write(tmp_path, bias)))


def test_dead_force_sensor_is_refused(tmp_path):
    def dead(c):
        c["f_mea_n"][:] = 0.0

    text = _refused(_write(tmp_path, dead))
    assert "f_mea_n reads no contact force" in text and "dead or disconnected" in text


def test_sign_flipped_force_is_refused(tmp_path):
    def flip(c):
        c["f_mea_n"] *= -1.0

    assert "sign-flipped force" in _refused(_write(tmp_path, flip))


def test_negated_positions_contradict_the_computers_velocity(tmp_path):
    def negate(c):
        c["p_des_m"] *= -1.0
        c["p_act_m"] *= -1.0

    text = _refused(_write(tmp_path, negate))
    assert "p_des_m moves against v_des_m_per_s" in text and "-1 x" in text


def test_sign_flipped_table_position_is_refused(tmp_path):
    def flip(c):
        c["p_act_m"] *= -1.0

    assert "p_act_m moves against the command p_des_m" in _refused(_write(tmp_path, flip))


def test_a_record_that_starts_in_contact_is_refused(tmp_path):
    # The record of a run cut 0.1 s after the contact began, re-timed from 0.
    def cut(c):
        start = int(np.argmax(c["f_mea_n"] > 100.0)) + 100
        for name in c:
            c[name] = c[name][start:]
        c["time_s"] = c["time_s"] - c["time_s"][0]

    assert "starts in contact" in _refused(_write(tmp_path, cut))


def test_a_record_without_contact_is_refused(tmp_path):
    # A 0.5 m gap at 0.08 m/s: the devices never meet within the 0.9 s record.
    text = _refused(_write(tmp_path, info={"initial_gap_m": 0.5}))
    assert "no contact in the record: p_act_m never exceeds" in text
    assert "f_mea_n never exceeds" in text


def test_an_absurd_cell_names_its_row_and_range(tmp_path):
    def spike(c):
        c["f_mea_n"][300] = 1e30

    text = _refused(_write(tmp_path, spike))
    assert "row 301 (t = 0.3 s), column f_mea_n: 1e+30 N is outside" in text


def test_a_long_log_with_a_large_reset_is_not_taken_for_a_flipped_column(tmp_path):
    # The model reset 0.5 m back between two contacts: one tick breaks the
    # computer's arithmetic by far more than the thousands of others keep it
    # (a least-squares slope over the log is 0.44, the median tick's is 1).
    from tests.generators.longlog import simulate_log, write_log

    info = {**NOMINAL, "run_id": "log"}
    log = simulate_log(info, [(0.002, 0.08), (0.5, 0.5), (0.002, 0.08)], 1.5, seed=1)
    step = log["v_des_m_per_s"][1:] * 1e-3
    assert np.dot(step, np.diff(log["p_des_m"])) / np.dot(step, step) < 0.5
    check_channels(read_run(write_log(tmp_path, "log", info, log)))
