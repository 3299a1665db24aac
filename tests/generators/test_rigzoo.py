"""Physics facts of the independent generator ``rigzoo`` (no hybridtable code)."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from tests.generators import rigzoo as rz

FORMAT_KEYS = {
    "format",
    "run_id",
    "sample_rate_hz",
    "spacecraft_mass_kg",
    "contact_stiffness_n_per_m",
    "sensor_delay_s",
    "table_natural_frequency_hz",
    "table_damping_ratio",
    "compensator",
    "lead_time_s",
    "initial_gap_m",
    "initial_velocity_m_per_s",
    "force_deadband_n",
}

RIG = rz.Rig(
    sample_rate_hz=1000,
    mass_kg=400.0,
    stiffness_n_per_m=200000.0,
    delay_ticks=5,
    table_hz=60.0,
    table_zeta=0.7,
    deadband_n=2.0,
    lead_time_s=0.005,
    initial_gap_m=0.0008,
)
NOISE = rz.NoiseSpec("ar1", (0.6,), sigma_f=8.0, sigma_p=4e-6)


def _spec(label="null", hidden=(), comps=("SDMDC", "none", "MDC"), seed=7):
    vel = (0.08, 0.15, 0.05)
    return rz.SetSpec(
        set_id=f"t-{label}",
        label=label,
        rig=RIG,
        noise=NOISE,
        velocities=vel,
        compensators=comps,
        n_ticks=(500, 500, 500),
        seed=seed,
        hidden=tuple(hidden),
    )


def _computer_replay(r: rz.RunRecord, m=None, lead=None, kc=None):
    """f_comp and v_des recomputed from the record by the format's arithmetic."""
    meta = r.meta
    h = 1.0 / meta["sample_rate_hz"]
    m = m or meta["spacecraft_mass_kg"]
    lead = meta["lead_time_s"] if lead is None else lead
    kc = meta["contact_stiffness_n_per_m"] if kc is None else kc
    comp = meta["compensator"]
    f, pa, pdes = r.f_mea, r.p_act, r.p_des
    fc = np.zeros_like(f)
    for k in range(1, len(f)):
        if f[k] <= meta["force_deadband_n"]:
            continue
        v = f[k]
        if comp in ("SDC", "SDMDC"):
            v += lead * (f[k] - f[k - 1]) / h
        if comp in ("MDC", "SDMDC"):
            v += kc * (pdes[k - 1] - pa[k])
        fc[k] = max(v, 0.0)
    v = r.v_des[0] - np.cumsum(np.r_[0.0, fc[1:]]) / m * h
    return fc, v


def test_written_runs_obey_the_computers_arithmetic(tmp_path):
    spec = _spec()
    paths = rz.write_set(tmp_path, spec)
    assert len(paths) == 3
    runs = rz.read_set(tmp_path)
    metas = [r.meta for r in runs]
    for meta in metas:
        assert set(meta) == FORMAT_KEYS
        fs = meta["sample_rate_hz"]
        assert abs(meta["sensor_delay_s"] * fs - round(meta["sensor_delay_s"] * fs)) < 1e-9
    common = [
        {
            k: v
            for k, v in m.items()
            if k not in ("run_id", "compensator", "initial_velocity_m_per_s")
        }
        for m in metas
    ]
    assert all(c == common[0] for c in common)
    header = paths[0].read_text().splitlines()[0]
    assert header == "time_s,p_des_m,p_act_m,f_mea_n,f_comp_n,v_des_m_per_s"
    for r in runs:
        h = 1.0 / r.meta["sample_rate_hz"]
        fc, v = _computer_replay(r)
        scale = max(1.0, float(np.abs(r.f_comp).max()))
        assert np.max(np.abs(fc[1:] - r.f_comp[1:])) < 1e-6 * scale
        assert np.max(np.abs(v - r.v_des)) < 1e-6 * r.meta["initial_velocity_m_per_s"]
        # p_des steps by v_des h, from -gap.
        x = -r.meta["initial_gap_m"] + np.cumsum(r.v_des) * h
        assert np.max(np.abs(x - r.p_des)) < 1e-6 * r.meta["initial_gap_m"]
        assert r.time_s[1] == pytest.approx(h)


