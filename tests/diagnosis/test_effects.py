"""Candidate effects: the library and registry, and each effect against an
independent simulation of a rig that has it (tests/generators/effectsim.py).
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.effects.registry import (
    EFFECTS,
    build_spec,
    effect_names,
    get_effect,
    parse_effect_spec,
    register_effect,
    unregister_effect,
)
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError
from hybridtable.measurement.replay import replay
from hybridtable.measurement.rig import RigPhysics
from hybridtable.measurement.run_reader import read_run
from tests.diagnosis.support import sensor_gain_effect
from tests.generators.effectsim import HIDDEN, simulate_hidden
from tests.generators.rigsim import NOMINAL, write_run

#: Contact stiffness of the test rigs, N/m.
K = 60000.0


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
    gain = sensor_gain_effect("sensor_gain_test", typical_change=0.01)
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
