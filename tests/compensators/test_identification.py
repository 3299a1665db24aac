"""Online contact identification: convergence on a known spring-damper (with
and without noise), contact onset and separation, forgetting, the Drake
system in the loop."""

import math

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput

from hybridtable import ParameterError
from hybridtable.compensators.identification import (
    ContactIdentifier,
    ContactIdentifierLeaf,
    IdentifierParams,
    RecursiveContactIdentifier,
    forgetting_factor,
    rls_step,
)
from hybridtable.loop.builder import add_hybrid_loop
from hybridtable.studies.paper import table1_params

K, C, M, V0, H = 2e4, 300.0, 50.0, 0.1, 1e-3
W = math.sqrt(K / M)
F0 = V0 * math.sqrt(K * M)  # undamped peak force, 100 N


def _half_sine(c=C):
    """Deflection, rate and force of one contact of the known spring-damper
    (sampled at H: 158 samples, force clamped at zero at the end)."""
    t = np.arange(0.0, math.pi / W, H)
    x = V0 / W * np.sin(W * t)
    xd = V0 * np.cos(W * t)
    return x, xd, np.maximum(K * x + c * xd, 0.0)


def _identifier(noise_n=1e-3, threshold_n=0.0, **kw):
    fields = dict(
        prior_stiffness_n_per_m=0.5 * K,
        damping_std_n_s_per_m=math.sqrt(K * M),
        force_noise_std_n=noise_n,
        force_threshold_n=threshold_n,
        forgetting_time_s=math.inf,
    )
    fields.update(kw)
    return RecursiveContactIdentifier(IdentifierParams(**fields), H)


def test_converges_on_a_known_spring_damper_in_two_contact_samples():
    x, xd, f = _half_sine()
    ident = _identifier()
    est = ident.run(f, x, xd)
    # Sample 0 has zero deflection (not used): samples 1 and 2 determine k, c.
    assert est[0, 0] == 0.5 * K and est[0, 1] == 0.0
    assert est[2, 0] == pytest.approx(K, rel=1e-5)
    assert est[2, 1] == pytest.approx(C, rel=1e-5)
    assert est[-1] == pytest.approx([K, C], rel=1e-9)


def test_converges_with_one_percent_force_noise_within_50_samples():
    x, xd, f = _half_sine()
    sigma = 0.01 * F0
    f_noisy = f + sigma * np.random.default_rng(1).standard_normal(f.size)
    ident = _identifier(noise_n=sigma, threshold_n=5 * sigma)
    est = ident.run(f_noisy, x, xd)
    assert abs(est[50, 0] / K - 1) < 0.02
    assert abs(est[50, 1] / C - 1) < 0.02
    assert abs(est[-1, 0] / K - 1) < 0.01
    assert abs(est[-1, 1] / C - 1) < 0.01


def test_stiffness_only_keeps_the_prior_damping():
    x, xd, f = _half_sine(c=0.0)
    ident = _identifier(prior_damping_n_s_per_m=0.0, damping_std_n_s_per_m=0.0)
    est = ident.run(f, x, xd)
    assert np.all(est[:, 1] == 0.0)
    assert est[1, 0] == pytest.approx(K, rel=1e-6)  # one unknown: one sample


def test_no_update_outside_contact():
    p = IdentifierParams(1e4, 10.0, damping_std_n_s_per_m=100.0, force_threshold_n=2.0)
    state = list(p.initial_state())
    lam = forgetting_factor(p.forgetting_time_s, H)
    # Before onset / after separation: force at or below the threshold, or
    # the devices apart (noise reading a force while the deflection is < 0).
    for f, x, xd in [(0.0, 1e-3, 0.1), (2.0, 1e-3, 0.1), (50.0, -1e-4, 0.1), (50.0, 0.0, -0.1)]:
        assert rls_step(state, f, x, xd, lam, p) == state


def test_estimate_frozen_after_separation_and_prior_before_onset():
    x, xd, f = _half_sine()
    pad = np.zeros(40)
    noise = 0.5 * np.random.default_rng(3).standard_normal(f.size + 80)
    f_all = np.concatenate([pad, f, pad]) + noise  # noise below the 2 N threshold apart
    x_all = np.concatenate([pad - 1e-3, x, pad - 1e-3])
    xd_all = np.concatenate([pad + V0, xd, pad - V0])
    ident = _identifier(noise_n=0.5, threshold_n=2.0)
    est = ident.run(f_all, x_all, xd_all)
    assert np.all(est[:40] == [0.5 * K, 0.0])
    assert np.all(est[-40:] == est[-41])
    assert est[-1] == pytest.approx([K, C], rel=0.01)


