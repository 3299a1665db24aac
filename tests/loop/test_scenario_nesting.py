"""The loop's parameters nest one config per component
(:mod:`hybridtable.loop.params`): built nested or by the flat names, the same
scenario; each flat name reads its config; a change touches one config; an
error names what the user wrote."""

from __future__ import annotations

import math
import pickle

import pytest

from hybridtable.errors import ParameterError
from hybridtable.loop.params import (
    FIELDS,
    Approach,
    CompensatorConfig,
    HybridLoopParams,
    Plant,
    RigComputer,
)
from hybridtable.systems.contact import ContactParams
from hybridtable.systems.sensor import SensorParams
from hybridtable.systems.spacecraft import SpacecraftParams
from hybridtable.systems.table import TableParams

NESTED = HybridLoopParams(
    plant=Plant(
        SpacecraftParams(mass_kg=2500.0),
        ContactParams(stiffness_n_per_m=1e5, damping_n_s_per_m=30.0),
        TableParams(response_frequency_hz=25.0, damping_ratio=0.7),
    ),
    rig=RigComputer(
        sensor=SensorParams(sensor_delay_s=0.004),
        sample_rate_hz=1000.0,
        compensator=CompensatorConfig(name="SDMDC", lead_time_s=0.003, force_deadband_n=2.0),
    ),
    approach=Approach(initial_velocity_m_per_s=0.05, initial_gap_m=0.002),
)

FLAT = dict(
    spacecraft_mass_kg=2500.0,
    contact_stiffness_n_per_m=1e5,
    contact_damping_n_s_per_m=30.0,
    table_response_hz=25.0,
    table_damping_ratio=0.7,
    sensor_delay_s=0.004,
    sample_rate_hz=1000.0,
    compensator="SDMDC",
    lead_time_s=0.003,
    force_deadband_n=2.0,
    initial_velocity_m_per_s=0.05,
    initial_gap_m=0.002,
)


def test_nested_and_flat_build_the_same_scenario():
    flat = HybridLoopParams(**FLAT)
    assert flat == NESTED and hash(flat) == hash(NESTED)
    for name, value in FLAT.items():
        assert getattr(NESTED, name) == value, name


def test_every_flat_name_reads_its_config():
    for name, path in FIELDS.items():
        config = NESTED
        for key in path:
            config = getattr(config, key)
        assert getattr(NESTED, name) is config or getattr(NESTED, name) == config, name
    assert NESTED.quantities() == {name: getattr(NESTED, name) for name in FIELDS}
    assert list(NESTED.quantities()) == list(FIELDS)


def test_a_change_touches_only_its_config():
    changed = NESTED.with_(sensor_delay_s=0.006)
    assert changed.rig.sensor.sensor_delay_s == 0.006
    assert changed.plant is NESTED.plant and changed.approach is NESTED.approach
    assert changed.rig.compensator is NESTED.rig.compensator
    # A config replaced whole, and a quantity changed in the same call.
    table = TableParams(response_frequency_hz=math.inf, damping_ratio=0.8)
    plant = Plant(NESTED.plant.spacecraft, NESTED.plant.contact, table)
    both = NESTED.with_(plant=plant, contact_damping_n_s_per_m=0.0)
    assert both.plant.table.is_ideal and both.contact_damping_n_s_per_m == 0.0
    assert NESTED.contact_damping_n_s_per_m == 30.0  # frozen: the original is unchanged


def test_the_rig_computers_rule_spans_its_delay_and_rate():
    # 4 ms at 1 kHz is 4 ticks; at 1.5 kHz 6 ticks; at 300 Hz 1.2 ticks (read
    # between two ticks).
    assert NESTED.with_(sample_rate_hz=1500.0).sample_period_s == pytest.approx(1 / 1500)
    assert NESTED.with_(sample_rate_hz=300.0).rig.sensor.sensor_delay_s == 0.004
    # Changing both at once is checked once, on the new pair.
    moved = NESTED.with_(sample_rate_hz=300.0, sensor_delay_s=0.01)
    assert moved.rig.sensor.sensor_delay_s == 0.01


@pytest.mark.parametrize(
    "name, value, words",
    [
        ("spacecraft_mass_kg", -1.0, "^spacecraft_mass_kg must be > 0"),
        ("contact_stiffness_n_per_m", 0.0, "^contact_stiffness_n_per_m must be > 0"),
        ("table_damping_ratio", -0.1, "^table_damping_ratio must be >= 0"),
        ("table_response_hz", float("nan"), "^table_response_hz must be > 0 or inf"),
        ("sensor_delay_s", -0.001, "^sensor_delay_s must be >= 0"),
        ("compensator", "sdmdcx", "^compensator must be one of"),
        ("compensator_stiffness_n_per_m", -5.0, "^compensator_stiffness_n_per_m must be >= 0"),
        ("initial_velocity_m_per_s", 0.0, "^initial_velocity_m_per_s must be > 0"),
    ],
)
def test_an_error_names_the_flat_name_the_user_wrote(name, value, words):
    with pytest.raises(ParameterError, match=words):
        HybridLoopParams(**{**FLAT, name: value})
    with pytest.raises(ParameterError, match=words):
        NESTED.with_(**{name: value})


def test_a_config_built_by_hand_names_its_own_field():
    with pytest.raises(ParameterError, match="^mass_kg must be > 0"):
        SpacecraftParams(mass_kg=0.0)
    with pytest.raises(ParameterError, match="plausible|outside"):
        Plant(SpacecraftParams(1e12), ContactParams(1e5))


def test_wrong_shapes_are_refused_in_one_line():
    with pytest.raises(TypeError, match="unknown sensor_delay_ms"):
        HybridLoopParams(**FLAT, sensor_delay_ms=4.0)
    with pytest.raises(TypeError, match="needs plant= or spacecraft_mass_kg"):
        HybridLoopParams(sensor_delay_s=0.001)
    with pytest.raises(ParameterError, match="plant must be a Plant .*by name"):
        HybridLoopParams(2500.0, 1e5)


def test_a_scenario_crosses_a_process_boundary_unchanged():
    again = pickle.loads(pickle.dumps(NESTED))
    assert again == NESTED and hash(again) == hash(NESTED)
    assert again.sensor_delay_s == 0.004
