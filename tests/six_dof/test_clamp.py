"""The 1-D run format's clamp and dead band on the wrench compensator
(``[compensator] clamp_nonnegative``, ``deadband_reading = "axial_force"``):
on axis the 6-DoF loop with them is the 1-D loop with its clamp."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.errors import ParameterError
from hybridtable.loop.fast import simulate_fast
from hybridtable.loop.params import HybridLoopParams
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.conftest import docking_params


def _on_axis(**kwargs):
    return docking_params(
        compensator="SDMDC",
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        table_damping_ratio=0.8,
        **kwargs,
    )


def test_unclamped_the_wrench_compensator_pulls_and_clamped_it_never_does():
    free = simulate6(_on_axis()).log["compensated_wrench"][:, 5]
    assert free.max() > 10.0  # SDMDC's lead pulls at the release (fz > 0 on the spacecraft)
    clamped = simulate6(_on_axis(clamp_nonnegative=True)).log["compensated_wrench"]
    assert clamped[:, 5].max() <= 0.0
    pulled = np.flatnonzero(free > 0.0)
    assert np.all(clamped[pulled] == 0.0)  # the whole wrench, as the 1-D clamp zeroes f_comp


@pytest.mark.parametrize("reading", ["force_norm", "axial_force"])
def test_on_axis_the_clamped_loop_is_the_1d_loop_with_its_clamp(reading):
    six = simulate6(
        _on_axis(clamp_nonnegative=True, deadband_reading=reading, force_deadband_n=5.0)
    )
    one = simulate_fast(
        HybridLoopParams(
            spacecraft_mass_kg=1e5 / (2.0 * math.pi) ** 2,
            contact_stiffness_n_per_m=1e5,
            compensator="SDMDC",
            sample_rate_hz=1000.0,
            sensor_delay_s=0.005,
            table_response_hz=25.0,
            table_damping_ratio=0.8,
            initial_gap_m=0.001,
            force_deadband_n=5.0,
            clamp_nonnegative=True,
        )
    )
    assert six.metrics.cor_normal == pytest.approx(one.cor, rel=1e-9)


def test_a_bad_option_is_named():
    with pytest.raises(ParameterError, match="deadband_reading"):
        _on_axis(deadband_reading="normal")
    with pytest.raises(ParameterError, match="clamp_nonnegative"):
        _on_axis(clamp_nonnegative="yes")
