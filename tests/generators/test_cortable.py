"""Physics facts of the independent CoR-table generator ``cortable`` (no hybridtable code)."""

from __future__ import annotations

import ast
import csv
import math
from pathlib import Path

import numpy as np
import pytest

from tests.generators import cortable as ct
from tests.generators import rigzoo as rz

INF = math.inf
PI2 = math.pi**2
#: One clearly visible size of each loop effect at the Table 1 point.
LOOP_CASES = {
    "extra_delay": {"extra_delay_s": 0.002},
    "lead_time_error": {"lead_time_s": 0.008},
    "table_response": {"table_response_hz": 15.0},
    "table_damping": {"table_damping_ratio": 0.5},
    "stiffness_error": {"compensator_stiffness_ratio": 0.7},
    "contact_frequency_error": {"contact_frequency_ratio": 1.3},
    "contact_damping": {"damping_n_s_per_m": 2000.0},
    "contact_damping_ratio": {"contact_damping_ratio": 0.05},
}


def _cors(condition=None, hidden=None, fs=10000.0, **kw) -> dict[str, float]:
    rows = ct.make_table([condition or {}], hidden=hidden, sample_rate_hz=fs, decimals=None, **kw)
    return {r["compensator"]: r["cor"] for r in rows}


def _interaction(c: dict[str, float]) -> float:
    ln = {k: math.log(v) for k, v in c.items()}
    return ln["none"] - ln["SDC"] - ln["MDC"] + ln["SDMDC"]


def test_every_effect_has_a_case_and_the_lists_agree():
    assert set(LOOP_CASES) == set(ct.LOOP_EFFECTS)
    assert set(ct.LOOP_EFFECTS) | set(ct.OUTSIDE_EFFECTS) == set(ct.HIDDEN_EFFECTS)


