"""6-DoF campaigns: a spec naming a 6-DoF scenario varies its quantities by flat
name, runs the docking loop and writes its metrics to the same Parquet file."""

from __future__ import annotations

import math
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from hybridtable.errors import ParameterError, SpecError
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.scenario import load_scenario
from hybridtable.sweeps.docking import COMPONENTS, docking_inputs, docking_params
from hybridtable.sweeps.runner import row_problem, run_one
from hybridtable.sweeps.spec import parse_spec
from hybridtable.sweeps.store import read_results, write_results

ROOT = Path(__file__).resolve().parents[2]
OFFSET = ROOT / "examples" / "six_dof" / "offset.toml"


@pytest.fixture(scope="module")
def base() -> DockingLoopParams:
    return load_scenario(OFFSET)


def _spec(text: str):
    import tomllib

    return parse_spec(tomllib.loads(f'scenario = "{OFFSET}"\n' + text), "spec.toml")


def test_every_single_quantity_of_the_scenario_is_an_input(base):
    inputs = docking_inputs()
    for name in DockingLoopParams.FIELDS:
        if name in ("spacecraft", "contact", "stewart", "compensator_stiffness_matrix", "seed"):
            assert name not in inputs
        elif name in COMPONENTS:
            assert name not in inputs
            # a component is the vector's name with its axis before the unit
            axes = [
                n for n in inputs for a in COMPONENTS[name] if n.replace(f"_{a}_", "_", 1) == name
            ]
            assert len(axes) == len(COMPONENTS[name]), (name, axes)
        else:
            assert name in inputs, name
    assert inputs["misalignment_pitch_rad"].unit == "rad"
    assert inputs["contact_stiffness_n_per_m"].unit == "N/m"
    assert inputs["compensator"].kind == "text"


@pytest.mark.parametrize(
    ("name", "value", "read"),
    [
        ("initial_velocity_m_per_s", 0.17, lambda p: p.approach.initial_velocity_m_per_s),
        ("friction_coefficient", 0.6, lambda p: p.contact.friction_coefficient),
        ("pad_count", 6, lambda p: p.contact.pad_count),
        ("lateral_offset_y_m", -0.05, lambda p: p.spacecraft.lateral_offset_m[1]),
        ("misalignment_roll_rad", 0.1, lambda p: p.approach.misalignment_rad[0]),
        ("inertia_z_kg_m2", 2000.0, lambda p: p.spacecraft.inertia[2, 2]),
        ("angular_rate_y_rad_per_s", 0.02, lambda p: p.approach.angular_rate_rad_per_s[1]),
        ("sensor_delay_s", 0.012, lambda p: p.rig.sensor.sensor_delay_s),
        ("compensator", "SDC", lambda p: p.rig.compensator.name),
        ("lateral_miss_x_m", 0.12, lambda p: p.approach.lateral_miss_m[0]),
        ("geometry", "cone", lambda p: p.contact.geometry),
        ("cone_half_angle_rad", 0.4, lambda p: p.contact.cone_half_angle_rad),
    ],
)
def test_an_input_sets_its_quantity_and_leaves_the_rest(base, name, value, read):
    p = docking_params(base, {name: value}, seed=3)
    assert read(p) == pytest.approx(value) if not isinstance(value, str) else read(p) == value
    # the other component of a vector keeps the scenario's value
    if name == "lateral_offset_y_m":
        assert p.spacecraft.lateral_offset_m[0] == base.spacecraft.lateral_offset_m[0]
    if name == "misalignment_roll_rad":
        assert p.approach.misalignment_rad[1] == base.approach.misalignment_rad[1]
    assert p.seed == 3


