"""Compensator plug-ins: registry, sdmdc-online, polynomial, smith, the
passivity guard and the measurement noise; step and ramp responses against
closed forms, tick by tick as a rig computer runs them, and loop-level facts."""

import math

import numpy as np
import pytest

from hybridtable import Compensator, HybridLoopParams, ParameterError
from hybridtable.compensators.online import AdaptiveSDMDC, make_online_sdmdc
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.compensators.passivity import PassivityGuard, PassivityParams, passivity_guarded
from hybridtable.compensators.polynomial import (
    PolynomialExtrapolator,
    PolynomialParams,
    extrapolation_weights,
    make_polynomial,
)
from hybridtable.compensators.registry import (
    compensator_factory,
    compensator_names,
    make_compensator,
    register_compensator,
)
from hybridtable.compensators.smith import SmithParams, SmithPredictor, make_smith
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import run_loop, simulate
from hybridtable.studies.paper import table1_params
from hybridtable.systems.noise import (
    MeasurementNoise,
    MeasurementNoiseParams,
    noise_sample,
    with_measurement_noise,
)

PLUGINS = ("sdmdc-online", "polynomial", "smith", "smith-online")


def _ticks(system, inputs, output="compensated_force"):
    """Run a discrete system as the rig computer does: at tick k fix the
    inputs, read the output (state of the earlier ticks), then update.

    ``inputs``: port name -> array (n_ticks, size). Returns (n_ticks, size).
    """
    ctx = system.CreateDefaultContext()
    n = len(next(iter(inputs.values())))
    out = []
    for k in range(n):
        for name, values in inputs.items():
            system.GetInputPort(name).FixValue(ctx, np.atleast_1d(values[k]))
        out.append(np.array(system.GetOutputPort(output).Eval(ctx)))
        ctx.SetDiscreteState(system.EvalUniquePeriodicDiscreteUpdate(ctx))
    return np.array(out)


def _inputs(n, f=0.0, p_act=0.0, v_act=0.0, p_des=0.0, v_des=0.0):
    def col(x):
        return np.broadcast_to(np.asarray(x, dtype=float), (n,))

    return {
        "measured_force": col(f)[:, None],
        "measured_force_rate": np.zeros((n, 1)),
        "table_motion": np.stack([col(p_act), col(v_act), np.zeros(n)], axis=1),
        "commanded_state": np.stack([col(p_des), col(v_des)], axis=1),
    }


# -- registry ---------------------------------------------------------------


def test_registry_holds_the_paper_compensators_then_the_plugins():
    names = compensator_names()
    assert names[:4] == COMPENSATORS
    assert set(PLUGINS) <= set(names)
    for name in PLUGINS:
        assert HybridLoopParams(1.0, 1.0, compensator=name).compensator == name
    with pytest.raises(ParameterError, match="smith"):  # the message lists the choices
        HybridLoopParams(1.0, 1.0, compensator="nonesuch")
    with pytest.raises(ValueError, match="already registered"):
        register_compensator("smith", make_smith)
    with pytest.raises(ValueError, match="already registered"):
        register_compensator("SDMDC", make_smith, replace=True)


def test_a_registered_factory_builds_the_loop_compensator():
    from hybridtable.compensators import registry

    calls = []

    def factory(params, period):
        calls.append(period)
        return Compensator(params.with_(compensator="SDC").compensator_params(), period)

    register_compensator("test-sdc", factory)
    try:
        p = table1_params("test-sdc")
        cor = simulate(p).metrics.cor
        assert calls and calls[0] == build_hybrid_loop(p, log=False).computer_period_s
        assert cor == simulate(table1_params("SDC")).metrics.cor
    finally:
        del registry._REGISTRY["test-sdc"]


@pytest.mark.parametrize("name", ["none", "SDMDC"])
def test_paper_compensators_unchanged_by_the_registry(name):
    p = table1_params(name)
    h = build_hybrid_loop(p, log=False).computer_period_s
    direct = Compensator(p.compensator_params(), derivative_period_s=h)
    assert simulate(p).metrics.cor == run_loop(build_hybrid_loop(p, compensator=direct)).metrics.cor


# -- sdmdc-online -------------------------------------------------------------


