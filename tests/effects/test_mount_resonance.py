"""The compliant sensor mount (``mount_resonance``): its law over a tick is
the exact first-order-hold solution, it rings as a second-order system, and a
fit finds the mount that two independent generators hid (the 1-D rig zoo's
resonant force sensor, the 6-DoF rig's ringing F/T mount), each written
without the library's code."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import cont2discrete

from hybridtable.effects.registry import get_effect
from hybridtable.laws.table import ramp_tick, second_order_matrices
from hybridtable.systems.measurement_chain import MeasurementChain, MeasurementChainParams
from tests.generators import rigzoo
from tests.generators import run6_logs as g6


def test_the_tick_is_scipys_first_order_hold():
    A, B = second_order_matrices(40.0, 0.1)
    phi, g0, g1 = ramp_tick(A, B, 1e-3)
    C, D = np.array([[1.0, 0.0]]), np.zeros((1, 1))
    ad, bd, cd, dd, _ = cont2discrete((A, B, C, D), 1e-3, method="foh")
    # scipy's state is x - G1 u: the same realization as the chain's LinearSystem
    np.testing.assert_allclose(phi, ad, rtol=1e-12, atol=0)
    np.testing.assert_allclose(phi @ g1 + g0, bd, rtol=1e-10)
    np.testing.assert_allclose(g1[0], dd[0, 0], rtol=1e-10)


@pytest.mark.parametrize("zeta", [0.05, 0.2])
def test_a_mount_overshoots_a_step_and_rings_at_its_damped_frequency(zeta):
    f_hz, h, n = 30.0, 1e-4, 20000
    chain = MeasurementChain(
        MeasurementChainParams(h, mount_frequency_hz=f_hz, mount_damping_ratio=zeta)
    )
    y = chain.readings(np.r_[0.0, np.ones(n - 1)])  # a step, linear over its first tick
    assert y[-1] == pytest.approx(1.0, abs=1e-6)  # unit gain
    overshoot = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    assert y.max() - 1.0 == pytest.approx(overshoot, rel=0.01)
    peaks = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    assert h * (peaks[1] - peaks[0]) == pytest.approx(
        1.0 / (f_hz * math.sqrt(1.0 - zeta**2)), abs=2 * h
    )
    with pytest.raises(ValueError, match="mount_damping_ratio"):
        MeasurementChainParams(h, mount_frequency_hz=f_hz, mount_damping_ratio=0.0)


@pytest.mark.slow
def test_a_fit_finds_the_rig_zoos_resonant_force_sensor(tmp_path):
    """1-D: the zoo's sensor is its own scipy first-order-hold transfer function."""
    from hybridtable.diagnosis.fit import fit_given
    from hybridtable.measurement.run_reader import read_runs

    rig = rigzoo.draw_rig(np.random.default_rng(4))
    noise = rigzoo.NoiseSpec(kind="white", ar=(), sigma_f=2.0, sigma_p=3e-6)
    hidden = {"resonant_force_sensor": {"fs_hz": 30.0, "zeta_s": 0.12}}
    for i, v in enumerate((0.08, 0.12)):
        rec = rigzoo.simulate_run(
            rig, hidden, v, "SDMDC", rigzoo.MAX_TICKS, noise=noise, seed=i, run_id=f"r{i}"
        )
        rigzoo.write_run(tmp_path, f"r{i}", rec)
    values, std = fit_given(read_runs([str(tmp_path)]), [(get_effect("mount_resonance"), {})])
    found, err = values["mount_resonance"], std["mount_resonance"]
    assert abs(found["mount_frequency_hz"] - 30.0) < 4.0 * err["mount_frequency_hz"] + 0.05
    assert abs(found["mount_damping_ratio"] - 0.12) < 4.0 * err["mount_damping_ratio"] + 0.002


@pytest.mark.slow
def test_a_fit_finds_the_six_axis_generators_ringing_mount(tmp_path):
    """6-DoF: the generator's mount is its own exponential per tick, on each
    channel of the F/T sensor, in its own closed loop."""
    from hybridtable.six_dof.fit6 import fit_runs6
    from hybridtable.six_dof.run6 import read_run6

    scen = g6.scenario(compensator={"name": "SDC"})
    truth = {"mount_frequency_hz": 40.0, "mount_damping_ratio": 0.15}
    rows = g6.generate_run6(
        scen,
        seed=3,
        force_noise_n=2.0,
        moment_noise_n_m=0.5,
        position_noise_m=2e-6,
        attitude_noise_rad=1e-6,
        hidden={"mount_resonance": truth},
        table_start="tick0",
    )
    csv, _ = g6.write_run6(tmp_path, "mount", scen, rows)
    fit = fit_runs6([read_run6(csv)], [(get_effect("mount_resonance"), {})])
    assert fit.chi2_after / fit.n_residuals < 1.05  # down to the noise
    for name, value in truth.items():
        std = fit.std["mount_resonance"][name]
        assert std is not None and abs(fit.values["mount_resonance"][name] - value) < 4.0 * std


def test_a_cor_with_a_mount_runs_its_system_and_the_linear_model_names_what_it_leaves():
    """The fast engine has no mount: a CoR with one runs the Drake diagram
    (it differs from the nominal one), and the linear model says it leaves
    the mount out (it used to drop it silently)."""
    from hybridtable.effects.spec import ModelSpec
    from hybridtable.explain.model import ln_cor
    from hybridtable.loop.params import HybridLoopParams

    params = HybridLoopParams(
        spacecraft_mass_kg=2500.0,
        contact_stiffness_n_per_m=1.0e5,
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        compensator="SDMDC",
        sample_rate_hz=1000.0,
    )
    spec = ModelSpec().with_sensor(mount_frequency_hz=8.0, mount_damping_ratio=0.1)
    loop, systems = spec.realize(params)
    assert systems is not None and systems.sensor is not None
    assert abs(ln_cor(loop, systems) - ln_cor(params)) > 1e-3
    _, left = spec.linear_changes(params)
    assert left == ["the sensor's mount (8 Hz)"]
