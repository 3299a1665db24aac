"""The run recorder writes what a rig's data logger would: the computer's
arithmetic exact on the noisy readings, the noise it was asked for, the
hidden physics in the signals and not in the JSON."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.effects.spec import ModelSpec
from hybridtable.errors import CommandError, ParameterError
from hybridtable.measurement.audit import audit_runs
from hybridtable.measurement.recorder import record_run, write_run
from hybridtable.measurement.rig import simulate_rig
from hybridtable.measurement.run_format import Run, RunInfo
from hybridtable.measurement.run_reader import read_runs
from hybridtable.systems.noise import MeasurementNoiseParams, noise_series

K, M = 6e4, 675.0


def _info(compensator="SDMDC", v=0.08, **kw) -> RunInfo:
    values = dict(
        run_id="rec",
        sample_rate_hz=1000.0,
        spacecraft_mass_kg=M,
        contact_stiffness_n_per_m=K,
        sensor_delay_s=0.004,
        table_natural_frequency_hz=30.0,
        table_damping_ratio=0.7,
        compensator=compensator,
        lead_time_s=0.004,
        initial_gap_m=0.002,
        initial_velocity_m_per_s=v,
        force_deadband_n=6.0,
    )
    values.update(kw)
    return RunInfo(**values)


def test_a_noise_free_record_is_the_rig_loop():
    run, truth = record_run(_info())
    frame = Run(run.info, run.time_s, *([np.zeros(run.n)] * 5))
    loop = simulate_rig(frame)
    for c in ("p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s"):
        np.testing.assert_array_equal(getattr(run, c), getattr(loop, c))
    assert truth["cor"] == pytest.approx(1.007, abs=0.002)  # SDMDC at a 4 ms delay


def test_the_computer_reads_the_noise_the_record_shows(tmp_path):
    noise = MeasurementNoiseParams(1.5, 1e-6, seed=3, ar1_coefficient=0.0)
    run, _ = record_run(_info("SDMDC"), noise=noise)
    written = write_run(run, tmp_path, "run1")
    back = read_runs([written.csv_path])[0]
    for c in ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s"):
        np.testing.assert_array_equal(getattr(back, c), getattr(run, c))
    # The audit solves the computer's arithmetic from the noisy readings:
    # exact (no finding), the mass, lead and stiffness of the JSON.
    audit = audit_runs([back])
    assert audit.findings == []
    est = audit.estimates[0]
    assert est.mass_kg == pytest.approx(M, rel=1e-8)
    assert est.lead_time_s == pytest.approx(0.004, rel=1e-8)
    assert est.stiffness_n_per_m == pytest.approx(K, rel=1e-6)
    # Before the touch the force reading is the noise alone.
    quiet = slice(0, 20)
    np.testing.assert_allclose(run.f_mea_n[quiet], noise_series(noise, "force", 20), atol=1e-9)


def test_ar1_noise_has_the_asked_deviation_and_correlation():
    noise = MeasurementNoiseParams(2.0, 1e-6, seed=11, ar1_coefficient=0.8)
    e = noise_series(noise, "force", 20000)
    assert np.std(e) == pytest.approx(2.0, rel=0.05)
    assert np.corrcoef(e[1:], e[:-1])[0, 1] == pytest.approx(0.8, abs=0.02)
    # The same samples whatever the length asked (a function of the tick).
    np.testing.assert_array_equal(noise_series(noise, "force", 5000), e[:5000])
    w = noise_series(MeasurementNoiseParams(2.0, 0.0, seed=11), "force", 20000)
    assert abs(np.corrcoef(w[1:], w[:-1])[0, 1]) < 0.03


def test_hidden_damping_is_in_the_signals_not_in_the_json():
    c = 300.0
    zeta = c / (2.0 * math.sqrt(K * M))
    physics = ModelSpec().with_contact(damping_n_s_per_m=c).physics()
    nominal, t0 = record_run(_info("none"))
    damped, t1 = record_run(_info("none"), physics)
    assert damped.info == nominal.info
    # ln CoR adds up: the damping's loss exp(-pi zeta / sqrt(1 - zeta^2)) on
    # top of the delay's gain (to first order in both).
    expected = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2))
    assert t1["cor"] / t0["cor"] == pytest.approx(expected, abs=0.01)
    assert t1["cor"] < t0["cor"]


def test_bad_requests_get_one_clear_error(tmp_path):
    with pytest.raises(ParameterError, match="run format"):
        record_run(_info("smith"))
    with pytest.raises(ParameterError, match="ar1_coefficient"):
        MeasurementNoiseParams(1.0, 0.0, 0, ar1_coefficient=1.0)
    with pytest.raises(ParameterError, match="seed"):
        MeasurementNoiseParams(1.0, 0.0, -1)
    run, _ = record_run(_info(), duration_s=1.0)
    write_run(run, tmp_path, "run1")
    with pytest.raises(CommandError, match="--force"):
        write_run(run, tmp_path, "run1")
    write_run(run, tmp_path, "run1", force=True)
    with pytest.raises(Exception, match="still in contact"):
        record_run(_info(), duration_s=0.1)