def test_the_contact_frequency_sets_the_mass_and_a_scenario_holding_it_keeps_it(base):
    k = 4.0e5
    p = docking_params(base, {"contact_frequency_hz": 2.0, "contact_stiffness_n_per_m": k}, 0)
    assert p.spacecraft.mass_kg == pytest.approx(k / (2 * math.pi * 2.0) ** 2, rel=1e-12)
    # offset.toml gives contact_frequency_hz = 1: a stiffer contact, a heavier body
    held = docking_params(base, {"contact_stiffness_n_per_m": k}, 0, holds=True)
    assert held.contact_frequency_hz == pytest.approx(1.0, rel=1e-12)
    kept = docking_params(base, {"contact_stiffness_n_per_m": k}, 0, holds=False)
    assert kept.spacecraft.mass_kg == base.spacecraft.mass_kg
    ratio = docking_params(base, {"compensator_stiffness_ratio": 0.5}, 0)
    assert ratio.compensator_stiffness_n_per_m == pytest.approx(
        0.5 * base.contact.contact_stiffness_n_per_m
    )


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("[base]\ntable_backend = 'stewart'", "unknown parameter 'table_backend'"),
        ('metrics = ["cor"]', "unknown metric 'cor'"),
        ('engine = "fast"', 'engine = "fast"'),
        ('model = "m.json"', "no model"),
        ("[grid]\nmisalignment_roll_rad = [0.0, 0.9]", "grid.misalignment_roll_rad[1]"),
        ("[base]\npad_count = 2", "base.pad_count: pad_count must be in [3, 64]"),
        ("[base]\ncompensator = 'polynomial'", "compensator must be one of"),
        ("[grid]\ngeometry = ['cone', 'funnel']", "grid.geometry[1]"),
        ("[base]\ngeometry = 'cone'\nprobe_radius_m = 0.2", "base.probe_radius_m"),
        ("[grid]\nprobe_radius_m = [0.04, 0.05]", "probe_radius_m (in grid) belongs to the cone"),
        ("[base]\ngeometry = 'cone'\n[grid]\npad_count = [4, 8]", "pad_count (in grid) belongs"),
        (
            "[base]\nspacecraft_mass_kg = 1000.0\n[grid]\ncontact_frequency_hz = [1.0]",
            "set the same quantity",
        ),
    ],
)
def test_a_wrong_6dof_spec_is_one_line_naming_the_key(text, words):
    with pytest.raises(SpecError) as err:
        _spec(text)
    assert words in str(err.value)
    assert "\n" not in str(err.value)


def test_both_devices_inputs_with_both_geometries():
    spec = _spec(
        "[grid]\ngeometry = ['plate', 'cone']\npad_count = [4, 8]\nprobe_radius_m = [0.05]"
    )
    assert spec.n_runs == 4


def test_a_missing_scenario_names_the_file(tmp_path):
    with pytest.raises(SpecError, match="nowhere.toml"):
        parse_spec({"scenario": "nowhere.toml"}, "spec.toml", tmp_path)


def test_a_1d_spec_says_nothing_of_scenarios():
    spec = parse_spec({"name": "x"})
    assert spec.loop == "1d" and "scenario" not in spec.to_json()


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """Two draws of a delayed offset docking, each with no compensation,
    SDMDC believing twice the stiffness, and sdmdc-online from that belief."""
    spec = _spec(
        """
name = "envelope"
seed = 5
compensators = ["none", "SDMDC", "sdmdc-online"]
metrics = ["cor_normal", "energy_ratio", "peak_force_n", "lateral_drift_m", "captured",
           "identified_stiffness_n_per_m", "energy_excess"]
[base]
compensator_stiffness_ratio = 2.0
[monte_carlo]
samples = 2
[monte_carlo.draw]
initial_velocity_m_per_s = {distribution = "uniform", low = 0.08, high = 0.12}
lateral_offset_x_m = {distribution = "uniform", low = -0.05, high = 0.05}
"""
    )
    rows = [run_one(spec, i) for i in range(spec.n_runs)]
    return spec, rows, tmp_path_factory.mktemp("envelope")


