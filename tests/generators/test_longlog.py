"""Physical checks of the long-log generator (tests/generators/longlog.py).

Between resets the log is the rig computer's own arithmetic; a reset breaks it
at one tick, from which its state can be read back; each contact's CoR is the
compensator's (about 1 with SDMDC, above 1 without); the table has settled
before a contact when the period only just covers the contacts; a log of one
contact is rigsim's run, noise draw for noise draw; a long period makes the
reset's jump large enough for the table to strike the contact first.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.generators.longlog import shortest_period_s, simulate_log, truth, write_log
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record

#: Four contacts whose approaches (60-100 ms) outlast eight table decay times.
CONTACTS = [(0.005, 0.05), (0.005, 0.08), (0.004, 0.06), (0.003, 0.05)]


def _info(compensator: str = "SDMDC") -> dict:
    return {**NOMINAL, "compensator": compensator}


@pytest.fixture(scope="module")
def sdmdc_log() -> dict[str, np.ndarray]:
    info = _info()
    return simulate_log(info, CONTACTS, shortest_period_s(info, CONTACTS), seed=3)


def test_arithmetic_holds_between_resets_and_breaks_at_them(sdmdc_log):
    log, info = sdmdc_log, _info()
    h_s = 1.0 / info["sample_rate_hz"]
    mass_kg = info["spacecraft_mass_kg"]
    r_p_m = np.diff(log["p_des_m"]) - log["v_des_m_per_s"][1:] * h_s
    r_v_m_per_s = np.diff(log["v_des_m_per_s"]) + log["f_comp_n"][1:] * h_s / mass_kg
    resets = log["reset_ticks"][1:]
    between = np.ones(r_p_m.size, dtype=bool)
    between[resets - 1] = False
    assert np.max(np.abs(r_p_m[between])) < 1e-15
    assert np.max(np.abs(r_v_m_per_s[between])) < 1e-15
    # At a reset the velocity jumps from the last rebound to the next approach.
    assert np.all(np.abs(r_v_m_per_s[resets - 1]) > 0.09)
    assert np.all(np.abs(r_p_m[resets - 1]) > 1e-3)  # the jump: mm, not float rounding
    # The contacts' reset states are in the record (the JSON holds only the first).
    x0_m = log["p_des_m"][resets] - log["v_des_m_per_s"][resets] * h_s
    v0_m_per_s = log["v_des_m_per_s"][resets] + log["f_comp_n"][resets] * h_s / mass_kg
    np.testing.assert_allclose(-x0_m, [g for g, _ in CONTACTS[1:]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(v0_m_per_s, [u for _, u in CONTACTS[1:]], rtol=0, atol=1e-15)


def test_period_keeps_the_reset_jump_to_a_few_mm(sdmdc_log):
    assert sdmdc_log["reset_jump_m"][0] == 0.0
    assert 0.0 < np.max(sdmdc_log["reset_jump_m"][1:]) < 0.01


def test_cor_is_the_compensators(sdmdc_log):
    info = _info("none")
    none = simulate_log(info, CONTACTS, shortest_period_s(info, CONTACTS), seed=3)
    # A 4 ms sensor delay pumps energy in: CoR 1.17 in every contact; SDMDC
    # takes it out to within 1 % (the sampled, deadbanded rig's remainder).
    assert np.all(none["cor"] > 1.1)
    assert np.all(np.abs(sdmdc_log["cor"] - 1.0) < 0.02)
    # The contacts are alike: the CoR of a linear spring does not depend on the approach.
    assert np.ptp(sdmdc_log["cor"]) < 0.005 and np.ptp(none["cor"]) < 0.005
    # The model leaves with the velocity it had when the contact ended (only
    # a noise reading above the deadband can touch it in flight).
    before_reset = sdmdc_log["v_des_m_per_s"][[*sdmdc_log["reset_ticks"][1:] - 1, -1]]
    np.testing.assert_allclose(before_reset, sdmdc_log["v_out_m_per_s"], rtol=1e-3)
    assert json.loads(json.dumps(truth(sdmdc_log)))["contacts"][2]["cor"] == pytest.approx(
        sdmdc_log["cor"][2]
    )


def test_damping_takes_energy_out_of_every_contact():
    info = _info()
    period_s = shortest_period_s(info, CONTACTS)
    k_n_per_m, mass_kg = info["contact_stiffness_n_per_m"], info["spacecraft_mass_kg"]
    c_n_s_per_m = 400.0
    quiet = {"noise_f_n": 0.0, "noise_p_m": 0.0}
    plain = simulate_log(info, CONTACTS, period_s, **quiet)
    damped = simulate_log(
        info, CONTACTS, period_s, contact=damped_spring(k_n_per_m, c_n_s_per_m), **quiet
    )
    # Damping ratio 400 / (2 sqrt(k m)) = 0.031: a half cycle keeps
    # exp(-pi zeta / sqrt(1 - zeta^2)) = 0.906 of the velocity.
    zeta = c_n_s_per_m / (2.0 * math.sqrt(k_n_per_m * mass_kg))
    kept = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2))
    np.testing.assert_allclose(damped["cor"] / plain["cor"], kept, rtol=0.01)


def test_table_has_settled_before_each_contact(sdmdc_log):
    info = _info()
    noiseless = simulate_log(
        info, CONTACTS, shortest_period_s(info, CONTACTS), noise_f_n=0.0, noise_p_m=0.0
    )
    h_s = 1.0 / info["sample_rate_hz"]
    w_rad_per_s = 2.0 * math.pi * info["table_natural_frequency_hz"]
    # In steady tracking a second-order table lags a ramp by 2 zeta / omega,
    # and the held command adds half a tick.
    lag_s = 2.0 * info["table_damping_ratio"] / w_rad_per_s + h_s / 2.0
    for start in noiseless["contact_start_ticks"]:
        ticks = slice(start - 10, start)
        v = noiseless["v_des_m_per_s"][ticks]
        tracking = noiseless["p_des_m"][ticks] - v * lag_s
        error_m = np.max(np.abs(noiseless["p_act_m"][ticks] - tracking))
        assert error_m < 5e-6  # against a lag of 0.3-0.6 mm and jumps of mm
        assert np.all(v * lag_s > 3e-4)
    # The spacecraft model, not the table, leads each contact.
    assert np.all(noiseless["p_des_at_touch_m"] > 0.0)


def test_one_contact_is_rigsims_run():
    info = _info("none")
    period_s = 0.9
    log = simulate_log(info, [(info["initial_gap_m"], info["initial_velocity_m_per_s"])], period_s)
    h_s = 1.0 / info["sample_rate_hz"]
    run = simulate_record(info, duration_s=period_s - h_s)  # same seed, same draws
    assert log["time_s"].size == run["time_s"].size == 900
    for name, atol in (
        ("time_s", 0.0),
        ("p_des_m", 1e-14),
        ("p_act_m", 1e-14),
        ("v_des_m_per_s", 1e-14),
        ("f_mea_n", 1e-9),
        ("f_comp_n", 1e-9),
        ("f_act_n", 1e-9),
    ):
        np.testing.assert_allclose(log[name], run[name], rtol=0, atol=atol, err_msg=name)


def test_a_long_period_makes_the_table_strike_first():
    info = _info()
    contacts = [(0.002, 0.1), (0.003, 0.08)]
    log = simulate_log(info, contacts, 5.0, noise_f_n=0.0, noise_p_m=0.0)
    # 5 s after the first contact the model has flown |v_out| t away ...
    flight_s = 5.0 - log["contact_end_ticks"][0] * 1e-3
    assert log["reset_jump_m"][1] == pytest.approx(
        abs(log["v_out_m_per_s"][0]) * flight_s - contacts[1][0], rel=0.02
    )
    # ... and the table, overshooting that jump by 4.6 % (zeta 0.7), reaches
    # the contact while the model is still apart.
    assert log["reset_jump_m"][1] > 0.4
    assert log["p_des_at_touch_m"][0] > 0.0 > log["p_des_at_touch_m"][1]


def test_write_log_holds_the_first_contact_only(tmp_path, sdmdc_log):
    csv_path = write_log(tmp_path, "campaign", _info(), sdmdc_log)
    info = json.loads((tmp_path / "campaign.json").read_text())
    assert info["initial_gap_m"] == CONTACTS[0][0]
    assert info["initial_velocity_m_per_s"] == CONTACTS[0][1]
    assert info["format"] == "hybridtable-run/1"
    header = csv_path.read_text().splitlines()[0]
    assert header == "time_s,p_des_m,p_act_m,f_mea_n,f_comp_n,v_des_m_per_s"
    table = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    assert table.shape == (sdmdc_log["time_s"].size, 6)
    np.testing.assert_allclose(table[:, 1], sdmdc_log["p_des_m"], rtol=1e-9, atol=1e-15)
