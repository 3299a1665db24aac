"""A deadband of 0 (the paper's rig model): the sensor's noise passes the gate
in free flight, so f_comp is noise before and after the contact. The CoR is
measured over the contact the readings show, and such a run is compared, not
refused (measurement.phases.record_cor)."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.measurement.comparison import compare_run
from hybridtable.measurement.phases import contact_reading, cor_from_record, record_cor
from hybridtable.measurement.run_reader import read_runs
from tests.generators import rigsim


def _record(tmp_path, compensator: str, deadband_n: float, noise_f_n: float, seed: int):
    info = dict(
        rigsim.NOMINAL,
        force_deadband_n=deadband_n,
        compensator=compensator,
        run_id=f"{compensator}-{deadband_n:g}-{noise_f_n:g}",
    )
    cols = rigsim.simulate_record(
        info, seed=seed, noise_f_n=noise_f_n, noise_p_m=2e-6 if noise_f_n else 0.0
    )
    folder = tmp_path / info["run_id"]
    rigsim.write_run(folder, "run", info, cols)
    (run,) = read_runs([folder])
    return run


@pytest.mark.parametrize("compensator", ["none", "SDC", "SDMDC"])
def test_the_cor_of_a_noisy_zero_deadband_run_is_the_noise_free_one(tmp_path, compensator):
    clean = _record(tmp_path, compensator, 0.0, 0.0, seed=4)
    noisy = _record(tmp_path, compensator, 0.0, 2.0, seed=4)
    # the noise passes the gate: f_comp is non-zero on many free-flight ticks
    assert contact_reading(noisy) is not None
    assert np.count_nonzero(noisy.f_comp_n[:3]) or np.count_nonzero(noisy.f_comp_n[-20:])
    cor_clean = record_cor(clean)[0]
    cor_noisy = record_cor(noisy)[0]
    assert cor_noisy == pytest.approx(cor_clean, abs=2e-3)
    # the old rule (first non-zero f_comp to the last tick) is biased or refuses
    try:
        old = cor_from_record(noisy.v_des_m_per_s, noisy.f_comp_n, 0.08)[0]
    except ValueError:
        return
    assert abs(old - cor_clean) > abs(cor_noisy - cor_clean)


def test_a_gating_deadband_keeps_the_rule_of_non_zero_f_comp(tmp_path):
    run = _record(tmp_path, "SDMDC", 6.0, 0.0, seed=1)
    assert contact_reading(run) is None
    v = run.v_des_m_per_s
    assert record_cor(run) == (abs(v[-1]) / 0.08, 0.08, v[-1])


def test_a_contact_that_lasts_to_the_end_is_still_refused(tmp_path):
    run = _record(tmp_path, "none", 0.0, 2.0, seed=2)
    end = int(np.flatnonzero(contact_reading(run))[len(np.flatnonzero(contact_reading(run))) // 2])
    with pytest.raises(ValueError, match="has not ended"):
        cor_from_record(
            run.v_des_m_per_s[:end], run.f_comp_n[:end], 0.08, contact_reading(run)[:end]
        )


@pytest.mark.slow
def test_compare_reads_a_zero_deadband_run_within_the_noise(tmp_path):
    run = _record(tmp_path, "SDC", 0.0, 2.0, seed=3)
    c = compare_run(run)
    assert c.within_noise("f_mea_n") and c.within_noise("p_act_m")
    assert c.cor_matches()
