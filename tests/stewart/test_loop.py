"""The hybrid loop closed around the Stewart platform back-end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hybridtable.cli import main
from hybridtable.errors import ParameterError, WorkspaceError
from hybridtable.loop.simulation import run_loop, simulate
from hybridtable.stewart.backend import build_stewart_loop
from hybridtable.stewart.identify import identify_chirp, tune_leg_gains, tune_table
from hybridtable.stewart.params import StewartParams
from hybridtable.studies.paper import paper_params, table1_params

TARGET_HZ, TARGET_ZETA = 25.0, 0.8


@pytest.fixture(scope="module")
def tuned():
    """The default platform tuned to the paper's 25 Hz, zeta 0.8 table."""
    return tune_table(StewartParams(), TARGET_HZ, TARGET_ZETA)


def test_tuned_table_has_the_target_response_by_step_and_chirp(tuned):
    params, step = tuned
    assert step.response_frequency_hz == pytest.approx(TARGET_HZ, rel=2e-3)
    assert step.damping_ratio == pytest.approx(TARGET_ZETA, abs=2e-3)
    assert step.static_gain == pytest.approx(1.0, abs=2e-3)
    assert step.rms_error_m < 0.01 * 1e-3  # < 1 % of the 1 mm step
    chirp = identify_chirp(params, initial_guess=(TARGET_HZ, TARGET_ZETA))
    assert chirp.response_frequency_hz == pytest.approx(TARGET_HZ, rel=0.03)
    assert chirp.damping_ratio == pytest.approx(TARGET_ZETA, abs=0.05)


def test_leg_gains_alone_can_be_tuned_to_the_response():
    params, step = tune_leg_gains(StewartParams(), TARGET_HZ, TARGET_ZETA)
    assert params.reference_response_hz is None
    assert step.response_frequency_hz == pytest.approx(TARGET_HZ, rel=2e-3)
    assert step.damping_ratio == pytest.approx(TARGET_ZETA, abs=2e-3)
    # Compliant legs: the heave stiffness is the response's, ~M w^2, about
    # 2e6 N/m for the default platform, far below the stiff servo's.
    kp, _ = params.servo_gains()
    assert kp < 0.2 * StewartParams().servo_gains()[0]


def test_unreachable_response_is_a_clear_error():
    # 100 Hz at a 1 ms step: the explicit servo would need w h ~ 0.6 or more.
    with pytest.raises(ParameterError, match="unstable"):
        tune_leg_gains(StewartParams(), 100.0, TARGET_ZETA)
    with pytest.raises(ParameterError, match="Nyquist"):
        tune_table(StewartParams(), 100.0, TARGET_ZETA)
    with pytest.raises(ParameterError, match="finite"):
        tune_table(StewartParams(), float("inf"), TARGET_ZETA)


def test_backend_ports_match_the_loop_contract(tuned):
    loop = build_stewart_loop(table1_params("none", sample_rate_hz=1000.0), tuned[0])
    assert loop.table.GetInputPort("commanded_state").size() == 2
    assert loop.table.GetOutputPort("motion").size() == 3
    assert loop.contact.GetInputPort("motion").size() == 3
    assert loop.contact.GetOutputPort("force").size() == 1
    assert loop.contact.GetOutputPort("force_rate").size() == 1


@pytest.mark.parametrize("compensator", ["none", "SDMDC"])
def test_loop_cor_matches_the_1d_loop_with_the_identified_table(tuned, compensator):
    params, step = tuned
    loop_params = table1_params(compensator, sample_rate_hz=1000.0)
    result = run_loop(build_stewart_loop(loop_params, params))
    one_d = simulate(
        loop_params.with_(
            table_response_hz=step.response_frequency_hz, table_damping_ratio=step.damping_ratio
        )
    )
    assert result.metrics.cor == pytest.approx(one_d.metrics.cor, abs=0.01)
    # Force = k p in contact, at the same tick (no hidden one-step shift).
    in_contact = result.f_act_n > 50.0
    assert result.f_act_n[in_contact] == pytest.approx(1e5 * result.p_act_m[in_contact], rel=1e-6)
    # Apart, the sensor reads an exact zero (no round-off opening the
    # compensator's contact gate).
    assert np.all(result.f_act_n[result.p_act_m < -1e-4] == 0.0)
    # Acceptance (paper's Table 1): delay pumps energy; SDMDC removes it.
    if compensator == "none":
        assert result.metrics.cor > 1.05
    else:
        assert result.metrics.cor == pytest.approx(1.0, abs=0.01)


def test_command_leaving_the_workspace_is_a_clear_error(tuned):
    # 1 m/s into a 0.5 Hz contact would penetrate ~0.32 m: beyond the stroke.
    loop_params = paper_params(
        "none", sample_rate_hz=1000.0, initial_velocity_m_per_s=1.0, contact_frequency_hz=0.5
    )
    with pytest.raises(WorkspaceError, match="leaves the docking-axis workspace"):
        run_loop(build_stewart_loop(loop_params, tuned[0]))


def test_cli_simulate_stewart_reports_the_identified_table(tmp_path, capsys):
    out = tmp_path / "run.json"
    html = tmp_path / "run.html"
    args = ["simulate", "--table", "stewart", "--compensator", "SDMDC"]
    assert main([*args, "--json", str(out), "--html", str(html)]) == 0
    data = json.loads(out.read_text())
    assert data["table"] == "stewart"
    assert data["sample_rate_hz"] == 1000.0
    step = data["identified_table"]["step"]
    assert step["response_frequency_hz"] == pytest.approx(TARGET_HZ, rel=2e-3)
    assert data["cor"] == pytest.approx(data["second_order_cor"], abs=0.01)
    assert html.read_text().lstrip().lower().startswith("<!doctype html")
    # Never overwrite a user's file.
    assert main([*args, "--html", str(html)]) == 2
    assert main(["simulate", "--html", str(tmp_path / "x.html")]) == 2
    assert "needs --table stewart" in capsys.readouterr().err