def test_a_6dof_campaign_measures_the_physics(campaign):
    spec, rows, _ = campaign
    assert [r["status"] for r in rows] == ["ok"] * 6, [r["message"] for r in rows]
    assert {r["engine"] for r in rows} == {"diagram"}
    by = {(r["sample"], r["compensator"]): r for r in rows}
    k = 1.0e5
    for s in range(2):
        none, sdmdc, online = (by[s, c] for c in ("none", "SDMDC", "sdmdc-online"))
        # the 5 ms delay pumps energy in; SDMDC believing 2 k over-compensates;
        # the online identifier finds k and lands near an energy-neutral bounce
        assert none["energy_ratio"] > 1.1
        assert sdmdc["energy_ratio"] < 0.97
        assert abs(online["energy_ratio"] - 1.0) < 0.01
        assert online["identified_stiffness_n_per_m"] == pytest.approx(k, rel=0.05)
        assert math.isnan(sdmdc["identified_stiffness_n_per_m"])
        assert not online["captured"]
        # against the same docking on the ideal rig (no delay, ideal table)
        assert none["energy_excess"] > 0.1 and abs(online["energy_excess"]) < 0.01
        assert sdmdc["energy_excess"] < -0.03
        # one draw: every compensator meets the same approach
        assert none["initial_velocity_m_per_s"] == online["initial_velocity_m_per_s"]


def test_the_energy_excess_is_over_the_same_docking_on_the_ideal_rig(campaign, base):
    from hybridtable.six_dof.simulation import simulate6

    spec, rows, _ = campaign
    row = rows[1]  # SDMDC, sample 0
    params = docking_params(base, spec.run_inputs(1).values, spec.run_inputs(1).seed)
    ideal = simulate6(params.ideal_rig()).metrics.energy_ratio
    assert row["energy_excess"] == row["energy_ratio"] - ideal


def test_a_6dof_campaign_writes_and_resumes_its_parquet(campaign):
    spec, rows, folder = campaign
    path = folder / "envelope.parquet"
    write_results(path, spec, rows, replace=True)
    table = read_results(path, spec)
    assert table.column("captured").type == "bool"
    assert table.column("lateral_offset_x_m").type == "double"
    for row in table.to_pylist():
        assert row_problem(spec, row) is None, row
    bad = dict(table.to_pylist()[0], energy_ratio=math.nan)
    assert "energy_ratio" in row_problem(spec, bad)


def test_a_record_ending_at_rest_in_contact_is_a_capture_and_one_cut_moving_is_not(base):
    """``captured``: the devices touch at the record's end with the port at
    rest along the axis (the deepest press of a contact), not merely touching."""
    from hybridtable.six_dof.simulation import simulate6

    p = base.with_(compensator="none")
    full = simulate6(p)
    assert not full.metrics.captured
    assert np.isfinite(full.metrics.lateral_drift_m) and full.metrics.lateral_drift_m >= 0.0
    v = full.port_velocity_m_per_s[:, 2]
    touching = np.flatnonzero(np.linalg.norm(full.log["contact_wrench"][:, 3:], axis=1) > 0)
    deepest = touching[np.argmin(np.abs(v[touching]))]
    at_rest = simulate6(p.with_(duration_s=float(full.time_s[deepest])))
    assert at_rest.metrics.captured
    cut = simulate6(p.with_(duration_s=float(full.time_s[deepest]) - 0.1))
    assert not cut.metrics.captured  # touching, but moving at ~0.5 v0


def test_the_params_dict_of_simulate6_is_unchanged_by_the_flat_names(base):
    d = base.to_dict()
    for f in fields(base.contact):
        assert f.name not in d  # inside "contact"
    assert "initial_velocity_m_per_s" not in d and "approach" in d


def test_a_value_out_of_a_configs_range_is_refused_by_that_config(base):
    with pytest.raises(ParameterError, match="friction_coefficient"):
        docking_params(base, {"friction_coefficient": -1.0}, 0)
