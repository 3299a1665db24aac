"""The fast path reproduces the Drake diagram: the same CoR on the paper's points,
on sampled, damped, dead-banded, ideal-table and switching loops; the exact
energy balance of an elastic bounce; the same divergence and refusals."""

import math

import pytest

from hybridtable.errors import DivergenceError, ParameterError, SimulationError
from hybridtable.loop.fast import fast_unsupported, simulate_fast
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import paper_params, table1_params, table2_params, table2_rows

#: CoR agreement demanded of the fast path against the diagram: the paper needs 1e-4;
#: both integrate the same update, and differ by the diagram integrator's error (<= 3e-7).
COR_TOL = 1e-6


def _agree(params, diagram=None):
    """The fast path against the diagram's run of ``params`` (``diagram``: that
    run, already simulated)."""
    fast = simulate_fast(params)
    diagram = (diagram or simulate(params)).metrics
    assert fast.cor == pytest.approx(diagram.cor, abs=COR_TOL)
    assert fast.v_in_m_per_s == diagram.v_in_m_per_s
    # Peaks are sampled at the ticks by both (the diagram also between them).
    assert fast.peak_force_n == pytest.approx(diagram.peak_force_n, rel=1e-3)
    assert fast.contact_duration_s == pytest.approx(diagram.contact_duration_s, abs=3e-4)
    return fast, diagram


@pytest.mark.parametrize("row", range(len(table2_rows())))
def test_table2_points_match_the_diagram(row, table2_run):
    _agree(table2_params(table2_rows()[row]), table2_run(row))


@pytest.mark.parametrize("compensator", ["none", "SDC", "MDC", "SDMDC"])
def test_table1_compensators_match_the_diagram(compensator, paper_run):
    fast, _ = _agree(table1_params(compensator), paper_run(compensator))
    # The paper's ordering: each compensator removes more of the delay's energy.
    if compensator == "SDMDC":
        assert fast.cor == pytest.approx(1.0, abs=1e-3)
    else:
        assert fast.cor > 1.01


@pytest.mark.parametrize(
    "changes",
    [
        {"sample_rate_hz": 1000.0},  # 5 ms = 5 ticks
        {"sample_rate_hz": 1000.0, "clamp_nonnegative": True, "contact_gate": "table_position"},
        {"force_deadband_n": 50.0},
        {"table_response_hz": math.inf},
        {"table_initial_state": "rest"},
        {"clamp_nonnegative": True, "contact_gate": "table_position"},
        {"sensor_delay_s": 0.0},  # the gate follows the contact: switches inside ticks
    ],
    ids=[
        "sampled",
        "sampled-clamp-position",
        "deadband",
        "ideal-table",
        "rest",
        "clamp",
        "no-delay",
    ],
)
def test_variants_match_the_diagram(changes):
    _agree(table1_params("SDMDC").with_(**changes))


def test_damped_contact_matches_the_diagram_and_loses_energy():
    fast, _ = _agree(table1_params("SDMDC").with_contact_damping_ratio(0.1))
    # Contact damping dissipates: a damping ratio of 0.1 costs about a quarter of v.
    assert 0.6 < fast.cor < 0.9
    assert fast.energy_gain_j < 0.0


def test_undelayed_ideal_undamped_bounce_conserves_energy_exactly():
    p = paper_params(sensor_delay_s=0.0, table_response_hz=math.inf)
    m = simulate_fast(p)
    k, mass, v0 = p.contact_stiffness_n_per_m, p.spacecraft_mass_kg, p.initial_velocity_m_per_s
    assert m.cor == pytest.approx(1.0, abs=1e-9)
    assert m.v_out_m_per_s == pytest.approx(-v0, abs=1e-10)
    # Half a contact period in contact; peak force v sqrt(k m) (sampled at the ticks).
    assert m.contact_duration_s == pytest.approx(math.pi * math.sqrt(mass / k), abs=p.step_s)
    assert m.peak_force_n == pytest.approx(v0 * math.sqrt(k * mass), rel=1e-6)


def test_divergent_loop_raises_as_the_diagram_does():
    # No compensation, a delay of 0.5 s on a 50 Hz contact: the force grows past
    # 100 v sqrt(k m) before the spacecraft leaves.
    p = paper_params(sensor_delay_s=0.5, contact_frequency_hz=50.0, time_step_s=2e-4)
    with pytest.raises(DivergenceError, match="diverged by t = ") as fast:
        simulate_fast(p)
    with pytest.raises(DivergenceError) as diagram:
        simulate(p)
    assert str(fast.value) == str(diagram.value)


def test_contact_that_never_ends_is_reported():
    # Every reading is inside the deadband: the model never feels the contact.
    with pytest.raises(SimulationError, match="force_deadband_n"):
        simulate_fast(table1_params("none", force_deadband_n=1e6))


@pytest.mark.parametrize(
    "changes, words",
    [({"compensator": "smith"}, "plug-in compensator"), ({"passivity": True}, "passivity")],
)
def test_unsupported_parameters_are_refused_with_a_reason(changes, words):
    p = table1_params("SDMDC").with_(**changes)
    assert words in fast_unsupported(p)
    with pytest.raises(ParameterError, match=words):
        simulate_fast(p)


def test_paper_parameters_are_supported():
    for c in ("none", "SDC", "MDC", "SDMDC"):
        assert fast_unsupported(table1_params(c, sample_rate_hz=1000.0)) is None
        assert fast_unsupported(table1_params(c).with_contact_damping_ratio(0.3)) is None
