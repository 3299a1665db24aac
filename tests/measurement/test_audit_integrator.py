"""The rig computer's integration rule, read from the record by the audit
(measurement.audit): runs of the independent rig zoo stepped by each rule."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.measurement.audit import audit_runs
from hybridtable.measurement.rig import simulate_rig
from hybridtable.measurement.run_reader import read_runs
from tests.generators import rigzoo

RULES = {
    "semi_implicit_euler": "semi_implicit_euler",
    "explicit_euler": "explicit_euler",
    "trapezoid": "trapezoid",
    "rk4": "trapezoid",  # with the force held over the tick, RK4 is the trapezoid rule
}


def _runs(tmp_path, integrator: str, compensator: str, noisy: bool, seed: int = 3):
    rig = rigzoo.draw_rig(np.random.default_rng(seed), integrator=integrator)
    noise = None
    if noisy:
        noise = rigzoo.NoiseSpec(kind="white", ar=(), sigma_f=2.0, sigma_p=2e-6)
    record = rigzoo.simulate_run(
        rig, None, 0.1, compensator, rigzoo.MAX_TICKS, noise=noise, seed=seed, run_id="r1"
    )
    folder = tmp_path / f"{integrator}-{compensator}-{noisy}"
    rigzoo.write_run(folder, "r1", record)
    return read_runs([folder]), rig


@pytest.mark.parametrize("noisy", [False, True], ids=["clean", "noisy"])
@pytest.mark.parametrize("compensator", ["none", "SDC", "SDMDC"])
@pytest.mark.parametrize("integrator", list(RULES))
def test_the_audit_names_the_rule_and_nothing_else(tmp_path, integrator, compensator, noisy):
    runs, rig = _runs(tmp_path, integrator, compensator, noisy)
    audit = audit_runs(runs)
    assert audit.integrator == RULES[integrator]
    (est,) = audit.estimates
    # the time step is the rig's, not the rule's bias
    assert est.time_step_s == pytest.approx(rig.h, rel=1e-6)
    # no mass, lead time or stiffness of the rule's own
    keys = {f.key for f in audit.findings}
    assert keys <= {"integrator"}, audit.findings
    assert ("integrator" in keys) == (RULES[integrator] != "semi_implicit_euler")


@pytest.mark.parametrize("integrator", ["explicit_euler", "trapezoid"])
def test_with_the_audited_rule_the_closed_loop_is_the_record(tmp_path, integrator):
    from hybridtable.measurement.rig import RigPhysics

    runs, _ = _runs(tmp_path, integrator, "SDC", noisy=False)
    audit = audit_runs(runs)
    (run,) = runs
    changes = audit.computer_changes(run.run_id)
    assert changes == {"computer_integrator": integrator}
    stated = simulate_rig(run)
    audited = simulate_rig(run, RigPhysics(computer=changes))
    scale = np.max(np.abs(run.v_des_m_per_s))
    err_stated = np.max(np.abs(stated.v_des_m_per_s - run.v_des_m_per_s)) / scale
    err_audited = np.max(np.abs(audited.v_des_m_per_s - run.v_des_m_per_s)) / scale
    assert err_audited < 1e-4 < err_stated


def test_a_computer_without_mdc_is_not_given_a_stiffness_of_zero():
    from hybridtable.measurement.audit_findings import Audit, ComputerEstimate, Finding

    est = ComputerEstimate(
        *("r1", 1e-3, 1e-12, "semi_implicit_euler", 1.0, 0.0, 0.01, 0.1, 500.0, 1e-3),
        *(0.004, 1e-6, 1e-3, 5.0, 1.0, 1e-9, 0.0, 1e-9, 1e-9, (0.0, 1.0), 100, 0.0, 0),
    )
    audit = Audit([est], [Finding("lead_time_s", 0.005, 0.004, 1e-6, ("r1",), "lead")])
    changes = audit.computer_changes("r1")
    assert changes == {"lead_time_s": 0.004, "compensator": "SDC"}


@pytest.mark.slow
def test_a_saved_model_keeps_the_rule_and_reproduces_the_cor(tmp_path):
    from hybridtable.cli import main

    runs, _ = _runs(tmp_path, "explicit_euler", "SDC", noisy=True)
    model = tmp_path / "model.json"
    folder = str(runs[0].csv_path.parent)
    assert (
        main(["diagnose", folder, "--workers", "1", "--no-progress", "--save-model", str(model)])
        == 0
    )
    text = model.read_text()
    assert '"computer_integrator": "explicit_euler"' in text
    out = tmp_path / "sim.json"
    assert main(["simulate", "--model", str(model), "--json", str(out)]) == 0
    bad = tmp_path / "bad.json"
    bad.write_text(text.replace('"explicit_euler"', '"leapfrog"'))
    assert main(["simulate", "--model", str(bad)]) == 2