def test_adaptive_sdmdc_step_and_ramp_closed_forms():
    from hybridtable import CompensatorParams

    h, lead, k, c = 1e-3, 4e-3, 2e4, 150.0
    comp = AdaptiveSDMDC(CompensatorParams("SDMDC", lead_time_s=lead), h)
    n = 12
    # Force step of 50 N at tick 3 with a response error (1 mm, 0.02 m/s).
    f = np.where(np.arange(n) >= 3, 50.0, 0.0)
    u = _inputs(n, f=f, p_act=1e-3, v_act=0.08, p_des=2e-3, v_des=0.1)
    u["contact_parameters"] = np.tile([k, c], (n, 1))
    y = _ticks(comp, u)[:, 0]
    mdc = k * 1e-3 + c * 0.02
    assert np.all(y[:3] == 0.0)  # gated: no measured force
    assert y[3] == pytest.approx(50.0 + lead * 50.0 / h + mdc)
    assert y[4:] == pytest.approx(50.0 + mdc)
    # Ramp 1e4 N/s: f + lead * rate.
    f = 1e4 * h * np.arange(1, n + 1)
    u = _inputs(n, f=f)
    u["contact_parameters"] = np.tile([k, c], (n, 1))
    y = _ticks(comp, u)[:, 0]
    assert y[1:] == pytest.approx(f[1:] + lead * 1e4)


def test_sdmdc_online_identifies_then_compensates_with_the_true_stiffness():
    # Sampled loop at 1 kHz, 3 ms sensor delay: f_mea[k] = K p_act[k - 3].
    k_true, h, n = 1e5, 1e-3, 40
    params = table1_params(
        "sdmdc-online", sample_rate_hz=1e3, compensator_stiffness_n_per_m=0.5 * k_true
    ).with_(sensor_delay_s=3e-3)
    comp = make_online_sdmdc(params, h)
    t = h * np.arange(n)
    p_act = 0.1 * t - 1e-3  # contact from tick 10
    p_des = p_act + 1.6e-3  # the table lags the command
    f = np.maximum(k_true * np.concatenate([np.full(3, -1.0), p_act[:-3]]), 0.0)
    y = _ticks(comp, _inputs(n, f=f, p_act=p_act, v_act=0.1, p_des=p_des, v_des=0.1))[:, 0]
    rate = np.concatenate([[0.0], np.diff(f)]) / h
    expected = f + 3e-3 * rate + k_true * 1.6e-3
    first = np.argmax(f > 0)
    assert first == 14
    # The first contact tick uses the prior, then the identified stiffness.
    assert y[first] == pytest.approx(f[first] + 3e-3 * rate[first] + 0.5 * k_true * 1.6e-3)
    assert y[first + 2 :] == pytest.approx(expected[first + 2 :], rel=1e-6)


# -- polynomial ---------------------------------------------------------------


def test_extrapolation_weights_are_exact_for_polynomials_up_to_the_order():
    rng = np.random.default_rng(0)
    for order in (1, 2, 3):
        for horizon in (0.3, 1.0, 2.5):
            w = extrapolation_weights(order, horizon)
            assert w.sum() == pytest.approx(1.0)
            coef = rng.standard_normal(order + 1)
            samples = np.polyval(coef, -np.arange(order + 1.0))
            assert w @ samples == pytest.approx(np.polyval(coef, horizon))
    # Order 1, one-tick spacing, horizon T: the paper's SDC backward difference.
    assert extrapolation_weights(1, 5.0) == pytest.approx([6.0, -5.0])


def test_polynomial_step_response_is_the_partial_sums_of_the_weights():
    h = 1e-3
    p = PolynomialParams(horizon_s=6e-3, order=2, spacing_s=3e-3)
    comp = PolynomialExtrapolator(p, h)
    w = p.weights(h)  # spacing 3 ticks, horizon 2 spacings
    assert w == pytest.approx(extrapolation_weights(2, 2.0))
    n = 10
    y = _ticks(comp, _inputs(n, f=np.where(np.arange(n) >= 2, 10.0, 0.0)))[:, 0]
    expected = [0, 0, w[0], w[0], w[0], w[0] + w[1], w[0] + w[1], w[0] + w[1], 1.0, 1.0]
    assert y == pytest.approx(10.0 * np.array(expected))


def test_polynomial_ramp_and_parabola_are_extrapolated_exactly():
    h, horizon = 1e-3, 7e-3
    n = 30
    t = h * np.arange(n)
    for order, f in ((1, 1e3 * t + 5.0), (2, 1e3 * t + 4e5 * t**2 + 5.0)):
        p = PolynomialParams(horizon_s=horizon, order=order, spacing_s=2e-3)
        y = _ticks(PolynomialExtrapolator(p, h), _inputs(n, f=f))[:, 0]
        start = order * 2  # the history is full from here on
        tt = t[start:] + horizon
        exact = 1e3 * tt + 5.0 if order == 1 else 1e3 * tt + 4e5 * tt**2 + 5.0
        assert y[start:] == pytest.approx(exact, rel=1e-9)


