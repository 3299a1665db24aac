"""Stability figures of the linear loop (hybridtable.analysis.margins, hybridtable.analysis.exact_delay):
closed forms of the delayed contact, the paper's Table 1, the sampled loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.exact_delay import exact_contact_root, exact_growth, exact_margins
from hybridtable.analysis.margins import (
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    ideal_crossover_frequency,
    loop_margins,
    phase_margin_at_contact,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import load_tables, paper_params, table1_params
from tests.analysis.support import damped

# -- closed forms ------------------------------------------------------------------


def test_perfect_rig_undamped_contact_is_marginal(lin):
    p = paper_params(sensor_delay_s=0.0, table_response_hz=math.inf)
    m = loop_margins(lin.open_loop(p))
    w = math.sqrt(p.contact_stiffness_n_per_m / p.spacecraft_mass_kg)
    assert m.contact_pole == pytest.approx(1j * w, abs=1e-9 * w)
    assert m.predicted_cor == pytest.approx(1.0, abs=1e-9)
    assert m.phase_margin_deg == pytest.approx(0.0, abs=1e-7)
    assert m.effective_delay_s == pytest.approx(0.0, abs=1e-9)
    assert not m.stable  # marginal is not stable


@pytest.mark.parametrize("zeta", [0.05, 0.3])
def test_perfect_rig_damped_contact_cor_is_the_oscillator_formula(lin, zeta):
    p = damped(paper_params(sensor_delay_s=0.0, table_response_hz=math.inf), zeta)
    m = loop_margins(lin.open_loop(p))
    assert m.damping_ratio == pytest.approx(zeta, rel=1e-9)
    assert m.predicted_cor == pytest.approx(
        math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)), rel=1e-9
    )
    assert m.stable


@pytest.mark.parametrize("table_hz", [math.inf, 25.0, 5.0])
def test_undamped_uncompensated_loop_has_critical_delay_zero(lin, table_hz):
    p = paper_params(table_response_hz=table_hz)
    assert critical_sensor_delay(growth_of(lin.open_loop), p) == 0.0
    assert critical_sensor_delay(exact_growth(lin), p) == 0.0
    # ... and every delay makes it gain energy.
    for T in (1e-4, 0.005, 0.02):
        m = loop_margins(lin.open_loop(p.with_(sensor_delay_s=T)), "fast")
        assert m.energy_growth_per_contact > 0.0
        assert m.predicted_cor > 1.0


@pytest.mark.parametrize("zeta", [0.02, 0.1, 0.4])
def test_damped_contact_ideal_table_critical_delay_closed_form(lin, zeta):
    # m s^2 + (c s + k) e^{-sT}: at the crossover w_c (m w^2 = |k + i c w|)
    # the contact's phase lead atan(c w_c / k) is used up by w_c T.
    p = damped(paper_params(table_response_hz=math.inf), zeta)
    k, c = p.contact_stiffness_n_per_m, p.contact_damping_n_s_per_m
    w = ideal_crossover_frequency(p)
    assert p.spacecraft_mass_kg * w**2 == pytest.approx(abs(k + 1j * c * w), rel=1e-12)
    expected = math.atan(c * w / k) / w
    assert critical_sensor_delay(exact_growth(lin), p) == pytest.approx(expected, rel=1e-8)
    assert critical_sensor_delay(growth_of(lin.open_loop), p) == pytest.approx(expected, rel=1e-4)
    # The phase margin of the undelayed loop is that same lead.
    pm, wgc = phase_margin_at_contact(lin.open_loop(p.with_(sensor_delay_s=0.0)))
    assert math.radians(pm) == pytest.approx(math.atan(c * w / k), rel=1e-7)
    assert wgc == pytest.approx(w, rel=1e-7)


def test_exact_root_solves_the_quasi_polynomial(lin):
    p = damped(paper_params(sensor_delay_s=0.03, table_response_hz=math.inf), 0.1)
    m, k, c, T = (
        p.spacecraft_mass_kg,
        p.contact_stiffness_n_per_m,
        p.contact_damping_n_s_per_m,
        p.sensor_delay_s,
    )
    s = exact_contact_root(lin, p)
    residual = m * s * s + (c * s + k) * np.exp(-s * T)
    assert abs(residual) < 1e-9 * k
    assert s.imag > 0


def test_pade_error_shrinks_with_order():
    p = paper_params(compensator="SDC", sensor_delay_s=0.02, table_response_hz=5.0)
    errs = [abs(exact_margins(ContactLoopLinearizer(n), p).pade_cor_error) for n in (1, 2, 3)]
    assert errs[0] > 1e-5
    assert errs[0] > 100 * errs[1] > 100 * 100 * errs[2]


def test_effective_delay_of_uncompensated_loop_is_delay_plus_table_lag(lin):
    # Low-frequency phase of the second-order table: w (2 zeta / w_t).
    p = paper_params(sensor_delay_s=0.004, table_response_hz=60.0)
    m = loop_margins(lin.open_loop(p))
    assert m.effective_delay_s == pytest.approx(p.effective_delay_s, rel=2e-3)
    # First-order CoR estimate exp(pi w tau / 2) of a small delay.
    assert m.predicted_cor == pytest.approx(
        math.exp(math.pi * m.crossover_rad_per_s * m.effective_delay_s / 2), rel=1e-3
    )


def test_fast_phase_margin_equals_python_control(lin):
    S = SampledLoopLinearizer(lin)
    for comp in COMPENSATORS:
        for p in (
            paper_params(compensator=comp, sensor_delay_s=0.011, table_response_hz=13.0),
            damped(paper_params(compensator=comp), 0.2),
        ):
            a = phase_margin_at_contact(lin.open_loop(p), "python-control")
            b = phase_margin_at_contact(lin.open_loop(p), "fast")
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-9)
        ps = paper_params(compensator=comp, sample_rate_hz=500.0, sensor_delay_s=0.006)
        a = phase_margin_at_contact(S.open_loop(ps), "python-control")
        b = phase_margin_at_contact(S.open_loop(ps), "fast")
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-6)


def test_critical_table_frequency_separates_stable_from_unstable(lin):
    p = damped(paper_params(sensor_delay_s=0.005), 0.1)
    f = critical_table_frequency(growth_of(lin.open_loop), p)
    assert 5.0 < f < 1000.0
    above = loop_margins(lin.open_loop(p.with_(table_response_hz=1.01 * f)), "fast")
    below = loop_margins(lin.open_loop(p.with_(table_response_hz=0.99 * f)), "fast")
    assert above.stable and not below.stable
    # No table stabilizes a delay beyond the ideal-table critical delay.
    T_ideal = critical_sensor_delay(growth_of(lin.open_loop), p.with_(table_response_hz=math.inf))
    p_late = p.with_(sensor_delay_s=1.05 * T_ideal)
    assert critical_table_frequency(growth_of(lin.open_loop), p_late) == math.inf


def test_sampled_critical_delay_is_where_the_growth_crosses_zero_within_a_tick(lin):
    S = SampledLoopLinearizer(lin)
    p = damped(paper_params(sample_rate_hz=1000.0, table_response_hz=math.inf), 0.1)
    growth = growth_of(S.open_loop)
    T = critical_sensor_delay(growth, p)
    # Between two ticks the sensor reads both samples mixed: the growth rate is
    # continuous in the delay, and the critical delay is its zero, not a tick.
    assert abs(T * 1000.0 - round(T * 1000.0)) > 1e-3
    assert growth(p.with_(sensor_delay_s=T - 1e-7)) < 0.0 < growth(p.with_(sensor_delay_s=T + 1e-7))
    assert loop_margins(S.open_loop(p.with_(sensor_delay_s=T + 1e-6)), "fast").stable is False
    assert loop_margins(S.open_loop(p.with_(sensor_delay_s=T - 1e-6)), "fast").stable is True
    # Sampling adds about half a period of delay to the continuous critical delay.
    Tc = critical_sensor_delay(exact_growth(lin), p)
    assert Tc - 2.5e-3 < T < Tc + 1e-3


def test_a_delay_between_ticks_is_the_two_taps_mixed(lin):
    """The sampled sensor at (M + alpha) h: (1 - alpha) z^-M + alpha z^-(M+1)."""
    S = SampledLoopLinearizer(lin)
    h = 1e-3
    block = S.sensor_block(3.4e-3, h)
    z = np.exp(1j * np.array([0.1, 0.7, 2.0]))
    expected = 0.6 * z**-3 + 0.4 * z**-4
    np.testing.assert_allclose(block.transfer(z)[:, 0, 0], expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("comp", ["none", "SDMDC"])
def test_sampled_model_cor_between_ticks_matches_sampled_simulation(lin, comp):
    p = table1_params(comp, sample_rate_hz=1000.0, sensor_delay_s=0.0034)
    predicted = loop_margins(SampledLoopLinearizer(lin).open_loop(p), "fast").predicted_cor
    assert predicted == pytest.approx(simulate(p).metrics.cor, abs=5e-4)


# -- against the nonlinear simulation ---------------------------------------------


@pytest.mark.parametrize("comp", COMPENSATORS)
def test_table1_predicted_cor_matches_continuous_simulation(lin, comp):
    p = table1_params(comp)
    predicted = loop_margins(lin.open_loop(p)).predicted_cor
    assert predicted == pytest.approx(simulate(p).metrics.cor, abs=0.002)
    paper = load_tables()["table1_simulation"]["cor"][comp]
    assert predicted == pytest.approx(paper, abs=0.002)


@pytest.mark.parametrize("comp", COMPENSATORS)
def test_sampled_model_cor_matches_sampled_simulation(lin, comp):
    p = table1_params(comp).with_(sample_rate_hz=1000.0)
    predicted = loop_margins(SampledLoopLinearizer(lin).open_loop(p), "fast").predicted_cor
    assert predicted == pytest.approx(simulate(p).metrics.cor, abs=5e-4)
