"""Gain, phase and delay margins (hybridtable.analysis.robustness): closed forms of
the delayed spring-mass contact, what the gain and delay margins mean on the
rig (a lighter spacecraft model, an extra delay), and the delay a CoR limit
allows."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.exact_delay import exact_growth
from hybridtable.analysis.margins import (
    critical_sensor_delay,
    growth_of,
    loop_margins,
    phase_margin_at_contact,
)
from hybridtable.analysis.robustness import (
    cor_limited_delay,
    cor_limited_delay_on_grid,
    cor_limited_table_on_grid,
    gain_delay_margins,
    predicted_cor_of,
)
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.studies.paper import paper_params, table1_params
from tests.analysis.support import damped


def _spring_mass(delay_s: float, zeta: float = 0.0):
    """``m s^2 + (c s + k) e^{-sT}``: an ideal table, no compensator."""
    p = paper_params(sensor_delay_s=delay_s, table_response_hz=math.inf)
    return damped(p, zeta) if zeta else p


def _kmc(p):
    return p.contact_stiffness_n_per_m, p.spacecraft_mass_kg, p.contact_damping_n_s_per_m


# -- closed forms ------------------------------------------------------------------


@pytest.mark.parametrize("delay_s", [0.001, 0.005, 0.02])
def test_undamped_spring_mass_with_a_delay_has_phase_margin_minus_w_t(lin, delay_s):
    """``L = k e^{-sT} / (m s^2)``: |L| = 1 at ``w_con``, where the delay
    takes ``w_con T`` from -180 deg: ``pm = -w_con T``, delay margin ``-T``."""
    p = _spring_mass(delay_s)
    k, m, _ = _kmc(p)
    w = math.sqrt(k / m)
    g = gain_delay_margins(lin.open_loop(p))
    assert g.gain_crossover_rad_per_s == pytest.approx(w, rel=1e-9)
    assert g.phase_margin_deg == pytest.approx(-math.degrees(w * delay_s), rel=1e-9)
    assert g.delay_margin_s == pytest.approx(-delay_s, rel=1e-9)
    assert not g.closed_loop_stable


def test_perfect_rig_undamped_contact_has_no_margin_at_all(lin):
    """Phase -180 deg at every frequency: pm = 0, no phase crossover counted
    (gm = inf), delay margin 0, and the loop only marginal."""
    g = gain_delay_margins(lin.open_loop(_spring_mass(0.0)))
    assert g.phase_margin_deg == pytest.approx(0.0, abs=1e-9)
    assert g.delay_margin_s == pytest.approx(0.0, abs=1e-12)
    assert math.isinf(g.gain_margin) and math.isnan(g.phase_crossover_rad_per_s)
    assert not g.closed_loop_stable


@pytest.mark.parametrize("delay_s", [0.002, 0.005])
def test_damped_spring_mass_margins_are_the_closed_forms(delay_s):
    """``L = (k + c s) e^{-sT} / (m s^2)``: ``m^2 w^4 = k^2 + c^2 w^2`` at the
    gain crossover, ``pm = atan(c w / k) - w T``; the phase crossover solves
    ``atan(c w / k) = w T``, ``gm = m w^2 / |k + i c w|`` (Pade order 8: the
    phase crossover is at w T ~ 1.4, where order 3 is off by 1e-4)."""
    p = _spring_mass(delay_s, zeta=0.05)
    k, m, c = _kmc(p)
    wgc = math.sqrt((c * c + math.sqrt(c**4 + 4 * m * m * k * k)) / (2 * m * m))
    wpc = brentq(lambda w: math.atan(c * w / k) - w * delay_s, 1.0, 1e4)
    gm = m * wpc**2 / math.hypot(k, c * wpc)
    for order, rtol in ((8, 1e-9), (3, 2e-4)):
        g = gain_delay_margins(ContactLoopLinearizer(order).open_loop(p))
        assert g.gain_crossover_rad_per_s == pytest.approx(wgc, rel=1e-9)
        pm = math.atan(c * wgc / k) - wgc * delay_s
        assert g.phase_margin_deg == pytest.approx(math.degrees(pm), rel=1e-8)
        assert g.delay_margin_s == pytest.approx(pm / wgc, rel=1e-8)
        assert g.phase_crossover_rad_per_s == pytest.approx(wpc, rel=rtol)
        assert g.gain_margin == pytest.approx(gm, rel=rtol)
        assert g.gain_margin_db == pytest.approx(20 * math.log10(g.gain_margin), rel=1e-12)
        assert g.closed_loop_stable


def test_delay_margin_is_the_critical_delay_minus_the_delay(lin):
    """No compensator: the only path is the sensor's, so the delay margin is
    the extra sensor delay to the stability boundary (exact delay:
    ``atan(c w / k) / w - T``)."""
    p = _spring_mass(0.004, zeta=0.05)
    g = gain_delay_margins(lin.open_loop(p))
    crit = critical_sensor_delay(exact_growth(lin), p)
    assert g.delay_margin_s == pytest.approx(crit - 0.004, rel=1e-6)
    # ... and on the rig with a slow table: the Pade model's own critical delay.
    q = damped(table1_params("none"), 0.05)
    g = gain_delay_margins(lin.open_loop(q))
    crit = critical_sensor_delay(growth_of(lin.open_loop), q)
    assert g.delay_margin_s == pytest.approx(crit - q.sensor_delay_s, rel=1e-4)


# -- what the gain margin means on the rig ----------------------------------------------


@pytest.mark.parametrize("sampled", [False, True])
def test_gain_margin_is_how_much_lighter_the_spacecraft_model_may_be(lin, sampled):
    """The spacecraft model ``1 / (m s^2)`` sits right behind the break: a
    force path scaled by g is a model of mass m / g. Just below gm the loop
    is stable, just above it unstable (continuous, and the sampled model's
    python-control FRD margins)."""
    p = damped(table1_params("none"), 0.05)
    model = lin.open_loop
    if sampled:
        p = p.with_(sample_rate_hz=1000.0)
        model = SampledLoopLinearizer(lin).open_loop
    g = gain_delay_margins(model(p))
    assert g.closed_loop_stable and 2.0 < g.gain_margin < 1e3
    m = p.spacecraft_mass_kg
    for factor, stable in ((0.99, True), (1.01, False)):
        q = p.with_(spacecraft_mass_kg=m / (g.gain_margin * factor))
        assert loop_margins(model(q), "fast").stable is stable, factor


@pytest.mark.parametrize("comp", ["none", "MDC", "SDMDC"])
@pytest.mark.parametrize("rate", [None, 1000.0])
def test_the_phase_margin_is_the_one_of_the_contact_crossover(lin, comp, rate):
    """The same phase margin and crossover as the existing contact-crossover
    figure (python-control there too)."""
    p = table1_params(comp).with_(sample_rate_hz=rate)
    loop = (SampledLoopLinearizer(lin) if rate else lin).open_loop(p)
    g = gain_delay_margins(loop)
    pm, wgc = phase_margin_at_contact(loop, "python-control")
    assert g.phase_margin_deg == pytest.approx(pm, abs=1e-6)
    assert g.gain_crossover_rad_per_s == pytest.approx(wgc, rel=1e-6)


# -- the delay a CoR limit allows --------------------------------------------------------


def test_cor_limited_delay_is_where_the_cor_reaches_the_limit(lin):
    p = table1_params("MDC")  # CoR 1 at zero delay, growing with it
    cor = predicted_cor_of(lin.open_loop)
    T = cor_limited_delay(cor, p, 1.01)
    assert 0.0 < T < 0.005
    assert cor(p.with_(sensor_delay_s=T)) == pytest.approx(1.01, abs=1e-9)
    assert cor(p.with_(sensor_delay_s=0.9 * T)) < 1.01
    # Above the limit at zero delay (a 25 Hz table's lag, no compensation): 0.
    assert cor_limited_delay(cor, table1_params("none"), 1.01) == 0.0
    # Within it up to the search's end: inf.
    assert math.isinf(cor_limited_delay(cor, p, 5.0, max_delay_s=0.02))


def test_cor_limited_delay_sampled_is_refined_within_the_tick(lin):
    p = table1_params("MDC").with_(sample_rate_hz=1000.0)
    cor = predicted_cor_of(SampledLoopLinearizer(lin).open_loop)
    T = cor_limited_delay(cor, p, 1.02)
    n = math.floor(T * 1000.0)
    assert n >= 1 and abs(T * 1000.0 - round(T * 1000.0)) > 1e-3  # between two ticks
    # The CoR is continuous in the delay (two taps mixed): the limit is met there.
    assert cor(p.with_(sensor_delay_s=T)) == pytest.approx(1.02, abs=1e-9)
    assert (
        cor(p.with_(sensor_delay_s=n * 1e-3)) <= 1.02 < cor(p.with_(sensor_delay_s=(n + 1) * 1e-3))
    )


def test_cor_limits_read_off_a_grid():
    d = np.array([0.0, 0.001, 0.002])
    assert cor_limited_delay_on_grid(d, [1.0, 1.005, 1.015], 1.01) == pytest.approx(0.0015)
    assert cor_limited_delay_on_grid(d, [1.0, 1.005, 1.015], 1.01, interpolate=False) == 0.001
    assert cor_limited_delay_on_grid(d, [1.02, 1.03, 1.04], 1.01) == 0.0
    assert math.isinf(cor_limited_delay_on_grid(d, [1.0, 1.0, 1.0], 1.01))
    assert cor_limited_delay_on_grid(d, [1.0, math.nan, 1.0], 1.01) == 0.0  # NaN: an excess
    f = np.array([5.0, 10.0, 20.0])
    assert cor_limited_table_on_grid(f, [1.03, 1.02, 1.0], 1.01) == pytest.approx(15.0)
    assert cor_limited_table_on_grid(f, [1.0, 1.0, 1.0], 1.01) == 0.0
    assert math.isinf(cor_limited_table_on_grid(f, [1.03, 1.02, 1.02], 1.01))