def test_polynomial_gating_and_clamp():
    h = 1e-3
    p = PolynomialParams(horizon_s=2e-3, order=1, spacing_s=1e-3, force_deadband_n=5.0)
    y = _ticks(PolynomialExtrapolator(p, h), _inputs(4, f=[5.0, 20.0, 10.0, 6.0]))[:, 0]
    # 5 N is in the deadband; then 3 f[k] - 2 f[k-1].
    assert y == pytest.approx([0.0, 50.0, -10.0, -2.0])
    pc = PolynomialParams(2e-3, 1, 1e-3, force_deadband_n=5.0, clamp_nonnegative=True)
    y = _ticks(PolynomialExtrapolator(pc, h), _inputs(4, f=[5.0, 20.0, 10.0, 6.0]))[:, 0]
    assert y == pytest.approx([0.0, 50.0, 0.0, 0.0])
    with pytest.raises(ParameterError, match="order"):
        PolynomialParams(1e-3, order=0)


def test_polynomial_factory_horizon_is_the_loop_delay():
    params = table1_params("polynomial")
    comp = make_polynomial(params, 1e-4)
    assert comp.params.horizon_s == pytest.approx(params.effective_delay_s)
    assert comp.params.order == 2
    assert make_polynomial(params.with_(lead_time_s=2e-3), 1e-4).params.horizon_s == 2e-3


# -- smith --------------------------------------------------------------------


def _smith_inputs(n, p_des, p_act, f):
    return _inputs(n, f=f, p_act=p_act, v_act=0.0, p_des=p_des, v_des=0.0)


def test_smith_step_predicts_the_force_before_it_is_measured():
    k = 2e4
    comp = SmithPredictor(SmithParams(k))
    ctx = comp.CreateDefaultContext()
    for name, value in (
        ("measured_force", [0.0]),
        ("measured_force_rate", [0.0]),
        ("table_motion", [0.0, 0.0, 0.0]),
        ("commanded_state", [1e-3, 0.0]),  # command steps into contact
        ("delayed_table_motion", [0.0, 0.0, 0.0]),
    ):
        comp.GetInputPort(name).FixValue(ctx, value)
    assert comp.GetOutputPort("compensated_force").Eval(ctx)[0] == pytest.approx(k * 1e-3)


@pytest.mark.parametrize("k_model_ratio", [1.0, 0.5])
def test_smith_ramp_closed_form_in_the_sampled_loop(k_model_ratio):
    # 1 kHz, 3 ms delay: f_mea[k] = K p_act[k - 3]; model stiffness K_m.
    k_true, h, n = 1e5, 1e-3, 30
    params = table1_params(
        "smith", sample_rate_hz=1e3, compensator_stiffness_n_per_m=k_model_ratio * k_true
    ).with_(sensor_delay_s=3e-3)
    comp = make_smith(params, h)
    t = h * np.arange(n)
    p_act = 0.1 * t - 1e-3
    p_des = p_act + 1.6e-3
    p_old = np.concatenate([np.full(3, -1.0), p_act[:-3]])
    f = np.maximum(k_true * p_old, 0.0)
    y = _ticks(comp, _smith_inputs(n, p_des, p_act, f))[:, 0]
    k_m = k_model_ratio * k_true
    expected = np.maximum(k_m * p_des, 0) + f - np.maximum(k_m * p_old, 0)
    assert y == pytest.approx(expected, rel=1e-12, abs=1e-9)
    if k_model_ratio == 1.0:  # exact model: the ideal force k p_des
        assert y == pytest.approx(np.maximum(k_true * p_des, 0.0), abs=1e-9)


def test_smith_deadband_applies_to_measured_and_predicted_force():
    comp = SmithPredictor(SmithParams(1e4, force_deadband_n=5.0))
    ctx = comp.CreateDefaultContext()
    comp.GetInputPort("measured_force").FixValue(ctx, [4.0])
    comp.GetInputPort("measured_force_rate").FixValue(ctx, [0.0])
    comp.GetInputPort("table_motion").FixValue(ctx, [0.0, 0.0, 0.0])
    comp.GetInputPort("commanded_state").FixValue(ctx, [2e-3, 0.0])
    comp.GetInputPort("delayed_table_motion").FixValue(ctx, [4e-4, 0.0, 0.0])  # predicts 4 N
    assert comp.GetOutputPort("compensated_force").Eval(ctx)[0] == pytest.approx(20.0)


# -- passivity guard ------------------------------------------------------------


