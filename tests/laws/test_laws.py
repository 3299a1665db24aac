"""The physics core: each law once, the same numbers on every scalar type.

A law of :mod:`hybridtable.laws` runs on floats (the fast engine, the 6-DoF
rig computer), numpy arrays (the wrench, the replay's samples), ``AutoDiffXd``
and symbolic expressions (compiled into Drake systems). These tests hold the
forms to each other and to closed forms.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.autodiffutils import AutoDiffXd
from pydrake.symbolic import Variable

from hybridtable.compensators.paper import Compensator, CompensatorParams
from hybridtable.errors import DivergenceError, SimulationError
from hybridtable.laws.compensation import CompensationLaw, compensate
from hybridtable.laws.contact import spring_contact_force
from hybridtable.laws.select import both, select
from hybridtable.laws.separation import SeparationRule
from hybridtable.laws.table import second_order_tick

LAWS = {
    "SDMDC gated": CompensationLaw(0.005, True, 2.0, "measured_force", False),
    "SDMDC clamped": CompensationLaw(0.005, True, 0.0, "measured_force", True),
    "MDC table-position": CompensationLaw(0.0, True, 0.0, "table_position", False),
    "SDC ungated": CompensationLaw(0.003, False, 0.0, "none", False),
}

# (f_mea, rate, dp, dv, p_act) samples crossing every switch
SAMPLES = [
    (150.0, 2e4, 1e-3, 0.02, 1e-3),
    (1.0, -5e3, 2e-4, -0.01, 2e-4),  # under the dead band
    (40.0, -2e4, -1e-3, 0.0, -1e-4),  # pulls: clamp; apart: table gate
    (0.0, 0.0, 0.0, 0.0, 0.0),
]


def _float(law, f, r, dp, dv, pa, k=1e5, c=300.0):
    return compensate(law, f, r, dp, dv, k, c, touching=pa > 0.0)


@pytest.mark.parametrize("name", list(LAWS))
def test_symbolic_form_evaluates_to_the_float_form(name):
    law = LAWS[name]
    f, r, dp, dv, pa = (Variable(n) for n in ("f", "r", "dp", "dv", "pa"))
    expr = compensate(law, f, r, dp, dv, 1e5, 300.0, touching=pa > 0.0)
    for sample in SAMPLES:
        env = dict(zip((f, r, dp, dv, pa), sample, strict=True))
        value = expr.Evaluate(env) if hasattr(expr, "Evaluate") else float(expr)
        assert value == pytest.approx(_float(law, *sample), rel=1e-15, abs=1e-12)


@pytest.mark.parametrize("name", list(LAWS))
def test_array_form_is_the_law_per_sample(name):
    """On arrays of samples (``select`` -> ``numpy.where``), elementwise."""
    law = LAWS[name]
    cols = [np.array(c) for c in zip(*SAMPLES, strict=True)]
    out = compensate(law, cols[0], cols[1], cols[2], cols[3], 1e5, 300.0, cols[4] > 0.0)
    np.testing.assert_array_equal(out, [_float(law, *s) for s in SAMPLES])


def test_autodiff_form_has_the_closed_form_slopes():
    law = LAWS["SDMDC gated"]
    f = AutoDiffXd(150.0, [1.0, 0.0])
    dp = AutoDiffXd(1e-3, [0.0, 1.0])
    out = compensate(law, f, 0.0, dp, 0.0, 1e5, None)
    assert out.value() == pytest.approx(150.0 + 1e5 * 1e-3)
    np.testing.assert_allclose(out.derivatives(), [1.0, 1e5])


def test_the_wrench_law_on_the_normal_is_the_one_axis_law():
    """The 6-DoF law with G = -K: a wrench and a pose error along the normal
    give the 1-D law's force in that component, and nothing else."""
    law = CompensationLaw(0.005, True, 2.0)
    k, c = 1e5, 250.0
    K = np.zeros((6, 6))
    C = np.zeros((6, 6))
    K[5, 2], C[5, 2] = -k, -c  # force z from the approach (compression positive)
    for f, r, dp, dv, _ in SAMPLES:
        w = np.array([0.0, 0.0, 0.0, 0.0, 0.0, f])
        rate = np.array([0.0, 0.0, 0.0, 0.0, 0.0, r])
        dq = np.array([0.0, 0.0, dp, 0.0, 0.0, 0.0])
        dqd = np.array([0.0, 0.0, dv, 0.0, 0.0, 0.0])
        out = compensate(law, w, rate, dq, dqd, -K, -C, gate_force=abs(f))
        one = compensate(law, f, r, dp, dv, k, c)
        assert out[5] == one
        assert not np.any(out[:5])


