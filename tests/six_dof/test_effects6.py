"""Effects on a six-axis rig (Effect.apply6, six_dof/physics6.py, fit6.py):
each vanishes at its null values, acts as its law says, and a fit to the
replays of a noisy run finds the hidden values."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.effects.registry import build_spec, effect_names, get_effect
from hybridtable.effects.spec import RigScale
from hybridtable.errors import ParameterError
from hybridtable.six_dof.fit6 import fit_runs6
from hybridtable.six_dof.physics6 import DockingPhysics, physics_with, rig_scale
from hybridtable.six_dof.pose import rotation_exp
from hybridtable.six_dof.replay6 import replay_run6
from hybridtable.six_dof.run6 import run6_of_docking
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.test_run6 import SCENARIO, scenario_params

SIX = [n for n in effect_names() if get_effect(n).apply6 is not None]


@pytest.fixture(scope="module")
def nominal():
    """The scenario's own run (friction 0.3 stated, so the friction's offset
    is seen), and its replay."""
    scenario = {**SCENARIO, "contact": {**SCENARIO["contact"], "friction_coefficient": 0.3}}
    params = scenario_params(friction_coefficient=0.3)
    run = run6_of_docking(simulate6(params), "nominal", scenario)
    return run, replay_run6(run)


def test_the_six_axis_effects_are_listed_and_refused_by_the_1d_loop():
    assert {"friction_across_face", "sensor_misalignment", "table_misalignment"} <= set(SIX)
    along_the_normal = {"stiffness_error", "extra_delay", "table_response", "table_damping"}
    along_the_normal |= {"hunt_crossley", "sensor_filter", "force_bias", "mount_resonance"}
    along_the_normal |= {"contact_damping", "nonlinear_stiffness", "series_compliance"}
    along_the_normal |= {"coulomb_friction", "table_resonance"}
    assert along_the_normal <= set(SIX)
    face = get_effect("friction_across_face")
    assert face.loops == ("6-DoF",) and face.default_for == ()
    scale = RigScale(1e5, 2533.0, 1e-3, 5e-3, 0.1, 25.0)
    with pytest.raises(ParameterError, match="six-axis rig only"):
        build_spec([(face, {"extra_friction_coefficient": 0.1})], scale)
    with pytest.raises(ParameterError, match="1-D loop only"):
        physics_with([(get_effect("mass_error"), {})], scale)


@pytest.mark.parametrize("name", SIX)
def test_each_effect_vanishes_at_its_null_values_and_acts_away_from_them(nominal, name):
    run, replay = nominal
    effect = get_effect(name)
    scale = rig_scale(run.params)
    null = effect.null_values(scale)
    if null is None:  # a mode: no value at which it vanishes; it acts from its start
        assert all(p.null is None for p in effect.parameters[:1])
        away = effect.start(scale)
    else:
        at_null = replay_run6(run, physics_with([(effect, null)], scale))
        np.testing.assert_array_equal(at_null.measured_wrench, replay.measured_wrench)
        np.testing.assert_array_equal(at_null.table_state, replay.table_state)
        away = {
            p.name: min(null[p.name] + 5.0 * p.typical(scale), p.bounds(scale)[1])
            for p in effect.parameters
        }
    moved = replay_run6(run, physics_with([(effect, away)], scale))
    if effect.stage == "closed_loop":  # the rig computer's: the replay cannot see it, the loop does
        np.testing.assert_array_equal(moved.measured_wrench, replay.measured_wrench)
        looped = run6_of_docking(
            simulate6(run.params, physics=physics_with([(effect, away)], scale)),
            "moved",
            run.scenario,
        )
        n = min(looped.n, run.n)
        assert np.max(np.abs(looped.pose("des")[:n, 3:] - run.pose("des")[:n, 3:])) > 1e-6  # rad
        return
    assert np.max(np.abs(moved.measured_wrench - replay.measured_wrench)) > 1.0  # N or N m


def test_a_turned_sensor_reads_the_turned_wrench_and_a_turned_table_reaches_the_turned_pose(
    nominal,
):
    run, replay = nominal
    theta = np.array([0.01, -0.02, 0.005])
    R = rotation_exp(theta)
    turned = replay_run6(run, DockingPhysics().turn_sensor(theta))
    w = replay.measured_wrench
    expected = np.hstack([w[:, :3] @ R.T, w[:, 3:] @ R.T])
    np.testing.assert_allclose(turned.measured_wrench, expected, rtol=0, atol=1e-9)
    # an ideal table reaches the command it sees: R times the commanded pose
    ideal = run.params.with_(table_response_hz=float("inf"))
    run_ideal = run6_of_docking(simulate6(ideal), "ideal", {**SCENARIO, "table": {}})
    table = replay_run6(run_ideal, DockingPhysics().turn_table(theta)).table_state
    q = run_ideal.pose("des")
    np.testing.assert_allclose(table[1:, :3], q[:-1, :3] @ R.T, rtol=0, atol=1e-12)


def test_a_fit_to_a_noisy_run_finds_the_hidden_values():
    """Hidden: a turned sensor and friction across the face; F/T and encoder
    noise in the loop."""
    scenario = {
        **SCENARIO,
        "rig": {
            **SCENARIO["rig"],
            "force_noise_n": 2.0,
            "moment_noise_n_m": 0.5,
            "position_noise_m": 2e-6,
            "attitude_noise_rad": 1e-6,
        },
        "compensator": {"name": "SDMDC", "force_deadband_n": 12.0},
    }
    from hybridtable.six_dof.scenario import parse_scenario

    params = parse_scenario(scenario)
    truth = {"sensor_roll_rad": 0.01, "sensor_pitch_rad": -0.02, "sensor_yaw_rad": 0.005}
    friction = {"extra_friction_coefficient": 0.2}
    hidden = physics_with(
        [
            (get_effect("sensor_misalignment"), truth),
            (get_effect("friction_across_face"), friction),
        ],
        rig_scale(params),
    )
    run = run6_of_docking(simulate6(params, physics=hidden), "hidden", scenario)
    fit = fit_runs6(
        [run], [(get_effect("sensor_misalignment"), {}), (get_effect("friction_across_face"), {})]
    )
    assert fit.chi2_after < 0.01 * fit.chi2_before
    assert fit.chi2_after / fit.n_residuals < 1.5  # down to the noise
    for name, values in (("sensor_misalignment", truth), ("friction_across_face", friction)):
        for k, v in values.items():
            std = fit.std[name][k]
            assert std is not None and abs(fit.values[name][k] - v) < 4.0 * std + 1e-9, (k, std)
    # a given value is held
    held = fit_runs6(
        [run], [(get_effect("friction_across_face"), {"extra_friction_coefficient": 0.2})]
    )
    assert held.values["friction_across_face"]["extra_friction_coefficient"] == 0.2
    assert held.fitted["friction_across_face"] == ()


def test_a_low_pass_and_a_bias_read_as_the_1d_chains_law(nominal):
    """The sensor's low pass is the 1-D measurement chain's first-order-hold
    filter on each channel (it commutes with the whole-tick delay: zero
    before the contact), the bias an offset of the compression force."""
    from hybridtable.systems.measurement_chain import first_order_hold_filter

    run, replay = nominal
    tau = 0.004
    filtered = replay_run6(run, DockingPhysics().low_pass(tau).biased([0, 0, 0, 0, 0, -5.0]))
    a, b0, b1 = first_order_hold_filter(tau, run.params.sample_period_s)
    u = replay.measured_wrench
    y = np.zeros_like(u)
    for k in range(len(u)):
        y[k] = b1 * u[k] + (a * y[k - 1] + b0 * u[k - 1] if k else 0.0)
    y[:, 5] -= 5.0
    np.testing.assert_allclose(filtered.measured_wrench, y, rtol=0, atol=1e-9)


def test_a_mount_reads_as_the_1d_chains_mount_on_each_channel(nominal):
    """The compliant mount is the 1-D measurement chain's mode on each channel
    (before the whole-tick delay, which it commutes with: zero before the
    contact), and ringing: the reading overshoots the replayed wrench."""
    from hybridtable.systems.measurement_chain import MeasurementChain, MeasurementChainParams

    run, replay = nominal
    h = run.params.sample_period_s
    mounted = replay_run6(run, DockingPhysics().mount(45.0, 0.1))
    chain = MeasurementChain(
        MeasurementChainParams(h, mount_frequency_hz=45.0, mount_damping_ratio=0.1)
    )
    u = replay.measured_wrench
    expected = np.stack([chain.readings(u[:, j]) for j in range(6)], axis=1)
    np.testing.assert_allclose(mounted.measured_wrench, expected, rtol=0, atol=1e-9)
    assert mounted.measured_wrench[:, 5].max() > 1.05 * u[:, 5].max()  # it overshoots