def _guard_run(f0, v0, mass=10.0, h=1e-3, tol=0.0):
    """A sampled guard driving a semi-implicit Euler mass, as the loop does;
    returns forces applied, velocities and the guard's observed energy."""
    guard = PassivityGuard(PassivityParams(h, mass, sampled=True, energy_tolerance=tol))
    ctx = guard.CreateDefaultContext()
    v, x = v0, 0.0
    forces, vs, energies = [], [], []
    for f in f0:
        guard.GetInputPort("force").FixValue(ctx, [f])
        guard.GetInputPort("commanded_state").FixValue(ctx, [x, v])
        out = guard.GetOutputPort("compensated_force").Eval(ctx)[0]
        energies.append(guard.GetOutputPort("observed_energy").Eval(ctx)[0])
        ctx.SetDiscreteState(guard.EvalUniquePeriodicDiscreteUpdate(ctx))
        forces.append(out)
        v -= out / mass * h
        x += v * h
        vs.append(v)
    return np.array(forces), np.array(vs), np.array(energies)


def test_passivity_observer_is_the_energy_the_mass_lost():
    # A passive (spring-like) force history passes unchanged and the observed
    # energy equals the kinetic energy the model lost, exactly.
    n, mass, v0 = 200, 1e3, 0.1
    f0 = 50.0 * np.sin(np.linspace(0, np.pi, n))  # pushes back, the mass still approaching
    forces, vs, energy = _guard_run(f0, v0, mass)
    assert forces == pytest.approx(f0, abs=0.0)
    ke = 0.5 * mass * np.concatenate([[v0], vs[:-1]]) ** 2
    assert energy == pytest.approx(0.5 * mass * v0**2 - ke, rel=1e-9, abs=1e-15)


def test_passivity_controller_cuts_an_energy_generator():
    # The compensator pulls the approaching model (f < 0, v > 0): pure energy
    # generation. Strict guard: the model never gains kinetic energy.
    n, mass, v0 = 100, 10.0, 0.1
    forces, vs, energy = _guard_run(np.full(n, -30.0), v0, mass)
    assert np.all(0.5 * mass * vs**2 <= 0.5 * mass * v0**2 * (1 + 1e-12))
    assert np.all(np.abs(forces) < 1e-6)
    assert np.all(energy >= 0.0)


def test_passivity_credit_then_cut():
    # 0.4 J absorbed by a 40 N push at 0.1 m/s for 100 ticks, then a 20 N
    # pull: allowed until the credit is spent (about 0.4 / (20 * 0.1 * 1e-3) =
    # 200 ticks), then cut.
    mass, v0 = 1e3, 0.1
    f0 = np.concatenate([np.full(100, 40.0), np.full(400, -20.0)])
    forces, vs, energy = _guard_run(f0, v0, mass)
    passed = np.flatnonzero(np.isclose(forces[100:], -20.0))
    assert passed.size == pytest.approx(200, abs=2)
    assert np.all(energy >= -1e-12)
    assert 0.5 * mass * vs[-1] ** 2 <= 0.5 * mass * v0**2


def test_passivity_tolerance_bounds_the_energy_created():
    mass, v0, tol = 1e3, 0.1, 0.01
    f0 = np.concatenate([np.full(100, 40.0), np.full(600, -20.0)])
    _, vs, energy = _guard_run(f0, v0, mass, tol=tol)
    peak = energy.max()
    assert energy.min() >= -tol * peak - 1e-12
    assert energy.min() < -0.9 * tol * peak  # the tolerance is used


# -- measurement noise ----------------------------------------------------------


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
    y = _ticks(system, _inputs(n, f=100.0))[:, 0]
    assert y == pytest.approx(100.0 + 2.0 * np.array([noise_sample(3, 0, k) for k in range(n)]))
    ctx = noise.CreateDefaultContext()
    noise.GetInputPort("measured_force").FixValue(ctx, [0.0])
    noise.GetInputPort("table_motion").FixValue(ctx, [1e-3, 0.1, 2.0])
    motion = noise.GetOutputPort("table_motion").Eval(ctx)
    assert motion == pytest.approx([1e-3 + 1e-6 * noise_sample(3, 1, 0), 0.1, 2.0])


# -- in the loop ----------------------------------------------------------------


def test_sdmdc_online_within_001_of_cor_1_where_fixed_k_sdmdc_is_not():
    for ratio in (0.5, 2.0):
        kw = dict(compensator_stiffness_n_per_m=ratio * 1e5)
        fixed = simulate(table1_params("SDMDC", **kw)).metrics.cor
        online = simulate(table1_params("sdmdc-online", **kw)).metrics.cor
        assert abs(fixed - 1.0) > 0.04  # the mismatch matters ...
        assert abs(online - 1.0) < 0.01  # ... and the identification removes it


