"""Candidate effects: their Drake systems (closed forms, nominal limits, AutoDiff),
the library and registry, and each effect against an independent simulation of
a rig that has it (tests/_effectsim.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _effectsim import HIDDEN, simulate_hidden
from _rigsim import NOMINAL, write_run
from pydrake.autodiffutils import AutoDiffXd, InitializeAutoDiff
from pydrake.systems.primitives import MatrixGain

from hybridtable.diagnosis.effects import Effect, EffectParameter, ModelSpec, RigScale, Signature
from hybridtable.diagnosis.registry import (
    EFFECTS,
    build_spec,
    effect_names,
    get_effect,
    parse_effect_spec,
    register_effect,
    unregister_effect,
)
from hybridtable.errors import ParameterError
from hybridtable.measurement.replay import replay
from hybridtable.measurement.rig import RigPhysics
from hybridtable.measurement.run_format import read_run
from hybridtable.systems.blocks import chain_output
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.contact_law import ContactLaw, ContactLawParams, contact_law_force
from hybridtable.systems.measurement_chain import MeasurementChainParams, first_order_hold_filter
from hybridtable.systems.resonant_table import StructuralModeParams, resonant_table_matrices
from hybridtable.systems.table import TableParams

K = 60000.0


def _eval(system, motion):
    ctx = system.CreateDefaultContext()
    system.GetInputPort("motion").FixValue(ctx, np.asarray(motion, dtype=float))
    return system.GetOutputPort("force").Eval(ctx)[0], system.GetOutputPort("force_rate").Eval(ctx)[
        0
    ]


# -- contact law -----------------------------------------------------------------
@pytest.mark.parametrize(
    "motion", [(-1e-3, 0.1, 0.0), (0.0, 0.2, 1.0), (2e-3, 0.05, -3.0), (5e-3, -0.08, 2.0)]
)
def test_contact_law_at_null_values_is_the_nominal_spring(motion):
    assert _eval(ContactLaw(ContactLawParams(K)), motion) == pytest.approx(
        _eval(UnilateralSpringContact(ContactParams(K)), motion), rel=1e-15, abs=0.0
    )


def test_contact_law_closed_forms():
    p, v, a = 3e-3, 0.05, -2.0
    f, rate = contact_law_force(ContactLawParams(K, damping_n_s_per_m=400.0), p, v, a)
    assert f == pytest.approx(K * p + 400.0 * v) and rate == pytest.approx(K * v + 400.0 * a)
    f, _ = contact_law_force(ContactLawParams(K, hunt_crossley_s_per_m=3.0), p, v)
    assert f == pytest.approx(K * p * (1 + 3.0 * v))
    # Power law: secant stiffness k at d_ref, f ~ d^n elsewhere.
    law = ContactLawParams(K, exponent=1.5, reference_deflection_m=4e-3)
    assert contact_law_force(law, 4e-3, 0.0)[0] == pytest.approx(K * 4e-3)
    assert contact_law_force(law, 1e-3, 0.0)[0] == pytest.approx(K * 4e-3 * (1 / 4) ** 1.5)
    # Series compliance: k / (1 + k s) for a linear spring; the implicit law otherwise.
    s = 2e-6
    f, _ = contact_law_force(ContactLawParams(K, series_compliance_m_per_n=s), p, 0.0)
    assert f == pytest.approx(K / (1 + K * s) * p)
    law = ContactLawParams(
        K, exponent=1.5, reference_deflection_m=4e-3, series_compliance_m_per_n=s
    )
    f, _ = contact_law_force(law, p, 0.0)
    assert f == pytest.approx(K * 4e-3 * ((p - s * f) / 4e-3) ** 1.5, rel=1e-12)
    # Coulomb friction: +F compressing, -F relaxing, smoothed over v_F.
    law = ContactLawParams(K, friction_force_n=15.0, friction_velocity_m_per_s=1e-3)
    assert contact_law_force(law, p, 0.05)[0] == pytest.approx(K * p + 15.0)
    assert contact_law_force(law, p, -0.05)[0] == pytest.approx(K * p - 15.0)
    assert contact_law_force(law, p, 0.0)[0] == pytest.approx(K * p)


def test_contact_law_never_pulls_and_is_zero_apart():
    law = ContactLawParams(K, damping_n_s_per_m=5000.0, friction_force_n=50.0)
    assert contact_law_force(law, 1e-4, -0.05) == (0.0, 0.0)  # 6 - 250 - 50 < 0
    assert contact_law_force(law, -1e-3, 0.3) == (0.0, 0.0)


def test_contact_law_force_rate_is_the_time_derivative():
    law = ContactLawParams(
        K,
        exponent=1.4,
        reference_deflection_m=5e-3,
        damping_n_s_per_m=200.0,
        hunt_crossley_s_per_m=1.0,
        friction_force_n=10.0,
        friction_velocity_m_per_s=0.01,
        series_compliance_m_per_n=1e-6,
    )
    p, v, a, dt = 3e-3, 0.004, -1.5, 1e-7
    f0, rate = contact_law_force(law, p, v, a)
    f1, _ = contact_law_force(law, p + v * dt + 0.5 * a * dt * dt, v + a * dt)
    assert rate == pytest.approx((f1 - f0) / dt, rel=1e-4)


def test_contact_law_converts_to_autodiff():
    law = ContactLawParams(
        K,
        exponent=1.5,
        reference_deflection_m=4e-3,
        damping_n_s_per_m=100.0,
        series_compliance_m_per_n=1e-6,
    )
    ad = ContactLaw(law).ToAutoDiffXd()
    ctx = ad.CreateDefaultContext()
    x = np.array([3e-3, 0.02, 0.0])
    ad.GetInputPort("motion").FixValue(ctx, InitializeAutoDiff(x))
    f = ad.GetOutputPort("force").Eval(ctx)[0]
    assert isinstance(f, AutoDiffXd)
    eps = 1e-9
    fd = [
        (contact_law_force(law, *(x + eps * e))[0] - contact_law_force(law, *(x - eps * e))[0])
        / (2 * eps)
        for e in np.eye(3)
    ]
    np.testing.assert_allclose(f.derivatives(), fd, rtol=1e-5, atol=1e-6)


def test_contact_law_parameters_are_validated():
    with pytest.raises(ParameterError, match="damping_n_s_per_m"):
        ContactLawParams(K, damping_n_s_per_m=-1.0)
    with pytest.raises(ParameterError, match="exponent"):
        ContactLawParams(K, exponent=0.0)


# -- measurement chain and table -------------------------------------------------
def test_first_order_hold_filter_is_exact_for_a_ramp():
    tau, h = 2e-3, 1e-3
    a, b0, b1 = first_order_hold_filter(tau, h)
    t = h * np.arange(50)
    u = 3.0 * t
    y = np.zeros_like(t)
    for k in range(len(t) - 1):
        y[k + 1] = a * y[k] + b0 * u[k] + b1 * u[k + 1]
    np.testing.assert_allclose(y, 3.0 * (t - tau * (1 - np.exp(-t / tau))), rtol=0, atol=1e-12)
    assert first_order_hold_filter(0.0, h) == (0.0, 0.0, 1.0)


def test_measurement_chain_taps():
    c = MeasurementChainParams(1e-3, delay_s=0.0045)
    assert c.taps() == (4, pytest.approx(0.5))
    assert MeasurementChainParams(1e-3, delay_s=0.004).taps() == (4, 0.0)
    with pytest.raises(ParameterError, match="delay_s"):
        MeasurementChainParams(1e-3, delay_s=-1e-3)


def test_resonant_table_has_unit_static_gain_and_its_mode():
    A, B, C, D = resonant_table_matrices(TableParams(30.0, 0.7), StructuralModeParams(80.0, 0.05))
    x = -np.linalg.solve(A, B @ [1.0, 0.0])  # static response to a unit command
    np.testing.assert_allclose((C @ x + D @ [1.0, 0.0])[:2], [1.0, 0.0], atol=1e-12)
    w = 2 * math.pi * 80.0
    eig = np.linalg.eigvals(A)
    assert np.min(np.abs(eig - complex(-0.05 * w, w * math.sqrt(1 - 0.05**2)))) < 1e-6 * w


# -- each effect's model against an independent rig with that effect ------------
def _noiseless(tmp_path, effect, **info):
    run_info = dict(NOMINAL, run_id=f"hidden-{effect}", **info)
    cols = simulate_hidden(run_info, effect, noise_f_n=0.0, noise_p_m=0.0, substeps=40)
    return read_run(write_run(tmp_path, run_info["run_id"], run_info, cols))


def _true_values(effect: str, scale: RigScale) -> dict[str, float]:
    s = HIDDEN[effect]
    k = NOMINAL["contact_stiffness_n_per_m"]
    if effect == "nonlinear_stiffness":
        big_k = s["k_at_ref"] * s["d_ref"] ** (1 - s["n"])
        return {
            "exponent": s["n"],
            "reference_stiffness_n_per_m": big_k * scale.peak_deflection_m ** (s["n"] - 1),
        }
    return {
        "contact_damping": {"damping_n_s_per_m": s.get("c")},
        "hunt_crossley": {"damping_factor_s_per_m": s.get("alpha")},
        "stiffness_error": {"contact_stiffness_n_per_m": s.get("k")},
        "series_compliance": {"series_compliance_m_per_n": s.get("s")},
        "coulomb_friction": {"friction_force_n": s.get("F")},
        "sensor_filter": {"time_constant_s": s.get("tau")},
        "extra_delay": {"extra_delay_s": s.get("d")},
        "table_resonance": {"frequency_hz": s.get("f"), "damping_ratio": s.get("zeta")},
        "force_bias": {"bias_n": s.get("b")},
    }[effect] | ({} if k else {})


#: Largest |f_mea| error (N) of the model with the true effect against the
#: independent simulation: integration and the smoothed sign of friction,
#: the first-order-hold filter at the touch, interpolation of a fractional delay.
TOLERANCE_N = {"coulomb_friction": 16.0, "sensor_filter": 0.5, "extra_delay": 2.0}


@pytest.mark.parametrize(
    "effect", [e for e in HIDDEN if e not in ("none", "mass_error", "sensor_gain")]
)
def test_effect_model_reproduces_a_rig_with_the_effect(tmp_path, effect):
    run = _noiseless(tmp_path, effect)
    scale = RigScale.from_runs([run])
    nominal = replay(run, accuracy=1e-8)
    spec = build_spec([(get_effect(effect), _true_values(effect, scale))], scale)
    model = replay(run, spec.physics(), accuracy=1e-8)
    e_nom = np.abs(run.f_mea_n - nominal.f_mea_n).max()
    e_mod = np.abs(run.f_mea_n - model.f_mea_n).max()
    p_nom = np.abs(run.p_act_m - nominal.p_act_m).max()
    p_mod = np.abs(run.p_act_m - model.p_act_m).max()
    assert max(e_nom, p_nom * K) > 3.0  # the effect is visible to the nominal model
    assert e_mod < TOLERANCE_N.get(effect, 0.05)
    assert p_mod < 1e-8
    if effect == "coulomb_friction":
        # The smoothed sign differs only near the turning point: |v| < 2 v_F
        # (tanh(2) = 0.96) lasts 4 v_F / a = 4 * 1.6e-3 / 0.75 s, about 9 ticks.
        e = np.abs(run.f_mea_n - model.f_mea_n)
        assert np.sum(e > 0.04 * HIDDEN[effect]["F"]) <= 12


def test_mass_error_changes_only_the_closed_loop(tmp_path):
    from hybridtable.measurement.rig import simulate_rig

    run_info = dict(NOMINAL, run_id="hidden-mass")
    cols = simulate_hidden(run_info, "mass_error", noise_f_n=0.0, noise_p_m=0.0)
    run = read_run(write_run(tmp_path, "hidden-mass", run_info, cols))
    scale = RigScale.from_runs([run])
    spec = build_spec(
        [(get_effect("mass_error"), {"mass_ratio": HIDDEN["mass_error"]["ratio"]})], scale
    )
    assert spec.physics().contact is None and spec.physics().sensor is None
    nominal = simulate_rig(run)
    model = simulate_rig(spec.closed_loop_run(run), spec.physics())
    assert np.abs(nominal.v_des_m_per_s - run.v_des_m_per_s).max() > 1e-3
    assert np.abs(model.v_des_m_per_s - run.v_des_m_per_s).max() < 1e-7


def test_null_spec_gives_the_nominal_physics_and_effects_compose(tmp_path):
    run = _noiseless(tmp_path, "none")
    scale = RigScale.from_runs([run])
    assert ModelSpec().is_nominal and ModelSpec().physics().contact is None
    # Every effect at its null value reproduces the nominal replay.
    ref = replay(run)
    for name in ("contact_damping", "extra_delay", "force_bias", "sensor_filter"):
        e = get_effect(name)
        rep = replay(run, build_spec([(e, e.null_values(scale))], scale).physics())
        np.testing.assert_allclose(rep.f_mea_n, ref.f_mea_n, rtol=0, atol=1e-9)
    both = build_spec(
        [
            (get_effect("contact_damping"), {"damping_n_s_per_m": 300.0}),
            (get_effect("force_bias"), {"bias_n": 5.0}),
        ],
        scale,
    )
    only_damping = build_spec(
        [(get_effect("contact_damping"), {"damping_n_s_per_m": 300.0})], scale
    )
    a = replay(run, both.physics()).f_mea_n
    b = replay(run, only_damping.physics()).f_mea_n
    np.testing.assert_allclose(a - b, 5.0, atol=1e-9)


def test_wrapped_backend_and_user_effect(tmp_path):
    run = _noiseless(tmp_path, "none")
    scale = RigScale.from_runs([run])
    gain = Effect(
        name="sensor_gain_test",
        description="a gain error of the force sensor",
        parameters=(
            EffectParameter(
                "gain", "1", "reading / force", lower=0.5, upper=2.0, scale=0.01, null=1.0
            ),
        ),
        signature=Signature(("f_mea_n",), ("compression", "restitution"), "scaled force"),
        apply=lambda spec, v, s: spec.wrap(
            "sensor",
            lambda p, sensor: chain_output(sensor, MatrixGain([[v["gain"]]]), "measured_force"),
        ),
    )
    register_effect(gain)
    try:
        assert "sensor_gain_test" in effect_names()
        with pytest.raises(ParameterError, match="already registered"):
            register_effect(gain)
        spec = build_spec([(get_effect("sensor_gain_test"), {"gain": 1.1})], scale)
        rep = replay(run, spec.physics())
        np.testing.assert_allclose(rep.f_mea_n, 1.1 * replay(run).f_mea_n, rtol=1e-12, atol=1e-9)
    finally:
        unregister_effect("sensor_gain_test")
    assert "sensor_gain_test" not in EFFECTS


# -- library ---------------------------------------------------------------------
def test_library_holds_the_issue_effects_with_units_and_bounds():
    required = {
        "contact_damping",
        "hunt_crossley",
        "nonlinear_stiffness",
        "stiffness_error",
        "series_compliance",
        "coulomb_friction",
        "sensor_filter",
        "extra_delay",
        "table_resonance",
        "force_bias",
        "mass_error",
    }
    assert required <= set(effect_names())
    scale = RigScale(K, 675.475, 1e-3, 4e-3, 0.08, 30.0)
    for name in required:
        e = get_effect(name)
        assert 1 <= len(e.parameters) <= 2 and e.signature.channels and e.signature.phases
        for p in e.parameters:
            lo, hi = p.bounds(scale)
            assert lo < hi and lo <= p.start(scale) <= hi and p.typical(scale) > 0
            assert p.unit
    assert get_effect("mass_error").stage == "closed_loop"
    assert get_effect("stiffness_error").conflicts_with(get_effect("nonlinear_stiffness"))
    assert not get_effect("contact_damping").conflicts_with(get_effect("force_bias"))


def test_effect_specs_are_parsed_and_checked():
    effect, values = parse_effect_spec("contact_damping:damping_n_s_per_m=250")
    assert effect.name == "contact_damping" and values == {"damping_n_s_per_m": 250.0}
    assert parse_effect_spec("force_bias")[1] == {}
    with pytest.raises(ParameterError, match="unknown effect"):
        parse_effect_spec("magic")
    with pytest.raises(ParameterError, match="no parameter"):
        parse_effect_spec("contact_damping:c=3")
    with pytest.raises(ParameterError, match="not a number"):
        parse_effect_spec("contact_damping:damping_n_s_per_m=lots")
    scale = RigScale(K, 675.475, 1e-3, 4e-3, 0.08, 30.0)
    with pytest.raises(ParameterError, match="out of bounds"):
        effect.check_values({"damping_n_s_per_m": -5.0}, scale)
    assert RigPhysics  # the physics back-end type specs turn into
