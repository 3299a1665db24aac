"""The compensator sweep as a campaign: every run's sweep inputs make the loop
the study describes (a Table 2 point, the scenario's contact, the believed
stiffness, the noise in newtons and metres), the references are the ideal
loop, and the campaign's rows become the errors against the reference."""

from __future__ import annotations

import math

import pytest

from hybridtable.studies.compensator_sweep import (
    RUN_METRICS,
    SweepSettings,
    sweep_points,
    sweep_result,
    sweep_runs,
)
from hybridtable.studies.paper import table2_params
from hybridtable.sweeps.inputs import loop_params, noise_params
from hybridtable.sweeps.spec import parse_spec


def _expected(run, row, settings):
    """The loop of a run, written from the paper's parameters and the scenario."""
    base = table2_params(row, sample_rate_hz=settings.sample_rate_hz)
    k, m = base.contact_stiffness_n_per_m, base.spacecraft_mass_kg
    zeta = settings.contact_damping_ratio if run["scenario"] == "damped" else 0.0
    c = 2.0 * zeta * math.sqrt(k * m)
    if run["compensator"] == "ideal":
        return base.with_(
            compensator="none",
            sensor_delay_s=0.0,
            table_response_hz=math.inf,
            contact_damping_n_s_per_m=c,
            sample_rate_hz=None,
        )
    deadband = 0.0
    if run["scenario"] == "noise":
        peak_force_n = base.initial_velocity_m_per_s * math.sqrt(k * m)
        deadband = settings.deadband_sigmas * (settings.force_noise_ratio * peak_force_n)
    return base.with_(
        compensator=run["compensator"],
        compensator_stiffness_n_per_m=run["prior_ratio"] * k,
        compensator_damping_n_s_per_m=0.0,
        contact_damping_n_s_per_m=c,
        passivity=run["passivity"],
        force_deadband_n=deadband,
    )


@pytest.mark.parametrize("sample_rate_hz", [None, 1000.0])
def test_every_run_is_the_loop_of_its_point_scenario_and_compensator(sample_rate_hz):
    settings = SweepSettings(sample_rate_hz=sample_rate_hz, seed=3)
    points = sweep_points(quick=True)  # the Table 1 point: v0 = 0.1 m/s
    references, cases = sweep_runs(settings, points)
    assert [(r["scenario"], r["compensator"]) for r in references] == [
        ("mismatch", "ideal"),
        ("damped", "ideal"),
    ]
    # k-free compensators at ratio 1 only; each case with and without the guard.
    n_comp = len(settings.compensators)
    n_free = sum(c in ("none", "SDC", "polynomial") for c in settings.compensators)
    per_guard = n_free * 3 + (n_comp - n_free) * (5 + 2 + 2)
    assert len(cases) == 2 * per_guard
    for run in references + cases:
        params = loop_params(run["inputs"])
        assert params == _expected(run, points[0], settings), run
        noise = noise_params(run["inputs"], seed=1)
        if run["scenario"] == "noise":
            k, m = params.contact_stiffness_n_per_m, params.spacecraft_mass_kg
            # 1e-3 of the undamped peak force v0 sqrt(k m) [N], 1e-4 of v0 / omega [m].
            assert noise.force_std_n == pytest.approx(1e-3 * 0.1 * math.sqrt(k * m), rel=1e-12)
            assert noise.position_std_m == pytest.approx(1e-4 * 0.1 / math.sqrt(k / m), rel=1e-12)
        else:
            assert noise is None
    # Every run of a campaign gives the same inputs: each list is one spec.
    for runs in (references, cases):
        spec = parse_spec(
            {"name": "c", "metrics": list(RUN_METRICS), "points": [r["inputs"] for r in runs]}
        )
        assert spec.n_runs == len(runs)
    assert ("sample_rate_hz" in cases[0]["inputs"]) == (sample_rate_hz is not None)
    assert all("sample_rate_hz" not in r["inputs"] for r in references)


def _row(run, status="ok", message="", **metrics):
    values = dict.fromkeys(RUN_METRICS, math.nan) if status != "ok" else dict(metrics)
    return {"run": run, "status": status, "message": message, **values}


def test_the_rows_become_errors_against_the_reference_of_the_same_contact():
    settings = SweepSettings(
        compensators=("SDMDC",),
        prior_ratios=(1.0,),
        damped_prior_ratios=(1.0,),
        scenarios=("mismatch", "damped"),
    )
    points = sweep_points(quick=True)
    references, cases = sweep_runs(settings, points)
    assert [c["scenario"] for c in cases] == ["mismatch", "mismatch", "damped", "damped"]
    metrics = dict(peak_force_n=100.0, v_in_m_per_s=-0.1, v_out_m_per_s=0.1)
    ref_rows = [
        _row(1, cor=0.8, energy_created=0.0, **metrics),  # any order: matched by run
        _row(0, cor=1.0, energy_created=0.0, **metrics),
    ]
    case_rows = [
        _row(0, cor=1.05, energy_created=0.2, **{**metrics, "peak_force_n": 110.0}),
        _row(1, status="diverged", message="the force grew without bound"),
        _row(2, cor=0.85, energy_created=0.0, **metrics),
        _row(3, cor=0.8, energy_created=0.0, **metrics),
    ]
    result = sweep_result(settings, points, references, cases, ref_rows, case_rows, 3.0)
    first, failed, damped = result.runs[0], result.runs[1], result.runs[2]
    assert first["error"] is None and first["cor_reference"] == 1.0
    assert first["cor_error"] == pytest.approx(0.05)
    assert first["peak_force_error"] == pytest.approx(0.1)
    assert first["energy_drift"] == pytest.approx(1.05**2 - 1.0)
    assert first["energy_created"] == 0.2 and "steps" not in first
    assert failed["error"] == "the force grew without bound" and math.isnan(failed["cor"])
    assert damped["cor_reference"] == 0.8 and damped["cor_error"] == pytest.approx(0.05)
    assert [r["compensator"] for r in result.references] == ["ideal", "ideal"]
    assert result.wall_time_s == 3.0
    with pytest.raises(ValueError, match="1 of 4 runs have no result"):
        sweep_result(settings, points, references, cases, ref_rows, case_rows[:3])