def test_slow_contact_peak_force_is_v_sqrt_km():
    rig = replace(RIG, sample_rate_hz=500, mass_kg=2000.0, stiffness_n_per_m=20000.0)
    rig = replace(rig, delay_ticks=1, table_hz=80.0, lead_time_s=0.002)
    v = 0.1
    r = rz.simulate_run(rig, None, v, "none", 1300)
    assert r.force.max() == pytest.approx(v * math.sqrt(2000.0 * 20000.0), rel=0.02)
    assert r.penetration.max() == pytest.approx(v * math.sqrt(2000.0 / 20000.0), rel=0.02)
    # The sensor reads the force one tick late.
    assert np.array_equal(r.f_mea[1:], r.force[:-1])


def test_nominal_error_is_one_with_noise_and_zero_without():
    for seed in (11, 12, 13):
        spec = rz.draw_base(np.random.default_rng(seed), "n", "null")
        runs = rz.simulate_set(spec)
        err = rz.nominal_error(runs, spec.noise.sigma_f, spec.noise.sigma_p)
        assert 0.9 <= err <= 1.1, (seed, err)
        clean = rz.simulate_set(spec, noise=False)
        assert rz.nominal_error(clean, spec.noise.sigma_f, spec.noise.sigma_p) < 1e-9


def test_fast_and_fine_paths_agree():
    for comp in ("none", "SDMDC"):
        a = rz.simulate_run(RIG, None, 0.1, comp, 400, noise=NOISE, seed=3)
        b = rz.simulate_run(RIG, None, 0.1, comp, 400, noise=NOISE, seed=3, force_fine=True)
        for col in ("p_des", "p_act", "f_mea", "f_comp", "v_des"):
            x, y = getattr(a, col), getattr(b, col)
            assert np.max(np.abs(x - y)) <= 1e-9 * np.max(np.abs(x)), col


def test_whole_tick_extra_delay_equals_a_longer_json_delay():
    a = rz.simulate_run(RIG, {"extra_delay": {"d_s": 0.002}}, 0.1, "none", 400)
    b = rz.simulate_run(replace(RIG, delay_ticks=7), None, 0.1, "none", 400)
    assert np.max(np.abs(a.f_mea - b.f_mea)) < 1e-9 * np.max(b.f_mea)


@pytest.mark.parametrize("name,target", [("contact_damping", 2.5), ("extra_delay", 2.0)])
def test_size_effect_reaches_its_target(name, target):
    spec = _spec("single", (rz.make_hidden(name, np.random.default_rng(0)),))
    sized = rz.size_effect(spec, 0, target)
    assert sized.hidden[0].magnitude > 0
    err = rz.set_error(sized)
    assert err == pytest.approx(target, rel=0.05)
    assert sized.info["sized_error"][name] == pytest.approx(err)


def test_mass_error_shows_in_the_velocity_increments(tmp_path):
    hid = rz.Hidden("mass_error", 0.12, {"sign": -1.0})
    spec = _spec("computer", (hid,))
    rz.write_set(tmp_path, spec)
    m_used = hid.params(spec.scales)["m_used_kg"]
    assert m_used == pytest.approx(RIG.mass_kg * 0.88)
    for r in rz.read_set(tmp_path):
        h = 1.0 / r.meta["sample_rate_hz"]
        dv = np.diff(r.v_des)
        fc = r.f_comp[1:]
        on = fc > 0.05 * fc.max()
        m_est = -fc[on] * h / dv[on]
        assert np.median(m_est) == pytest.approx(m_used, rel=1e-5)
        assert r.meta["spacecraft_mass_kg"] == RIG.mass_kg


def test_lead_and_stiffness_errors_show_in_the_compensation():
    spec = _spec(
        "computer", (rz.Hidden("lead_time_error", 0.3, {"sign": 1.0}),), comps=("SDMDC",) * 3
    )
    for r in rz.simulate_set(spec):
        fc, _ = _computer_replay(r, lead=RIG.lead_time_s * 1.3)
        assert np.max(np.abs(fc[1:] - r.f_comp[1:])) < 1e-6 * r.f_comp.max()
    spec = _spec("computer", (rz.Hidden("compensator_stiffness_error", 0.2, {"sign": -1.0}),))
    for r in rz.simulate_set(spec):
        fc, _ = _computer_replay(r, kc=RIG.stiffness_n_per_m * 0.8)
        assert np.max(np.abs(fc[1:] - r.f_comp[1:])) < 1e-6 * r.f_comp.max()


def test_every_effect_simulates_and_shows():
    rng = np.random.default_rng(5)
    spec = _spec("single")
    base = rz.set_error(spec)
    for name in (*rz.LIBRARY_PHYSICS, *rz.OUTSIDE_EFFECTS):
        h = rz.make_hidden(name, rng)
        lo, hi = rz.magnitude_bounds(h, spec.scales)
        h = replace(h, magnitude=min(hi, max(lo, 4 * rz.EFFECTS[name].guess)))
        runs = rz.simulate_set(spec, hidden=(h,))
        assert not any(r.diverged for r in runs), name
        err = rz.nominal_error(runs, NOISE.sigma_f, NOISE.sigma_p)
        assert err > base * 1.02, (name, err, base)