def test_the_compiled_compensator_is_the_python_one():
    """SymbolicVectorSystem (compiled) and LawSystem (Python callback) forms
    of one compensator give the same force on every sample."""
    params = CompensatorParams(
        "SDMDC", lead_time_s=0.005, stiffness_n_per_m=1e5, damping_n_s_per_m=300.0,
        force_deadband_n=2.0, clamp_nonnegative=True,
    )  # fmt: skip
    for f, _, dp, dv, pa in SAMPLES:
        values = []
        for compiled in (True, False):
            comp = Compensator(params, derivative_period_s=1e-3, compiled=compiled)
            ctx = comp.CreateDefaultContext()
            comp.GetInputPort("measured_force").FixValue(ctx, [f])
            comp.GetInputPort("measured_force_rate").FixValue(ctx, [0.0])
            comp.GetInputPort("table_motion").FixValue(ctx, [pa, 0.05, 0.0])
            comp.GetInputPort("commanded_state").FixValue(ctx, [pa + dp, 0.05 + dv])
            values.append(comp.GetOutputPort("compensated_force").Eval(ctx)[0])
        assert values[0] == pytest.approx(values[1], rel=1e-14, abs=1e-12)


def test_contact_never_pulls_on_any_type():
    k, c = 1e5, 2e3
    assert spring_contact_force(k, c, 1e-3, 0.0) == pytest.approx(100.0)
    assert spring_contact_force(k, c, 1e-3, -1.0) == 0.0  # the damper would pull
    assert spring_contact_force(k, c, -1e-3, 1.0) == 0.0  # apart
    p = np.array([1e-3, 1e-3, -1e-3])
    v = np.array([0.0, -1.0, 1.0])
    np.testing.assert_array_equal(spring_contact_force(k, c, p, v), [100.0, 0.0, 0.0])
    assert spring_contact_force(k, c, -1e-3, 0.0, bilateral=True) == pytest.approx(-100.0)


def test_select_and_both_on_each_type():
    assert select(True, 1, 2) == 1 and select(np.bool_(False), 1, 2) == 2
    assert both(True, np.bool_(True)) is True
    np.testing.assert_array_equal(select(np.array([True, False]), 1.0, 2.0), [1.0, 2.0])
    x = Variable("x")
    e = select(x > 0.0, x, 0.0 * x)
    assert e.Evaluate({x: -3.0}) == 0.0
    assert e.Evaluate({x: 3.0}) == 3.0


