"""The closed hybrid loop: energy, momentum, the sampled rig computer, bad input."""

import math

import numpy as np
import pytest

from hybridtable import HybridLoopParams, ParameterError, simulate
from hybridtable.studies.paper import cor_estimate, paper_params, table1_params


def test_ideal_loop_conserves_energy():
    # No delay, ideal table, no compensation: an elastic bounce.
    r = simulate(paper_params(sensor_delay_s=0.0, table_response_hz=math.inf))
    assert r.metrics.cor == pytest.approx(1.0, abs=1e-4)
    # Contact lasts half a contact period, peak force is k v0 / w_con.
    k, m, v0 = 1e5, r.params.spacecraft_mass_kg, 0.1
    assert r.metrics.contact_duration_s == pytest.approx(math.pi * math.sqrt(m / k), abs=2e-4)
    assert r.metrics.peak_force_n == pytest.approx(v0 * math.sqrt(k * m), rel=1e-4)


def test_energy_gain_matches_cor(paper_run):
    r = paper_run("none")
    m, v_in = r.params.spacecraft_mass_kg, r.metrics.v_in_m_per_s
    assert r.metrics.energy_gain_j == pytest.approx(
        0.5 * m * v_in**2 * (r.metrics.cor**2 - 1), rel=1e-9
    )
    assert r.metrics.energy_gain_j > 0


def test_sampled_loop_momentum_equals_impulse_of_fed_force():
    p = table1_params("SDMDC", sample_rate_hz=1000.0, clamp_nonnegative=True)
    r = simulate(p)
    h = 1e-3
    # Semi-implicit Euler: m (v_out - v0) = -sum(f_comp[k]) h exactly.
    dv = r.v_des_m_per_s[-1] - p.initial_velocity_m_per_s
    assert p.spacecraft_mass_kg * dv == pytest.approx(-np.sum(r.f_comp_n) * h, rel=1e-9)
    assert np.all(r.f_comp_n >= 0.0)
    np.testing.assert_allclose(np.diff(r.time_s), h, rtol=1e-9)


def test_sampled_loop_converges_to_continuous_as_rate_grows(paper_run):
    cont = paper_run("none").metrics.cor
    errs = [
        abs(simulate(table1_params("none", sample_rate_hz=fs)).metrics.cor - cont)
        for fs in (1000, 4000)
    ]
    assert errs[1] < errs[0]
    assert errs[1] < 0.01


def test_large_delay_throws_the_spacecraft_back():
    # A 20 ms sensor delay against a 5 Hz contact: one bounce, far more energy out.
    p = paper_params(sensor_delay_s=0.02, contact_frequency_hz=5.0)
    r = simulate(p)
    assert r.metrics.cor > 1.5
    assert r.metrics.energy_gain_j > 0


def test_undamped_table_run_ends_and_lags_only_by_the_sensor_delay():
    # zeta = 0: no ramp lag, so tau_eff = T_fms; the table rings after the contact.
    p = paper_params(table_response_hz=20.0, table_damping_ratio=0.0)
    r = simulate(p)
    assert r.metrics.cor == pytest.approx(cor_estimate(p), abs=0.005)


def test_contact_that_does_not_end_is_an_error():
    from hybridtable import SimulationError

    with pytest.raises(SimulationError, match="did not end"):
        simulate(table1_params("none"), t_max_s=0.2)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"spacecraft_mass_kg": 0.0}, "spacecraft_mass_kg"),
        ({"sensor_delay_s": -0.001}, "sensor_delay_s"),
        ({"compensator": "magic"}, "compensator"),
        ({"initial_velocity_m_per_s": float("nan")}, "initial_velocity_m_per_s"),
        ({"table_initial_state": "flying"}, "table_initial_state"),
    ],
)
def test_bad_parameters_name_the_field(kwargs, field):
    base = dict(spacecraft_mass_kg=100.0, contact_stiffness_n_per_m=1e5)
    with pytest.raises(ParameterError, match=field):
        HybridLoopParams(**{**base, **kwargs})


def test_contact_damping_ratio_is_of_the_critical_damping():
    p = HybridLoopParams(spacecraft_mass_kg=4.0, contact_stiffness_n_per_m=100.0)
    assert p.with_contact_damping_ratio(0.25).contact_damping_n_s_per_m == 2.0 * 0.25 * 20.0
    assert p.with_contact_damping_ratio(0.0).contact_damping_n_s_per_m == 0.0
    with pytest.raises(ParameterError, match="contact_damping_ratio"):
        p.with_contact_damping_ratio(-0.1)