@pytest.mark.parametrize("sampled", [False, True])
def test_smith_with_the_true_model_restores_cor_1(sampled):
    kw = {"sample_rate_hz": 1e3} if sampled else {}
    assert simulate(table1_params("smith", **kw)).metrics.cor == pytest.approx(1.0, abs=1e-3)


def test_polynomial_needs_no_stiffness():
    a = simulate(table1_params("polynomial")).metrics.cor
    b = simulate(table1_params("polynomial", compensator_stiffness_n_per_m=3e4)).metrics.cor
    assert a == b and abs(a - 1.0) < 0.01


@pytest.mark.parametrize("name", COMPENSATORS + PLUGINS)
def test_passivity_guard_keeps_every_compensator_at_or_below_cor_1005(name):
    # Prior stiffness 50 % low (the MDC-based compensators then create energy).
    p = table1_params(name, compensator_stiffness_n_per_m=5e4, passivity=True)
    unguarded = simulate(p.with_(passivity=False)).metrics.cor
    cor = simulate(p).metrics.cor
    assert cor <= 1.005
    assert cor <= 1.0 + 1e-6  # the strict guard (no energy tolerance)
    if unguarded > 1.01:
        assert cor >= 0.99  # it dissipates the excess, not much more


@pytest.mark.parametrize("name", ["none", "SDMDC"])
def test_passivity_guard_in_the_sampled_loop(name):
    p = table1_params(name, sample_rate_hz=1e3, clamp_nonnegative=True, passivity=True)
    assert simulate(p.with_(passivity=False)).metrics.cor > 1.004
    assert simulate(p).metrics.cor <= 1.0 + 1e-9


def test_passivity_wraps_an_explicit_compensator_and_keeps_the_ports():
    p = table1_params("none", passivity=True)
    loop = build_hybrid_loop(p, compensator=Compensator(p.compensator_params(), 1e-4))
    names = {loop.compensator.get_input_port(i).get_name() for i in range(4)}
    assert names == {"measured_force", "measured_force_rate", "table_motion", "commanded_state"}
    assert loop.compensator.HasOutputPort("observed_energy")
    guarded = passivity_guarded(compensator_factory("smith")(p, 1e-4), p)
    assert guarded.HasOutputPort("compensated_force")


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


def test_plugins_convert_to_autodiff():
    p = table1_params("sdmdc-online", sample_rate_hz=1e3)
    for name in PLUGINS:
        assert make_compensator(p.with_(compensator=name), 1e-3).ToAutoDiffXd() is not None
    assert make_compensator(p.with_(passivity=True), 1e-3).ToAutoDiffXd() is not None


# -- command line ------------------------------------------------------------------


def test_simulate_command_takes_a_plugin_the_prior_stiffness_and_passivity(tmp_path, capsys):
    import json

    from hybridtable.cli import main

    out = tmp_path / "run.json"
    argv = ["simulate", "--compensator", "smith", "--compensator-stiffness-n-per-m", "5e4"]
    assert main([*argv, "--json", str(out)]) == 0
    assert json.loads(out.read_text())["cor"] > 1.05  # the model stiffness is half the true one
    assert main([*argv, "--passivity", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["cor"] <= 1.0 + 1e-6
    assert main(["simulate", "--compensator", "nonesuch"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sdmdc-online" in err[0]


def test_compensators_command_quick(tmp_path, capsys):
    import json

    from hybridtable.cli import main

    out, report = tmp_path / "sweep.json", tmp_path / "report"
    argv = [
        "compensators",
        "--quick",
        "--compensators",
        "SDMDC,sdmdc-online",
        "--scenarios",
        "mismatch",
        "--prior-ratios",
        "0.5,1",
        "--jobs",
        "1",
        "--no-progress",
        "--report",
        str(report),
    ]
    assert main([*argv, "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert len(data["runs"]) == 8 and all(r["error"] is None for r in data["runs"])
    acc = data["acceptance"]
    assert acc["sdmdc_online"]["passed"] and acc["passivity"]["passed"]
    assert acc["fixed_k_sdmdc_at_half_k"][0]["cor_error"] > 0.04
    assert (report / "report.md").is_file()
    assert (report / "cor_error_vs_prior_stiffness.png").is_file()
    assert "sdmdc-online" in capsys.readouterr().out
    # Never overwrite a report; bad options are one-line errors with exit 2.
    assert main([*argv, "--json", str(out)]) == 2
    assert main(["compensators", "--compensators", "nonesuch", "--no-progress"]) == 2
    assert main(["compensators", "--scenarios", "nonesuch", "--no-progress"]) == 2
