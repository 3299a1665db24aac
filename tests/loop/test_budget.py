"""The simulation budget: predicted steps from closed forms, refusals in one line."""

from __future__ import annotations

import math

import pytest

from hybridtable.errors import SimulationError
from hybridtable.laws import separation
from hybridtable.loop import budget
from hybridtable.loop.budget import (
    SAMPLED_MEAN_STEP_S,
    SAMPLED_TICK_STEPS,
    STABLE_STEP_RAD,
    check_budget,
    check_steps_taken,
    estimate_cost,
    fastest_pole_rad_per_s,
)
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import paper_params


def test_fastest_pole_is_the_closed_form_of_each_second_order_part():
    # An overdamped table: omega (zeta + sqrt(zeta^2 - 1)).
    p = paper_params(table_response_hz=100.0, table_damping_ratio=3.0, sample_rate_hz=1000.0)
    pole, source = fastest_pole_rad_per_s(p)
    w = 2 * math.pi * 100.0
    assert pole == pytest.approx(w * (3.0 + math.sqrt(8.0)), rel=1e-12)
    assert "table" in source
    # Underdamped: omega. A continuous loop adds the contact's sqrt(k / m).
    p = paper_params(table_response_hz=5.0, contact_frequency_hz=40.0)
    pole, source = fastest_pole_rad_per_s(p)
    assert pole == pytest.approx(2 * math.pi * 40.0, rel=1e-9) and "contact" in source
    # A sampled rig computer steps the spacecraft itself: the contact is not integrated.
    p = paper_params(table_response_hz=5.0, contact_frequency_hz=40.0, sample_rate_hz=1000.0)
    assert fastest_pole_rad_per_s(p)[0] == pytest.approx(2 * math.pi * 5.0)


def test_cost_is_duration_over_the_step_the_dynamics_allow():
    p = paper_params()  # continuous, 1 Hz contact, 25 Hz table: the chosen step rules
    cost = estimate_cost(p, 2.0, p.step_s)
    assert not cost.stiff and cost.steps == pytest.approx(2.0 / p.step_s)
    # A stiff overdamped table: the explicit step is 2.5 / pole.
    p = paper_params(table_response_hz=1e4, table_damping_ratio=10.0, sample_rate_hz=1000.0)
    cost = estimate_cost(p, 1.0, 1e-3)
    pole = 2 * math.pi * 1e4 * (10.0 + math.sqrt(99.0))
    assert cost.stiff and cost.step_s == pytest.approx(STABLE_STEP_RAD / pole)
    # The same table sampled exactly (not integrated): one step per tick, and
    # each tick's own cost.
    cost = estimate_cost(p, 1.0, 1e-3, integrated=False)
    assert not cost.stiff and cost.steps == pytest.approx(1000.0 * (1 + SAMPLED_TICK_STEPS))
    # A sampled loop with an integrated table: the mean error-controlled step.
    p = paper_params(sample_rate_hz=1000.0)
    assert estimate_cost(p, 1.0, 1e-3).step_s == SAMPLED_MEAN_STEP_S


def test_a_day_long_approach_is_refused_as_too_long():
    p = paper_params(initial_gap_m=10.0, initial_velocity_m_per_s=1e-4, sample_rate_hz=1000.0)
    with pytest.raises(SimulationError, match=r"^too long to simulate: the run lasts 1e\+05 s"):
        simulate(p)


def test_a_stiff_table_is_refused_before_simulating():
    p = paper_params(table_response_hz=1e4, table_damping_ratio=10.0, sample_rate_hz=1000.0)
    with pytest.raises(SimulationError, match="^too stiff to simulate: the table's fastest pole"):
        check_budget(p, 11.0, 1e-3)
    # A continuous loop at a nanosecond step: too long, whatever the poles.
    p = paper_params(time_step_s=1e-9)
    with pytest.raises(SimulationError, match="^too long to simulate: .*time_step_s"):
        simulate(p)


def test_the_running_guard_stops_a_run_past_the_budget(monkeypatch):
    with pytest.raises(SimulationError, match=r"took 1\.1e\+03 steps by t = 0\.5 s"):
        check_steps_taken(1100, 0.5, budget=1000)
    check_steps_taken(1000, 0.5, budget=1000)  # at the budget: fine
    # A run the estimate lets through is stopped by the steps it really takes.
    p = paper_params(sample_rate_hz=1000.0)
    monkeypatch.setattr(budget, "MAX_INTEGRATOR_STEPS", 5000)
    monkeypatch.setattr(separation, "MAX_INTEGRATOR_STEPS", 5000)  # the running guard's
    monkeypatch.setattr(budget, "SAMPLED_MEAN_STEP_S", 1.0)  # estimate: 1 step per tick
    monkeypatch.setattr(budget, "SAMPLED_TICK_STEPS", 0.0)
    with pytest.raises(SimulationError, match="too stiff to simulate: the integrator took"):
        simulate(p)
