"""compare on a rig with coloured (AR(1)) noise and nothing missing: every
channel within the noise (the position's third differences read with the
noise model's colour, measurement.noise_model.third_difference_gain)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.noise_model import NoiseModel, third_difference_gain
from hybridtable.measurement.run_reader import read_runs
from tests.generators import rigzoo


def test_the_gain_of_third_differences_is_their_variance_over_a_white_noises():
    assert third_difference_gain(NoiseModel(1.0, 0.0, 100)) == pytest.approx(1.0)
    rng = np.random.default_rng(0)
    phi, n = 0.7, 400_000
    e = np.empty(n)
    e[0] = rng.standard_normal()
    w = rng.standard_normal(n) * math.sqrt(1 - phi * phi)
    for k in range(1, n):
        e[k] = phi * e[k - 1] + w[k]
    seen = float(np.mean(np.diff(e, 3) ** 2)) / 20.0
    assert third_difference_gain(NoiseModel(1.0, phi, n)) == pytest.approx(seen, rel=0.02)
    a = (1.2, -0.5)  # AR(2): the same through its correlations
    e = np.zeros(n)
    for k in range(2, n):
        e[k] = a[0] * e[k - 1] + a[1] * e[k - 2] + rng.standard_normal()
    e = e[1000:] / e[1000:].std()
    seen = float(np.mean(np.diff(e, 3) ** 2)) / 20.0
    assert third_difference_gain(NoiseModel(1.0, 0.8, n, a)) == pytest.approx(seen, rel=0.03)


@pytest.mark.parametrize("seed", [0, 3])
@pytest.mark.parametrize("compensator", ["none", "SDMDC"])
def test_a_null_run_with_ar1_noise_is_within_the_noise_on_every_channel(
    tmp_path, seed, compensator
):
    rig = rigzoo.draw_rig(np.random.default_rng(seed))
    noise = rigzoo.NoiseSpec(kind="ar1", ar=(0.7,), sigma_f=2.0, sigma_p=3e-6)
    record = rigzoo.simulate_run(
        rig, None, 0.1, compensator, rigzoo.MAX_TICKS, noise=noise, seed=seed, run_id="r"
    )
    rigzoo.write_run(tmp_path, "r", record)
    (run,) = read_runs([tmp_path])
    c = compare_run(run)
    for channel in ("f_mea_n", "p_act_m"):
        assert c.error_to_noise(channel) < 1.2, (channel, c.error_to_noise(channel))
    assert c.noise_rms["p_act_m"] == pytest.approx(3e-6, rel=0.2)


def test_a_filters_tail_after_the_contact_is_no_noise():
    from hybridtable.measurement.noise_model import estimate_noise
    from hybridtable.measurement.run_format import Run, RunInfo

    rng = np.random.default_rng(5)
    n, a, b, tau = 3000, 400, 700, 60.0
    k = np.arange(n)
    p_act = np.where((k >= a) & (k <= b), 1e-3 * np.sin(np.pi * (k - a) / (b - a)), -1e-3)
    force = np.where((k >= a) & (k <= b), 500.0 * np.sin(np.pi * (k - a) / (b - a)), 0.0)
    # a first-order sensor filter: the reading rings on after the contact
    reading = np.zeros(n)
    for i in range(1, n):
        reading[i] = reading[i - 1] + (force[i] - reading[i - 1]) / tau
    f_mea = reading + 2.0 * rng.standard_normal(n)
    info = RunInfo(
        *("r", 1000.0, 100.0, 1e5, 0.0, 30.0, 0.7, "none", 0.0, 1e-3, 0.1, 0.0),
    )
    zeros = np.zeros(n)
    run = Run(info, k * 1e-3, p_act, p_act + 1e-7 * rng.standard_normal(n), f_mea, zeros, zeros)
    sigma = estimate_noise(run, 0, 2)["f_mea_n"].sigma
    assert sigma == pytest.approx(2.0, rel=0.1)
