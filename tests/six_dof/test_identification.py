"""The 6-DoF ``sdmdc-online`` (issue 37): the contact's stiffness identified
online from the wrench, and the loop it compensates."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.compensators.identification import IdentifierParams, information_step
from hybridtable.six_dof.contact import DockingContact
from hybridtable.six_dof.identification import StiffnessIdentifier, make_online_sdmdc
from hybridtable.six_dof.params import DockingContactParams
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.conftest import docking_params


def test_information_step_is_the_batch_regularized_least_squares():
    """Without forgetting, the recursion ends where the batch solution is:
    ``theta = (Y0 + w sum phi phi')^-1 (Y0 theta0 + w sum phi t')`` (3
    parameters, 2 outputs)."""
    rng = np.random.default_rng(2)
    info = [0.5, 2.0, 0.1]
    theta0 = rng.normal(size=(3, 2))
    weight = 4.0
    Y = np.diag(info).tolist()
    y = (np.diag(info) @ theta0).tolist()
    Phi, T = rng.normal(size=(40, 3)), rng.normal(size=(40, 2))
    for phi, t in zip(Phi, T, strict=True):
        Y, y = information_step(Y, y, phi, t, 1.0, info, theta0.tolist(), weight)
    batch_Y = np.diag(info) + weight * Phi.T @ Phi
    batch_y = np.diag(info) @ theta0 + weight * Phi.T @ T
    np.testing.assert_allclose(np.array(Y), batch_Y, rtol=1e-12)
    np.testing.assert_allclose(
        np.linalg.solve(np.array(Y), np.array(y)), np.linalg.solve(batch_Y, batch_y), rtol=1e-10
    )


def identify(
    true: DockingContactParams, model_k: float, samples, forgetting_time_s: float = 0.1
) -> float:
    """The identifier's stiffness scale after ``samples`` of ``(q, qd)`` whose
    wrench is the ``true`` contact's (or ``(q, qd, true)``: that contact's),
    with a model of stiffness ``model_k``."""
    model = DockingContact(
        DockingContactParams(
            model_k,
            contact_dissipation_s_per_m=true.contact_dissipation_s_per_m,
            ring_radius_m=true.ring_radius_m,
            pad_radius_m=true.pad_radius_m,
        )
    )
    settings = IdentifierParams(
        model_k, force_noise_std_n=0.01, forgetting_time_s=forgetting_time_s
    )
    ident = StiffnessIdentifier(model, settings, 1e-3)
    context = ident.CreateDefaultContext()
    truths = {true: DockingContact(true)}
    state = context.get_discrete_state_vector()
    for q, qd, *other in samples:
        contact = other[0] if other else true
        if contact not in truths:
            truths[contact] = DockingContact(contact)
        truth = truths[contact]
        ident.GetInputPort("measured_wrench").FixValue(context, truth.wrench(q, qd))
        ident.GetInputPort("aligned_table_state").FixValue(context, np.concatenate([q, qd]))
        update = ident.EvalUniquePeriodicDiscreteUpdate(context)
        state.SetFromVector(update.get_vector().value())
    return float(ident.GetOutputPort("stiffness_scale").Eval(context)[0])


def poses(n: int = 30, seed: int = 4):
    """Pressed, tilted (up to 2 deg), offset poses, moving."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = np.concatenate(
            [rng.uniform(-0.02, 0.02, 2), [rng.uniform(0.001, 0.004)], rng.uniform(-0.03, 0.03, 3)]
        )
        yield q, rng.uniform(-0.05, 0.05, 6)


@pytest.mark.parametrize("believed", [0.5, 1.5])
def test_identifier_finds_the_stiffness_from_the_whole_wrench(believed):
    """The model's stiffness 50 % wrong, the true contact damped: the estimate
    over the model's is 1 / believed to 1e-4 after 30 samples."""
    true = DockingContactParams(8e4, contact_dissipation_s_per_m=0.3)
    assert identify(true, believed * 8e4, poses()) == pytest.approx(1.0 / believed, rel=1e-4)


def test_friction_outside_the_model_moves_the_estimate_little():
    """Sliding pads with mu = 0.3 (which the model leaves out): within 1 %."""
    true = DockingContactParams(8e4, friction_coefficient=0.3)
    assert identify(true, 1.2e5, poses()) == pytest.approx(8e4 / 1.2e5, rel=1e-2)