@pytest.mark.parametrize("zeta", [0.2, 0.8, 1.0, 2.0])
def test_held_tick_is_the_step_response(zeta):
    """From rest under a held unit command, one tick of the second-order
    response is the closed-form step response."""
    f, h = 25.0, 1e-3
    w = 2 * math.pi * f
    phi, gamma = second_order_tick(f, zeta, h)
    x = gamma * 1.0  # from rest
    t = h
    if zeta < 1.0:
        wd = w * math.sqrt(1 - zeta * zeta)
        e = math.exp(-zeta * w * t)
        pos = 1 - e * (math.cos(wd * t) + zeta * w / wd * math.sin(wd * t))
        vel = e * w * w / wd * math.sin(wd * t)
    elif zeta == 1.0:
        pos = 1 - math.exp(-w * t) * (1 + w * t)
        vel = w * w * t * math.exp(-w * t)
    else:
        r1, r2 = -w * (zeta - math.sqrt(zeta**2 - 1)), -w * (zeta + math.sqrt(zeta**2 - 1))
        pos = 1 + (r2 * math.exp(r1 * t) - r1 * math.exp(r2 * t)) / (r1 - r2)
        vel = r1 * r2 * (math.exp(r1 * t) - math.exp(r2 * t)) / (r1 - r2)
    assert x[0] == pytest.approx(pos, rel=1e-10)
    assert x[1] == pytest.approx(vel, rel=1e-10)
    # and it composes: two ticks are the tick of 2 h
    phi2, gamma2 = second_order_tick(f, zeta, 2 * h)
    np.testing.assert_allclose(phi @ phi, phi2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(phi @ gamma + gamma, gamma2, rtol=1e-12, atol=1e-15)


def _rule(**kw):
    args = dict(t_max_s=1.0, settle_s=0.05, check_interval_s=0.02, peak_force_n=100.0)
    return SeparationRule(**{**args, **kw})


def test_separation_after_the_settling_window():
    rule = _rule()
    ends = []
    for t_active in (False, True, True, False, False, False):
        ends.append(rule.check(10, 50.0, active=t_active))
    # checks at 0.02 ... 0.12; active at 0.04 and 0.06: quiet for 0.06 > 0.05 at t = 0.12
    assert ends == [False, False, False, False, False, True]
    assert rule.separated and rule.t == pytest.approx(0.12)
    rule.verdict()


def test_a_force_between_checks_moves_the_window():
    rule = _rule(settle_s=0.03)
    assert not rule.check(1, 0.0, active=True)  # t = 0.02
    assert not rule.check(1, 0.0, active=False, active_at_s=0.035)  # t = 0.04
    assert not rule.check(1, 0.0, active=False, active_at_s=0.035)  # t = 0.06: 0.025 quiet
    assert rule.check(1, 0.0, active=False, active_at_s=0.035)  # t = 0.08: 0.045 quiet


def test_divergence_budget_and_verdicts():
    with pytest.raises(DivergenceError, match="100 times the undamped peak force"):
        _rule().check(1, 1.0001e4, active=True)
    with pytest.raises(DivergenceError):
        _rule().check(1, 1.0, active=True, finite=False)
    with pytest.raises(DivergenceError):
        _rule().check(1, math.nan, active=True)
    with pytest.raises(SimulationError, match="too stiff to simulate"):
        _rule().check(10**9, 1.0, active=True)
    rule = _rule(t_max_s=0.04)
    assert not rule.check(1, 0.0, active=False)
    assert rule.check(1, 0.0, active=False)
    with pytest.raises(SimulationError, match="no contact within"):
        rule.verdict()
    rule = _rule(t_max_s=0.04)
    rule.check(1, 10.0, active=True, forces_n=(10.0, 0.5, 0.0))
    rule.check(1, 10.0, active=True, forces_n=(10.0, 0.5, 0.0))
    with pytest.raises(SimulationError, match=r"did not end .*\(spacecraft captured"):
        rule.verdict()
    # the contact pushes, every reading is in the dead band, nothing is fed back
    stuck = _rule(t_max_s=0.02, force_deadband_n=1.0)
    assert stuck.check(1, 0.0, active=True, forces_n=(10.0, 0.5, 0.0))
    with pytest.raises(SimulationError, match="never slows"):
        stuck.verdict()
    # the devices apart, the readings' noise above the dead band keeps the compensation on
    noisy = _rule(t_max_s=0.02, force_deadband_n=1.0)
    assert noisy.check(1, 3.0, active=True, forces_n=(0.0, 3.0, 3.0))
    with pytest.raises(SimulationError, match="devices are apart, but the readings"):
        noisy.verdict()


def test_the_end_tolerance_adds_no_chunk():
    rule = _rule(t_max_s=0.1, check_interval_s=0.02, end_tolerance_s=1e-9)
    checks = 0
    while not rule.check(1, 0.0, active=True):
        checks += 1
    assert checks == 4 and rule.t == pytest.approx(0.1)
