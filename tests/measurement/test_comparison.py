"""Comparison metrics (closed forms), the acceptance on the example runs, a
hidden physical effect found in the phases where it acts. The command is
tested in ``tests/commands/test_compare.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.phases import (
    contact_duration,
    cor_from_record,
    delayed_labels,
    loop_energy,
    phase_labels,
)
from hybridtable.measurement.run_reader import read_run, read_runs
from hybridtable.measurement.stats import (
    channel_error,
    correlation,
    force_noise_rms,
    lags_outside_by_chance,
    position_noise_rms,
)
from tests.examples import EXAMPLES
from tests.generators.rigsim import NOMINAL, damped_spring, simulate_record, write_run

needs_examples = pytest.mark.skipif(not EXAMPLES.is_dir(), reason="example runs not available")


# -- metric functions ----------------------------------------------------------
def test_channel_error_closed_forms():
    t = np.linspace(0, 1, 1001)
    y = np.sin(2 * np.pi * t)
    e = channel_error(y, y - 0.1)
    assert e.rms_error == pytest.approx(0.1) and e.mean_error == pytest.approx(0.1)
    assert e.nrmse == pytest.approx(0.1 / np.linalg.norm(y - y.mean()) * math.sqrt(len(y)))
    assert e.fit_percent == pytest.approx(100 * (1 - e.nrmse))
    assert channel_error(y, np.full_like(y, y.mean())).fit_percent == pytest.approx(0.0)
    assert channel_error(y, y).fit_percent == 100.0


def test_fit_percent_by_hand():
    # ||e|| = 1, ||y - mean(y)|| = sqrt(1.5^2 + 0.5^2 + 0.5^2 + 1.5^2) = sqrt(5).
    e = channel_error(np.array([1.0, 2.0, 3.0, 4.0]), np.array([1.0, 2.0, 3.0, 5.0]))
    assert e.nrmse == pytest.approx(1.0 / math.sqrt(5.0))
    assert e.fit_percent == pytest.approx(55.278640450004204)
    assert e.rms_error == pytest.approx(0.5) and e.mean_error == pytest.approx(-0.25)
    # The mean of the measurement fits 0 %; a model worse than it fits < 0 %.
    y = np.array([3.0, -1.0, 4.0, 1.0, 5.0])
    assert channel_error(y, np.full(5, y.mean())).fit_percent == pytest.approx(0.0, abs=1e-12)
    assert channel_error(y, y).fit_percent == 100.0
    assert channel_error(y, -y).fit_percent < 0.0


def test_lags_outside_by_chance_is_the_binomial_tail():
    # B(50, 0.01): P(X > 3) = 1.6e-3 > 0.1 %, P(X > 4) = 1.5e-4 <= 0.1 %.
    def tail(k, n=50, p=0.01):
        return 1.0 - sum(math.comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(k + 1))

    assert tail(3) > 1e-3 >= tail(4)
    assert lags_outside_by_chance(50) == 4
    assert lags_outside_by_chance(1) == 1  # P(X > 0) = 1 % > 0.1 %
    assert lags_outside_by_chance(500) > lags_outside_by_chance(50)


def test_whiteness_verdict_false_alarms_and_a_coloured_residual():
    rng = np.random.default_rng(11)
    u = rng.standard_normal(2000)
    alarms = 0
    for _ in range(300):
        c = correlation(rng.standard_normal(2000), u, 50)
        alarms += not (c.auto_white and c.cross_white)
    assert alarms <= 3  # two tests of 0.1 % each: about 0.6 of 300 expected
    # AR(1) with coefficient 0.5: autocorrelation 0.5^k, far outside the band.
    w = rng.standard_normal(2000)
    e = np.zeros(2000)
    for k in range(1, 2000):
        e[k] = 0.5 * e[k - 1] + w[k]
    c = correlation(e, u, 50)
    assert not c.auto_white and c.cross_white
    s = c.summary()
    assert s["auto_white"] is False and s["auto_chance_limit"] == 4


def test_noise_estimators_recover_known_noise():
    rng = np.random.default_rng(3)
    n = 4000
    quiet = np.ones(n, bool)
    quiet[1000:1500] = False
    f = 2.5 + 1.7 * rng.standard_normal(n)
    f[1000:1500] += 500.0  # a contact, excluded
    sigma, offset, used = force_noise_rms(f, quiet)
    assert sigma == pytest.approx(1.7, rel=0.05) and offset == pytest.approx(2.5, abs=0.1)
    assert used == n - 500
    # Third differences ignore any quadratic motion (a ramp and an acceleration).
    t = np.arange(n) * 1e-3
    p = 0.01 + 0.08 * t - 0.3 * t**2 + 3e-6 * rng.standard_normal(n)
    sigma_p, used_p = position_noise_rms(p, quiet)
    assert sigma_p == pytest.approx(3e-6, rel=0.05) and used_p == n - 500 - 6


def test_phases_and_delay_shift():
    p = np.concatenate([-np.linspace(0.002, 1e-4, 20), 1e-3 * np.sin(np.linspace(0.1, 3.0, 30))])
    p = np.concatenate([p, -np.linspace(1e-4, 0.01, 50)])
    labels = phase_labels(p)
    counts = [int(np.sum(labels == i)) for i in range(4)]
    peak = 20 + int(np.argmax(p[20:50]))
    assert counts == [20, peak - 20 + 1, 50 - peak - 1, 50]
    shifted = delayed_labels(labels, 4)
    np.testing.assert_array_equal(shifted[4:], labels[:-4])
    assert (shifted[:4] == 0).all()
    with pytest.raises(ValueError, match="no contact"):
        phase_labels(-np.ones(10))


def test_correlation_finds_a_delayed_input_and_passes_white_noise():
    rng = np.random.default_rng(7)
    u = rng.standard_normal(3000)
    white = correlation(rng.standard_normal(3000), u, 40)
    s = white.summary()
    assert s["auto_lags_outside"] <= 3 and s["cross_lags_outside"] <= 3
    assert white.band == pytest.approx(2.5758 / math.sqrt(3000), rel=1e-4)
    e = np.concatenate([np.zeros(5), u[:-5]]) + 0.2 * rng.standard_normal(3000)
    c = correlation(e, u, 40, sample_period_s=1e-3)
    assert int(np.argmax(np.abs(c.cross))) == 5 and c.cross[5] > 0.9
    assert c.summary()["cross_max_lag_s"] == pytest.approx(0.005)


def test_cor_duration_and_loop_energy_closed_forms():
    v = np.array([0.1, 0.1, 0.1, 0.05, -0.05, -0.12, -0.12])
    f = np.array([0, 0, 0, 9.0, 9.0, 1.0, 0])
    assert cor_from_record(v, f, 0.1) == (pytest.approx(1.2), 0.1, -0.12)
    with pytest.raises(ValueError, match="not ended"):
        cor_from_record(v[:-1], f[:-1], 0.1)
    with pytest.raises(ValueError, match="never felt"):
        cor_from_record(v, 0 * f, 0.1)
    # Half-sine penetration: duration pi / w; spring loop lossless; damper
    # absorbs c A^2 w pi / 2.
    w, a, k, c = 30.0, 1e-3, 6e4, 400.0
    t = np.arange(-0.05, 0.2, 1e-4)
    # Apart: approaching and leaving at the contact's speed (p continuous).
    p = np.where(t <= 0, a * w * t, -a * w * (t - np.pi / w))
    p = np.where((t > 0) & (t < np.pi / w), a * np.sin(w * t), p)
    vel = np.where((t > 0) & (t < np.pi / w), a * w * np.cos(w * t), 0.0)
    on = p > 0
    assert contact_duration(t, p) == pytest.approx(np.pi / w, abs=2e-4)
    assert abs(loop_energy(p, np.where(on, k * p, 0), on)) < 1e-4
    assert loop_energy(p, np.where(on, k * p + c * vel, 0), on) == pytest.approx(
        c * a * a * w * np.pi / 2, rel=0.01
    )


# -- acceptance on the example runs --------------------------------------------
@needs_examples
def test_examples_replay_within_noise_and_cor_within_0_005():
    for run in read_runs([EXAMPLES]):
        cmp = compare_run(run)
        assert cmp.error_to_noise("f_mea_n") <= 1.2, run.run_id
        assert cmp.error_to_noise("p_act_m") <= 1.2, run.run_id
        assert abs(cmp.cor_model - cmp.cor_measured) <= 0.005, run.run_id
        # A 2 N sensor noise and a micrometre position noise.
        assert 1.5 < cmp.noise_rms["f_mea_n"] < 2.5 and 1e-6 < cmp.noise_rms["p_act_m"] < 3e-6
        assert cmp.contact_duration_s["replay"] == pytest.approx(
            cmp.contact_duration_s["measured"], abs=1e-3
        )


# -- hidden effects ------------------------------------------------------------
def _synthetic(tmp_path, name, contact=None, seed=0):
    info = dict(NOMINAL, run_id=name)
    cols = simulate_record(info, contact, seed=seed)
    return compare_run(read_run(write_run(tmp_path, name, info, cols)))


def _contact_share(c, channel="f_mea_n"):
    return sum(c.phases[channel][p]["share"] for p in ("compression", "restitution"))


def test_nominal_synthetic_run_sits_on_the_noise_floor(tmp_path):
    c = _synthetic(tmp_path, "nominal")
    assert c.noise_rms["f_mea_n"] == pytest.approx(2.0, rel=0.1)
    assert c.noise_rms["p_act_m"] == pytest.approx(2e-6, rel=0.1)
    assert 0.85 < c.error_to_noise("f_mea_n") < 1.15
    assert 0.85 < c.error_to_noise("p_act_m") < 1.15
    assert c.whiteness["f_mea_n"].summary()["auto_lags_outside"] <= 3
    assert abs(c.cor_model - c.cor_measured) < 0.005


def test_contact_damping_is_found_in_compression_and_restitution(tmp_path):
    c = _synthetic(tmp_path, "damped", damped_spring(NOMINAL["contact_stiffness_n_per_m"], 600.0))
    noise = c.noise_rms["f_mea_n"]
    assert noise == pytest.approx(2.0, rel=0.1)  # the floor does not see the effect
    assert c.error_to_noise("f_mea_n") > 5.0
    assert _contact_share(c) > 0.95
    ph = c.phases["f_mea_n"]
    for free in ("approach", "free_flight"):
        assert ph[free]["rms_error"] < 1.3 * noise
    # Damping adds force while compressing and removes it while restituting.
    assert ph["compression"]["mean_error"] > 5 * noise
    assert ph["restitution"]["mean_error"] < -5 * noise
    # The table is not affected: p_act stays on its floor.
    assert c.error_to_noise("p_act_m") < 1.2
    # The residual is coloured and the contact absorbs energy, the model's none.
    assert c.whiteness["f_mea_n"].summary()["auto_lags_outside"] > 25
    assert c.loop_energy_j["measured"] > 0.3 and abs(c.loop_energy_j["model"]) < 0.01
    assert c.cor_measured < c.cor_model - 0.05


def test_hardening_contact_adds_force_in_both_contact_phases(tmp_path):
    k = NOMINAL["contact_stiffness_n_per_m"]

    def hardening(p, v):
        return k * p * (1.0 + p / 0.01) if p > 0 else 0.0

    c = _synthetic(tmp_path, "hardening", hardening, seed=1)
    noise = c.noise_rms["f_mea_n"]
    assert c.error_to_noise("f_mea_n") > 5.0
    assert _contact_share(c) > 0.95
    ph = c.phases["f_mea_n"]
    assert ph["compression"]["mean_error"] > 5 * noise
    assert ph["restitution"]["mean_error"] > 5 * noise
    # Elastic: no loop energy beyond noise.
    assert abs(c.loop_energy_j["measured"]) < 0.05