def test_the_generator_does_not_import_hybridtable():
    for name in ("cortable.py", "test_cortable.py"):
        tree = ast.parse((Path(__file__).parent / name).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                mods = [node.module or ""]
            else:
                continue
            assert not any(m.split(".")[0] == "hybridtable" for m in mods), name


@pytest.mark.parametrize("f_con", [1.0, 2.0, 5.0])
def test_ideal_loop_keeps_the_energy(f_con):
    # No delay, ideal table: semi-implicit Euler on the spring; measured
    # |CoR - 1| = 1e-11 (1 Hz), 2e-10 (2 Hz), 8e-9 (5 Hz) at 1 kHz.
    cond = {"contact_frequency_hz": f_con, "sensor_delay_s": 0.0, "table_response_hz": INF}
    for cor in _cors(cond, fs=1000.0).values():
        assert abs(cor - 1.0) < 1e-7


def test_ln_cor_grows_linearly_with_the_delay_at_slope_pi2_fcon():
    # Ideal table, no compensation, D = 0 .. 2 ms at 10 kHz: measured slope
    # 9.8692 1/s = 0.99996 pi^2 f_con at 1 Hz (0.99983 at 2 Hz).
    fs = 10000.0
    for f_con in (1.0, 2.0):
        delays = np.arange(0, 21, 4) / fs
        ln = [
            math.log(
                _cors(
                    {"contact_frequency_hz": f_con, "sensor_delay_s": d, "table_response_hz": INF},
                    fs=fs,
                    compensators=("none",),
                )["none"]
            )
            for d in delays
        ]
        slope, icpt = np.polyfit(delays, ln, 1)
        assert slope == pytest.approx(PI2 * f_con, rel=5e-4)
        assert abs(icpt) < 3e-6
        assert np.max(np.abs(np.polyval([slope, icpt], delays) - ln)) < 1e-4 * max(ln)


def test_cor_is_invariant_when_times_scale_together():
    base = {
        "contact_frequency_hz": 1.0,
        "sensor_delay_s": 0.004,
        "lead_time_s": 0.003,
        "table_response_hz": 25.0,
        "table_damping_ratio": 0.8,
    }
    ref = _cors(base, fs=10000.0)
    assert ref["none"] > 1.1  # the point is not trivial
    for s in (2.0, 4.0):
        cond = {
            "contact_frequency_hz": 1.0 * s,
            "sensor_delay_s": 0.004 / s,
            "lead_time_s": 0.003 / s,
            "table_response_hz": 25.0 * s,
            "table_damping_ratio": 0.8,
        }
        # The sample rate scaled too: the same discrete loop (measured to 1e-12).
        exact = _cors(cond, fs=10000.0 * s)
        # At a fixed 10 kHz (continuous limit): measured |dCoR| 5.6e-4 (x2), 1.7e-3 (x4).
        fixed = _cors(cond, fs=10000.0)
        for comp in ct.COMPENSATORS:
            assert exact[comp] == pytest.approx(ref[comp], rel=1e-9)
            assert abs(fixed[comp] - ref[comp]) < 1e-3 * s


def test_nominal_cor_depends_on_the_contact_frequency_only():
    # Linear, homogeneous loop: k and m scaled together, or the velocity, change nothing.
    ref = _cors({}, fs=2000.0)
    for cond in (
        {"contact_stiffness_n_per_m": 3e5},
        {"contact_stiffness_n_per_m": 5e4, "initial_velocity_m_per_s": 0.2},
        {"initial_velocity_m_per_s": 0.03},
    ):
        got = _cors(cond, fs=2000.0)
        for comp in ct.COMPENSATORS:
            assert got[comp] == pytest.approx(ref[comp], rel=1e-9)


def test_table1_point_reproduces_the_paper():
    # Paper Table 1: 1.1611 / 1.1057 / 1.0508 / 0.9999; measured at 10 kHz:
    # 1.16058 / 1.10515 / 1.05033 / 1.00006.
    got = _cors(fs=10000.0)
    paper = {"none": 1.1611, "SDC": 1.1057, "MDC": 1.0508, "SDMDC": 0.9999}
    for comp, cor in paper.items():
        assert got[comp] == pytest.approx(cor, abs=1e-3), comp
    # The run format's clamped computer keeps the onset loss: SDMDC 1.0046.
    clamped = _cors(fs=10000.0, clamp_nonnegative=True)
    assert clamped["SDMDC"] == pytest.approx(1.0046, abs=3e-4)
    assert clamped["none"] == pytest.approx(got["none"], abs=1e-9)


def test_table1_point_agrees_with_first_order():
    got = _cors(fs=10000.0)
    for comp, cor in got.items():
        fo = ct.first_order_ln_cor(comp, 1.0, 0.005, 25.0, 0.8)
        assert math.log(cor) == pytest.approx(fo, abs=1.2e-3), comp


@pytest.mark.parametrize("name", sorted(LOOP_CASES))
def test_loop_effects_do_not_interact_and_follow_first_order(name):
    # Measured |I| at 10 kHz (I = ln none - ln SDC - ln MDC + ln SDMDC): nominal
    # 1.0e-4, extra_delay 0.7e-4, lead_time_error 1.9e-4, table_response 2.7e-4,
    # table_damping 0.2e-4, stiffness_error 0.8e-4, contact_frequency_error
    # 2.2e-4, contact_damping 1.9e-4, contact_damping_ratio 1.6e-4.
    hidden = {name: LOOP_CASES[name]}
    got = _cors(hidden=hidden, fs=10000.0)
    nominal = _cors(fs=10000.0)
    assert abs(_interaction(got)) < 2e-3
    # The effect is visible (not a vacuous test).
    assert max(abs(math.log(got[c] / nominal[c])) for c in ct.COMPENSATORS) > 0.015
    # ... and where the first-order law says: lags within 2.5e-3 in ln CoR
    # (measured <= 2.0e-3); a damper that never pulls departs from -pi zeta by
    # up to 8 % of it (zeta 0.05: 0.0115; zeta 0.063: 0.016).
    st, rig = ct.true_rig({}, hidden, 10000.0)
    zeta = rig.damping_n_s_per_m / (2.0 * math.sqrt(rig.stiffness_n_per_m * rig.mass_kg))
    for comp, cor in got.items():
        fo = ct.first_order_ln_cor(
            comp,
            rig.contact_hz,
            rig.delay_ticks / rig.sample_rate_hz,
            rig.table_hz,
            rig.table_zeta,
            lead_time_s=rig.lead_time_s,
            compensator_stiffness_ratio=rig.compensator_stiffness_n_per_m / rig.stiffness_n_per_m,
            contact_damping_ratio=zeta,
        )
        tol = 2.5e-3 + 0.1 * math.pi * zeta
        assert math.log(cor) == pytest.approx(fo, abs=tol), comp


def test_single_effects_move_the_compensators_they_should():
    nom = _cors(fs=2000.0)
    # extra delay: every compensator up by about pi^2 f_con d.
    d = _cors(hidden={"extra_delay": LOOP_CASES["extra_delay"]}, fs=2000.0)
    for comp in ct.COMPENSATORS:
        assert math.log(d[comp] / nom[comp]) == pytest.approx(PI2 * 0.002, rel=0.03)
    # lead error: only the SDC rows move.
    lead = _cors(hidden={"lead_time_error": LOOP_CASES["lead_time_error"]}, fs=2000.0)
    assert lead["none"] == nom["none"] and lead["MDC"] == nom["MDC"]
    assert lead["SDC"] < nom["SDC"] - 0.02 and lead["SDMDC"] < nom["SDMDC"] - 0.02
    # MDC stiffness error: only the MDC rows move.
    kc = _cors(hidden={"stiffness_error": LOOP_CASES["stiffness_error"]}, fs=2000.0)
    assert kc["none"] == nom["none"] and kc["SDC"] == nom["SDC"]
    assert kc["MDC"] > nom["MDC"] + 0.02 and kc["SDMDC"] > nom["SDMDC"] + 0.02
    # a slower table: the MDC rows stay (it reads the true p_act).
    tab = _cors(hidden={"table_response": LOOP_CASES["table_response"]}, fs=2000.0)
    assert tab["none"] > nom["none"] + 0.05
    assert abs(tab["SDMDC"] - nom["SDMDC"]) < 1e-3


def test_outside_series_compliance_stiffer_spring_lowers_the_cor():
    # Same stated f_con 1 Hz, compliance 2 um/N: k s = 0.1, 0.2, 0.6.
    # Measured SDMDC at 2 kHz: 0.9909, 0.9823, 0.9547 (none 1.1505, 1.1437, 1.1234).
    hidden = {"series_compliance": {"compliance_m_per_n": 2e-6}}
    by_k = [_cors({"contact_stiffness_n_per_m": k}, hidden, 2000.0) for k in (5e4, 1e5, 3e5)]
    for comp in ct.COMPENSATORS:
        cors = [c[comp] for c in by_k]
        assert cors[0] > cors[1] + 1e-3 > cors[2] + 2e-3, comp
    assert by_k[2]["SDMDC"] < 0.96
    # The velocity does not matter (the law stays linear).
    slow = _cors({"initial_velocity_m_per_s": 0.03}, hidden, 2000.0)
    assert slow["SDMDC"] == pytest.approx(by_k[1]["SDMDC"], rel=1e-9)


def test_outside_hunt_crossley_loss_grows_with_the_velocity():
    # alpha 1 s/m: measured SDMDC 0.9678, 0.9372, 0.8813 at 0.05, 0.1, 0.2 m/s;
    # the stiffness at a given f_con does not matter.
    hidden = {"hunt_crossley": {"alpha_s_per_m": 1.0}}
    by_v = [_cors({"initial_velocity_m_per_s": v}, hidden, 2000.0) for v in (0.05, 0.1, 0.2)]
    for comp in ct.COMPENSATORS:
        cors = [c[comp] for c in by_v]
        assert cors[0] > cors[1] + 0.02 > cors[2] + 0.04, comp
    stiff = _cors({"contact_stiffness_n_per_m": 3e5}, hidden, 2000.0)
    assert stiff["none"] == pytest.approx(by_v[1]["none"], rel=1e-9)


def test_outside_coulomb_friction_loss_scales_with_the_peak_force():
    # F 20 N: the loss depends on v sqrt(k m) only; stiffer or faster -> higher CoR.
    hidden = {"coulomb_friction": {"friction_n": 20.0}}
    soft = _cors({"contact_stiffness_n_per_m": 5e4}, hidden, 2000.0)
    mid = _cors({"contact_stiffness_n_per_m": 1e5}, hidden, 2000.0)
    stiff = _cors({"contact_stiffness_n_per_m": 3e5}, hidden, 2000.0)
    same_peak = _cors(
        {"contact_stiffness_n_per_m": 5e4, "initial_velocity_m_per_s": 0.2}, hidden, 2000.0
    )
    for comp in ct.COMPENSATORS:
        assert soft[comp] < mid[comp] - 0.01 < stiff[comp] - 0.02, comp
        assert same_peak[comp] == pytest.approx(mid[comp], rel=1e-6)


@pytest.mark.parametrize(
    "ours,theirs",
    [
        (None, None),
        (
            {"contact_damping": {"damping_n_s_per_m": 2000.0}},
            {"contact_damping": {"c_n_s_per_m": 2000.0}},
        ),
        (
            {"stiffness_error": {"compensator_stiffness_ratio": 0.7}},
            {"compensator_stiffness_error": {"k_used_n_per_m": 7e4}},
        ),
        (
            {"contact_frequency_error": {"contact_frequency_ratio": 1.3}},
            {"mass_error": {"m_used_kg": 1e5 / (2 * math.pi * 1.3) ** 2}},
        ),
        (
            {"series_compliance": {"compliance_m_per_n": 2e-6}},
            {"series_compliance": {"s_m_per_n": 2e-6}},
        ),
    ],
)
def test_agrees_with_rigzoo_when_clamped(ours, theirs):
    # rigzoo (the run format's clamped computer, its own start and integrator
    # path): measured |dCoR| <= 1.5e-5 at 10 kHz.
    fs = 10000
    rig = rz.Rig(
        sample_rate_hz=fs,
        mass_kg=1e5 / (2 * math.pi) ** 2,
        stiffness_n_per_m=1e5,
        delay_ticks=50,
        table_hz=25.0,
        table_zeta=0.8,
        deadband_n=0.0,
        lead_time_s=0.005,
        initial_gap_m=0.01,
    )
    got = _cors(hidden=ours, fs=fs, clamp_nonnegative=True)
    for comp in ct.COMPENSATORS:
        ref = rz.simulate_run(rig, theirs, 0.1, comp, 8000).cor
        assert got[comp] == pytest.approx(ref, abs=5e-5), comp


def test_rows_carry_the_stated_conditions_not_the_true_ones():
    rows = ct.make_table(
        [{"sensor_delay_s": 0.003, "contact_stiffness_n_per_m": 2e5}],
        hidden={"extra_delay": {"extra_delay_s": 0.002}},
        sample_rate_hz=1000.0,
    )
    assert [r["compensator"] for r in rows] == list(ct.COMPENSATORS)
    for r in rows:
        assert set(r) == set(ct.COLUMNS) - {"cor_std"}
        assert r["sensor_delay_s"] == 0.003 and r["lead_time_s"] == 0.003
        assert r["contact_stiffness_n_per_m"] == 2e5 and r["sample_rate_hz"] == 1000.0
        assert r["cor"] == round(r["cor"], 4)
    truth = ct.make_table(
        [{"sensor_delay_s": 0.005, "lead_time_s": 0.003, "contact_stiffness_n_per_m": 2e5}],
        sample_rate_hz=1000.0,
    )
    assert [r["cor"] for r in rows] == [r["cor"] for r in truth]


def test_repeats_scatter_with_the_noise_and_the_seed():
    rows = ct.make_table(
        [{}], ("SDMDC",), sample_rate_hz=1000.0, repeats=400, cor_noise_std=0.01, seed=3
    )
    cors = np.array([r["cor"] for r in rows])
    assert len(rows) == 400
    assert np.std(cors, ddof=1) == pytest.approx(0.01, rel=0.1)
    assert np.mean(cors) == pytest.approx(_cors(fs=1000.0)["SDMDC"], abs=3e-3)
    again = ct.make_table(
        [{}], ("SDMDC",), sample_rate_hz=1000.0, repeats=400, cor_noise_std=0.01, seed=3
    )
    assert [r["cor"] for r in again] == list(cors)


def test_write_csv_writes_the_present_columns_in_order(tmp_path):
    rows = ct.make_table(
        [{}, {"contact_frequency_hz": 2.0}], ("none", "SDMDC"), sample_rate_hz=1000.0
    )
    rows.append({"compensator": "MDC", "cor": 1.05, "cor_std": 0.002})
    path = ct.write_csv(rows, tmp_path / "cor.csv")
    with path.open(newline="") as fh:
        table = list(csv.reader(fh))
    assert table[0] == list(ct.COLUMNS)
    assert all(len(line) == len(ct.COLUMNS) for line in table)
    assert table[1][:2] == ["none", str(rows[0]["cor"])]
    assert table[1][2] == "" and table[-1][2] == "0.002" and table[-1][3] == ""
    assert float(table[3][4]) == 2.0 and table[1][3] == "100000"
    few = ct.write_csv([{"compensator": "none", "cor": 1.2}], tmp_path / "few.csv")
    assert few.read_text() == "compensator,cor\nnone,1.2\n"


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="whole number of ticks"):
        ct.make_table([{"sensor_delay_s": 0.00125}], sample_rate_hz=1000.0)
    with pytest.raises(ValueError, match="unknown hidden effect"):
        ct.make_table([{}], hidden={"backlash": {}})
    with pytest.raises(ValueError, match="takes"):
        ct.make_table([{}], hidden={"extra_delay": {"delay_s": 0.001}})
    with pytest.raises(ValueError, match="unknown condition"):
        ct.make_table([{"mass_kg": 3.0}])
    with pytest.raises(ValueError, match="elastic"):
        ct.make_table(
            [{}],
            hidden={
                "series_compliance": {"compliance_m_per_n": 1e-6},
                "coulomb_friction": {"friction_n": 1.0},
            },
        )