def test_memory_forgets_once_a_tick():
    """The contact stiffens from k1 to k2 at a fixed pose: n ticks later the
    estimate is the data's exponentially weighted mean, ``(k1 l^n (1 - l^N) +
    k2 (1 - l^n)) / (l^n (1 - l^N) + 1 - l^n)`` with ``l = exp(-h / tau)`` (the
    prior's weight is negligible here): forgetting once per tick, not once per
    wrench component."""
    k1, k2, N, n, tau = 6e4, 9e4, 50, 10, 0.01
    q, qd = np.array([0.0, 0.0, 0.002, 0.01, -0.01, 0.0]), np.zeros(6)
    first, second = DockingContactParams(k1), DockingContactParams(k2)
    samples = [(q, qd, first)] * N + [(q, qd, second)] * n
    lam = math.exp(-1e-3 / tau)
    old, new = lam**n * (1 - lam**N), 1 - lam**n
    expected = (k1 * old + k2 * new) / (old + new)
    assert identify(first, 1e5, samples, tau) * 1e5 == pytest.approx(expected, rel=1e-6)


def test_no_contact_keeps_the_prior():
    true = DockingContactParams(8e4)
    apart = [(np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0]), np.zeros(6))] * 5
    assert identify(true, 1.2e5, apart) == pytest.approx(1.0, rel=1e-15)  # the prior


def test_online_sdmdc_has_the_wrench_compensators_ports():
    params = docking_params(compensator="sdmdc-online")
    contact = DockingContact(params.believed_contact)
    diagram = make_online_sdmdc(params, contact.stiffness)
    for name in ("measured_wrench", "table_state", "commanded_state"):
        assert diagram.HasInputPort(name)
    assert diagram.HasOutputPort("compensated_wrench")
    assert diagram.HasOutputPort("stiffness_scale")


@pytest.mark.slow
@pytest.mark.parametrize("believed", [0.5, 1.5])
def test_online_sdmdc_keeps_the_energy_with_the_stiffness_wrong(believed):
    """Off axis (15 mm, 1.5 deg pitch, other inertia), a damped contact with
    friction, 5 ms delay, 25 Hz table: the compensator believing the stiffness
    50 % wrong. SDMDC then misses the ideal rig's energy ratio by more than
    0.03; sdmdc-online stays within 0.01 of it (the issue's figure)."""
    base = docking_params(
        0.015,
        1.5,
        inertia=(1500.0, 1900.0, 2300.0),
        friction=0.2,
        dissipation=0.2,
        sensor_delay_s=0.005,
        table_response_hz=25.0,
        table_damping_ratio=0.8,
    )
    ideal = simulate6(base.with_(sensor_delay_s=0.0, table_response_hz=math.inf)).metrics
    wrong = base.contact.contact_stiffness_n_per_m * believed
    fixed = simulate6(base.with_(compensator="SDMDC", compensator_stiffness_n_per_m=wrong))
    online = simulate6(base.with_(compensator="sdmdc-online", compensator_stiffness_n_per_m=wrong))
    assert abs(fixed.metrics.energy_ratio - ideal.energy_ratio) > 0.03
    assert online.metrics.energy_ratio == pytest.approx(ideal.energy_ratio, abs=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [11, 12, 13])
def test_online_sdmdc_lands_where_the_true_stiffness_does(seed):
    """Drawn rigs (offset up to 30 mm, pitch up to 3 deg, inertia, delay 2-10
    ms, table 15-50 Hz, damping, friction) and a belief between half and twice
    the contact's: sdmdc-online's energy ratio is SDMDC's with the true
    stiffness to 1e-3, and the identified stiffness the contact's to 1e-3."""
    rng = np.random.default_rng(seed)
    inertia = tuple(sorted(rng.uniform(1400.0, 2000.0, 3)))
    base = docking_params(
        rng.uniform(0.0, 0.03),
        rng.uniform(0.0, 3.0),
        inertia=inertia,
        friction=float(rng.choice([0.0, 0.3])),
        dissipation=float(rng.choice([0.0, 0.2, 0.5])),
        sensor_delay_s=float(rng.choice([0.002, 0.005, 0.01])),
        table_response_hz=float(rng.choice([15.0, 25.0, 50.0])),
        table_damping_ratio=0.8,
    )
    k = base.contact.contact_stiffness_n_per_m
    belief = float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    true = simulate6(base.with_(compensator="SDMDC")).metrics.energy_ratio
    run = simulate6(
        base.with_(compensator="sdmdc-online", compensator_stiffness_n_per_m=belief * k)
    )
    assert run.metrics.energy_ratio == pytest.approx(true, abs=1e-3)
    assert run.extra["identified_stiffness_n_per_m"] == pytest.approx(k, rel=1e-3)
