"""Every compensator on a modelled rig (``hybridtable.studies.model_compensators``):
the reference is the model's contact on an ideal rig, and the ranking puts the
delay-compensating SDMDC ahead of no compensation."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from hybridtable.effects.model_file import FittedEffect, RigModel
from hybridtable.effects.spec import ModelSpec
from hybridtable.measurement.recorder import record_run, write_run
from hybridtable.measurement.run_format import RunInfo
from hybridtable.measurement.run_reader import read_runs
from tests.examples import example_info

#: The rig of ``examples/nominal``: k = 6e4 N/m, m = 675.475 kg (1.5 Hz),
#: 4 ms delay, 1 kHz computer, table 30 Hz / 0.7; SDMDC.
_EXAMPLE = example_info(compensator="SDMDC").to_dict()
RIG = {
    k: v for k, v in _EXAMPLE.items() if k not in ("format", "run_id", "initial_velocity_m_per_s")
}
DAMPING = 300.0


def damped_oscillator_cor(damping: float = DAMPING) -> float:
    """CoR of the rig's contact with viscous damping ``c``:
    ``exp(-pi zeta / sqrt(1 - zeta^2))``, ``zeta = c / (2 sqrt(k m))``."""
    zeta = damping / (2.0 * math.sqrt(RIG["contact_stiffness_n_per_m"] * RIG["spacecraft_mass_kg"]))
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))


def write_damped_model(
    folder: Path, velocities=(0.08,), effects=None, computer=None, name="model.json"
) -> Path:
    """Record runs of the rig with hidden contact damping and write a model
    file of them (``effects``: default contact damping of 300 N s/m)."""
    folder.mkdir(parents=True, exist_ok=True)
    hidden = ModelSpec().with_contact(damping_n_s_per_m=DAMPING).physics()
    paths = []
    for i, v in enumerate(velocities, 1):
        info = RunInfo(run_id=f"run{i}", initial_velocity_m_per_s=v, **RIG)
        run, _ = record_run(info, hidden)
        write_run(run, folder, f"run{i}", force=True)
        paths.append(folder / f"run{i}.csv")
    runs = read_runs([str(p) for p in paths])
    if effects is None:
        effects = [
            FittedEffect(
                "contact_damping",
                {"damping_n_s_per_m": DAMPING},
                {"damping_n_s_per_m": 5.0},
                ("damping_n_s_per_m",),
            )
        ]
    model = RigModel.from_runs(runs, effects, computer=computer, source="test")
    path = folder / name
    path.write_text(json.dumps(model.to_json()))
    return path


@pytest.fixture(scope="module")
def damped_model(tmp_path_factory):
    from hybridtable.effects.model_reader import load_model

    return load_model(write_damped_model(tmp_path_factory.mktemp("rig")))


def test_the_reference_is_the_damped_contact_and_sdmdc_beats_none(damped_model):
    from hybridtable.studies.model_compensators import run_model_compensators

    result = run_model_compensators(damped_model, ("none", "SDMDC"), passivity=(False,))
    (point,) = result.points
    # The ideal rig with the model's contact: the damped oscillator's CoR, not 1
    # (the unilateral contact separates a little early, as k p + c v reaches 0).
    assert point["cor_reference"] == pytest.approx(damped_oscillator_cor(), abs=0.01)
    assert point["cor_reference"] < 0.95
    ranking = {e["key"]: e for e in result.ranking()}
    assert [e["key"] for e in result.ranking()] == ["SDMDC", "none"]
    assert abs(ranking["SDMDC"]["cor_error"]) < abs(ranking["none"]["cor_error"])
    assert abs(ranking["SDMDC"]["cor_error"]) < 0.02
    # No compensation gains energy over the 4 ms delay and the table's lag.
    assert ranking["none"]["cor"] > 1.05 and ranking["none"]["max_energy_created"] > 0.1
    for r in result.runs:
        assert r["error"] is None and r["cor_reference"] == point["cor_reference"]


def test_the_points_are_the_runs_approach_velocities(tmp_path):
    from hybridtable.effects.model_reader import load_model
    from hybridtable.studies.model_compensators import rig_points, run_model_compensators

    model = load_model(write_damped_model(tmp_path, velocities=(0.1, 0.05)))
    assert [i.initial_velocity_m_per_s for i in rig_points(model)] == [0.05, 0.1]
    result = run_model_compensators(model, ("SDMDC",), passivity=(False, True))
    assert len(result.runs) == 4 and len(result.references) == 2
    (plain, guarded) = sorted(result.ranking(), key=lambda e: e["passivity"])
    assert guarded["key"] == "SDMDC +passivity"
    worst = max(abs(r["cor_error"]) for r in result.runs if not r["passivity"])
    assert plain["max_abs_cor_error"] == pytest.approx(worst)


def test_the_models_rig_computer_and_mass_reach_every_compensator(tmp_path):
    from hybridtable.effects.model_reader import load_model
    from hybridtable.measurement.rig import rig_params
    from hybridtable.studies.model_compensators import model_loop_params, rig_points

    effects = [FittedEffect("mass_error", {"mass_ratio": 1.02})]
    computer = {"run1": {"force_deadband_n": 3.0, "compensator": "MDC"}}
    model = load_model(write_damped_model(tmp_path, effects=effects, computer=computer))
    base = rig_params(rig_points(model)[0])
    for name in ("SDMDC", "smith", "polynomial"):
        q = model_loop_params(model, base.with_(compensator=name))
        # The loop's compensator stays; the audit's dead band and the mass ratio act.
        assert q.compensator == name and q.force_deadband_n == 3.0
        assert q.spacecraft_mass_kg == pytest.approx(1.02 * RIG["spacecraft_mass_kg"])
        assert q.compensator_stiffness_n_per_m == RIG["contact_stiffness_n_per_m"]
    ref = model_loop_params(model, base, rig_computer=False)
    assert ref.spacecraft_mass_kg == RIG["spacecraft_mass_kg"]


def test_the_linear_view_keeps_an_extra_delay_between_ticks(damped_model, tmp_path):
    from hybridtable.effects.model_reader import load_model
    from hybridtable.measurement.rig import rig_params
    from hybridtable.studies.model_compensators import model_transform

    base = rig_params(damped_model.nominal)
    q = model_transform(damped_model)(base)
    assert q.contact_damping_n_s_per_m == DAMPING and q.sensor_delay_s == base.sensor_delay_s
    assert q.compensator_damping_n_s_per_m == 0.0  # the compensator's beliefs stay nominal
    effects = [FittedEffect("extra_delay", {"extra_delay_s": 0.0013})]
    delayed = load_model(write_damped_model(tmp_path, effects=effects))
    q = model_transform(delayed)(base.with_(sensor_delay_s=0.002))
    # 3.3 ms at 1 kHz: the sampled model reads the two neighbouring samples mixed,
    # as the rig computer does (the delay is no longer rounded to 3 ticks).
    assert q.sensor_delay_s == pytest.approx(0.0033) and q.sample_rate_hz == 1000.0
    assert q.lead_time_s == base.lead_time_s
