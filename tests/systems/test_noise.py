"""Seeded measurement noise: white, of the given standard deviation, on force
and position only; a noisy loop with every plug-in stays close to the clean one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable import Compensator
from hybridtable.compensators.registry import (
    make_compensator,
)
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import run_loop
from hybridtable.studies.paper import table1_params
from hybridtable.systems.noise import (
    MeasurementNoise,
    MeasurementNoiseParams,
    noise_sample,
    with_measurement_noise,
)
from tests.compensators.support import PLUGINS, compensator_inputs, run_ticks


def test_noise_sequence_is_seeded_white_and_of_the_given_std():
    a = np.array([noise_sample(7, 0, i) for i in range(20000)])
    assert np.array_equal(a[:100], [noise_sample(7, 0, i) for i in range(100)])
    assert not np.array_equal(a[:100], [noise_sample(8, 0, i) for i in range(100)])
    assert abs(a.mean()) < 0.03 and abs(a.std() - 1.0) < 0.02
    assert abs(np.corrcoef(a[:-1], a[1:])[0, 1]) < 0.03


def test_noise_is_added_to_force_and_position_only():
    params = MeasurementNoiseParams(force_std_n=2.0, position_std_m=1e-6, seed=3)
    noise = MeasurementNoise(params, 1e-3)
    inner = Compensator(table1_params("none").compensator_params(), 1e-3)
    system = with_measurement_noise(inner, params, 1e-3)
    n = 5
    y = run_ticks(system, compensator_inputs(n, f=100.0))[:, 0]
    assert y == pytest.approx(100.0 + 2.0 * np.array([noise_sample(3, 0, k) for k in range(n)]))
    ctx = noise.CreateDefaultContext()
    noise.GetInputPort("measured_force").FixValue(ctx, [0.0])
    noise.GetInputPort("table_motion").FixValue(ctx, [1e-3, 0.1, 2.0])
    motion = noise.GetOutputPort("table_motion").Eval(ctx)
    assert motion == pytest.approx([1e-3 + 1e-6 * noise_sample(3, 1, 0), 0.1, 2.0])


def test_noisy_loop_with_every_plugin_runs_and_stays_close():
    base = table1_params("none")
    f0 = base.initial_velocity_m_per_s * math.sqrt(1e5 * base.spacecraft_mass_kg)
    noise = MeasurementNoiseParams(1e-3 * f0, 1e-6, seed=1)
    for name in PLUGINS:
        p = table1_params(name, force_deadband_n=5e-3 * f0)
        h = build_hybrid_loop(p, log=False).computer_period_s
        comp = with_measurement_noise(make_compensator(p, h), noise, h)
        cor = run_loop(build_hybrid_loop(p, compensator=comp)).metrics.cor
        assert abs(cor - 1.0) < 0.01, name
