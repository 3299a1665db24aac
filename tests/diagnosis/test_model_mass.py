"""The mass the rig computer's spacecraft model integrates with: one rule
(:func:`~hybridtable.measurement.rig.model_mass_kg`), the same in a model's
closed loop and in its linear models."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.effects.model_file import FittedEffect, RigModel
from hybridtable.effects.spec import RigScale
from hybridtable.measurement.rig import model_mass_kg, rig_params, run_with_model_mass
from hybridtable.measurement.run_format import Run, RunInfo

INFO = RunInfo(
    run_id="r1",
    sample_rate_hz=1000.0,
    spacecraft_mass_kg=675.475,
    contact_stiffness_n_per_m=6.0e4,
    sensor_delay_s=0.004,
    table_natural_frequency_hz=30.0,
    table_damping_ratio=0.7,
    compensator="SDC",
    lead_time_s=0.004,
    initial_gap_m=0.002,
    initial_velocity_m_per_s=0.08,
    force_deadband_n=6.0,
)
_EMPTY = np.zeros(1)
RUN = Run(INFO, _EMPTY, _EMPTY, _EMPTY, _EMPTY, _EMPTY, _EMPTY)


def _model(mass_ratio: float) -> RigModel:
    effects = () if mass_ratio == 1.0 else (FittedEffect("mass_error", {"mass_ratio": mass_ratio}),)
    return RigModel(nominal=INFO, scale=RigScale.from_info(INFO), effects=effects)


def test_the_computer_integrates_with_the_ratio_times_the_stated_mass():
    assert model_mass_kg(675.475, 1.05) == 675.475 * 1.05
    assert model_mass_kg(675.475) == 675.475
    assert run_with_model_mass(RUN, 1.0) is RUN
    assert run_with_model_mass(RUN, 1.05).info.spacecraft_mass_kg == 675.475 * 1.05
    assert RUN.info.spacecraft_mass_kg == 675.475


@pytest.mark.parametrize("ratio", [1.0, 0.8, 1.05])
def test_closed_loop_and_linear_models_integrate_with_the_same_mass(ratio):
    model = _model(ratio)
    expected = model_mass_kg(INFO.spacecraft_mass_kg, ratio)
    closed = model.physics().apply(rig_params(model.closed_loop_run(RUN).info))
    linear, _ = model.linear_params(rig_params(INFO))
    assert closed.spacecraft_mass_kg == expected
    assert linear.spacecraft_mass_kg == expected
    # The physics alone (the replay) does not see the ratio.
    assert model.physics().apply(rig_params(INFO)).spacecraft_mass_kg == INFO.spacecraft_mass_kg


@pytest.mark.parametrize("ratio", [1.0, 1.05])
def test_an_audited_mass_wins_over_the_ratio_in_every_loop(ratio):
    from dataclasses import replace

    audited = 700.0
    model = replace(_model(ratio), computer={"spacecraft_mass_kg": audited})
    closed = model.physics().apply(rig_params(model.closed_loop_run(RUN).info))
    linear, _ = model.linear_params(rig_params(INFO))
    assert closed.spacecraft_mass_kg == linear.spacecraft_mass_kg == audited