def test_draw_study_classes_and_seeds():
    specs = rz.draw_study(0)
    assert len(specs) >= 80
    by = {}
    for s in specs:
        by.setdefault(s.label, []).append(s)
    assert len(by["null"]) >= 15
    singles = {(s.hidden[0].name, s.hidden[0].target_error) for s in by["single"]}
    assert singles == {(n, t) for n in rz.LIBRARY_PHYSICS for t in (2.0, 5.0)}
    assert len(by["pair"]) + len(by["pair_cancel"]) >= 8
    assert len(by["pair_cancel"]) >= 3
    assert len(by["outside"]) >= 10
    assert len({s.hidden[0].name for s in by["outside"]}) >= 8
    assert {s.hidden[0].name for s in by["computer"]} == set(rz.COMPUTER_EFFECTS)
    assert by["tiny"] and all(1.2 <= s.hidden[0].target_error <= 1.4 for s in by["tiny"])
    assert {c for s in specs for c in s.compensators} == set(rz.COMPENSATORS)
    for s in specs:
        assert s.truth() == (
            set() if s.label in ("null", "outside") else {h.name for h in s.hidden}
        )
        assert 2 <= len(s.velocities) <= 5
        assert max(s.n_ticks) <= rz.MAX_TICKS
        r = s.rig
        assert 100 <= r.mass_kg <= 5000 and 1e4 <= r.stiffness_n_per_m <= 1e6
        assert 1e-3 - 1e-12 <= r.sensor_delay_s <= 20e-3 + 1e-12
        assert r.contact_hz <= r.table_hz / 4
    other = rz.draw_study(1)
    assert not {s.rig for s in specs} & {s.rig for s in other}
    assert [s.rig for s in rz.draw_study(0)] == [s.rig for s in specs]
    json.dumps([s.to_json() for s in specs])


def test_noise_has_the_stated_marginal_std_and_lag1():
    rng = np.random.default_rng(2)
    for spec in (
        rz.NoiseSpec("white", (), 1.0, 1.0),
        rz.NoiseSpec("ar1", (0.8,), 1.0, 1.0),
        rz.NoiseSpec("ar2", (1.4, -0.48), 1.0, 1.0),
        rz.NoiseSpec("ar2", (0.6, -0.64), 1.0, 1.0),
    ):
        e = spec.unit_series(rng, 200_000)
        assert e.std() == pytest.approx(1.0, rel=0.03), spec
        assert np.corrcoef(e[1:], e[:-1])[0, 1] == pytest.approx(spec.lag1(), abs=0.02), spec


def test_cancel_pair_keeps_the_cor():
    rng = np.random.default_rng(4)
    spec = _spec(
        "pair_cancel",
        (
            rz.make_hidden("contact_damping", rng, target_error=4.0),
            rz.make_hidden("extra_delay", rng),
        ),
    )
    out = rz.resolve(spec)
    info = out.info
    assert abs(info["cor_pair"] - info["cor_null"]) < 0.01
    assert info["cor_null"] - info["cor_first_alone"] > 0.05
    assert info["cor_second_alone"] - info["cor_null"] > 0.03
    assert info["error"] >= 2.5
    assert out.truth() == {"contact_damping", "extra_delay"}


def test_loaded_table_mode_tends_to_the_base_excited_one():
    base = {"fr_hz": 150.0, "zeta_r": 0.05}
    a = rz.simulate_run(RIG, {"table_resonance": {**base, "m_r_kg": 0.0}}, 0.1, "SDMDC", 400)
    b = rz.simulate_run(RIG, {"table_resonance": {**base, "m_r_kg": 1e9}}, 0.1, "SDMDC", 400)
    n = rz.simulate_run(RIG, None, 0.1, "SDMDC", 400)
    assert np.max(np.abs(a.f_mea - b.f_mea)) < 1e-5 * np.max(a.f_mea)
    assert np.max(np.abs(a.p_act - b.p_act)) < 1e-5 * np.max(np.abs(a.p_act))
    # ... and the mode shows in both channels.
    assert np.max(np.abs(a.f_mea - n.f_mea)) > 1e-3 * np.max(a.f_mea)
    assert np.max(np.abs(a.p_act - n.p_act)) > 1e-7