def test_forgetting_tracks_a_stiffness_change():
    # Two contacts, the second with a stiffer spring: with a 20 ms memory the
    # estimate follows; with none it stays between the two.
    x, xd, f1 = _half_sine()
    f2 = np.maximum(2 * K * x + C * xd, 0.0)
    f, xs, xds = np.concatenate([f1, f2]), np.concatenate([x, x]), np.concatenate([xd, xd])
    tracking = _identifier(forgetting_time_s=0.02).run(f, xs, xds)
    frozen = _identifier().run(f, xs, xds)
    assert tracking[-1, 0] == pytest.approx(2 * K, rel=1e-3)
    assert frozen[-1, 0] < 1.9 * K


def test_covariance_never_exceeds_the_prior_and_stays_positive_definite():
    x, xd, f = _half_sine()
    p = IdentifierParams(0.5 * K, damping_std_n_s_per_m=50.0, forgetting_time_s=0.005)
    ident = RecursiveContactIdentifier(p, H)
    prior = np.diag([p.stiffness_std_n_per_m**2, 50.0**2])
    for i in range(f.size):
        ident.update(f[i], x[i], xd[i])
        cov = ident.covariance
        assert np.all(np.linalg.eigvalsh(cov) > 0.0)
        assert np.all(np.linalg.eigvalsh(prior - cov) >= -1e-9 * prior.max())


def test_ill_conditioned_data_are_solved_to_full_precision():
    # Constant rate: k delta and c delta_dot separate only through the small
    # change of delta; two exact samples determine both (information form).
    p = IdentifierParams(0.5 * K, damping_std_n_s_per_m=math.sqrt(K * M))
    ident = RecursiveContactIdentifier(p, H)
    for x in (1e-4, 2e-4, 3e-4):
        ident.update(K * x + C * 0.1, x, 0.1)
    assert ident.stiffness_n_per_m == pytest.approx(K, rel=1e-6)
    assert ident.damping_n_s_per_m == pytest.approx(C, rel=1e-6)


def test_parameters_are_validated():
    with pytest.raises(ParameterError, match="prior_stiffness_n_per_m"):
        IdentifierParams(0.0)
    with pytest.raises(ParameterError, match="force_noise_std_n"):
        IdentifierParams(1e4, force_noise_std_n=0.0)
    with pytest.raises(ParameterError, match="forgetting_time_s"):
        IdentifierParams(1e4, forgetting_time_s=-1.0)
    assert IdentifierParams(1e4).stiffness_std_n_per_m == 1e4


def test_drake_leaf_matches_the_array_identifier_and_converts_to_autodiff():
    x, xd, f = _half_sine()
    p = IdentifierParams(0.5 * K, damping_std_n_s_per_m=math.sqrt(K * M), forgetting_time_s=0.05)
    leaf = ContactIdentifierLeaf(p, H)
    ctx = leaf.CreateDefaultContext()
    ref = RecursiveContactIdentifier(p, H)
    for i in range(30):
        leaf.GetInputPort("measured_force").FixValue(ctx, [f[i]])
        leaf.GetInputPort("aligned_motion").FixValue(ctx, [x[i], xd[i], 0.0])
        ctx.SetDiscreteState(leaf.EvalUniquePeriodicDiscreteUpdate(ctx))
        ref.update(f[i], x[i], xd[i])
    out = leaf.GetOutputPort("contact_parameters").Eval(ctx)
    assert out == pytest.approx([ref.stiffness_n_per_m, ref.damping_n_s_per_m], rel=1e-12)
    assert leaf.ToAutoDiffXd() is not None
    assert ContactIdentifier(p, H).ToAutoDiffXd() is not None


@pytest.mark.parametrize("sampled", [False, True])
def test_in_the_loop_the_estimate_starts_at_the_prior_and_finds_the_true_contact(sampled):
    from pydrake.systems.analysis import Simulator

    kw = {"sample_rate_hz": 1000.0} if sampled else {}
    params = table1_params("sdmdc-online", compensator_stiffness_n_per_m=5e4, **kw)
    builder = DiagramBuilder()
    loop = add_hybrid_loop(builder, params)
    sink = LogVectorOutput(loop.compensator.GetOutputPort("contact_parameters"), builder)
    loop.diagram = builder.Build()
    simulator = Simulator(loop.diagram)
    ctx = simulator.get_mutable_context()
    loop.set_initial_conditions(ctx)
    simulator.get_mutable_integrator().set_maximum_step_size(loop.computer_period_s)
    simulator.AdvanceTo(0.6)  # the contact lasts from 0.02 s to about 0.53 s
    log = sink.FindLog(ctx)
    t, (k_hat, c_hat) = log.sample_times(), log.data()
    # The prior until the measured force arrives (contact at 0.02 s plus the
    # table lag and the 5 ms sensor delay), then the true k = 1e5 N/m, c = 0.
    assert np.all(k_hat[t < 0.025] == 5e4)
    assert k_hat[-1] == pytest.approx(1e5, rel=1e-4)
    assert abs(c_hat[-1]) < 1.0  # N s/m, against a critical damping of 3.2e4
    later = t > 0.1
    assert np.all(np.abs(k_hat[later] / 1e5 - 1) < 1e-3)
