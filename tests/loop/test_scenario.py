"""The 1-D scenario file: nested sections shared with the 6-DoF loop, one line
naming the file, section and key for anything wrong, and the command line's
options over it."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import pytest

from hybridtable.errors import SpecError
from hybridtable.loop.scenario import load_loop_scenario, parse_loop_scenario
from hybridtable.six_dof.scenario import parse_scenario
from hybridtable.studies.paper import paper_params, table1_params

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "table1_sdmdc.toml"

SHARED = """
[spacecraft]
contact_frequency_hz = 0.5
[contact]
contact_stiffness_n_per_m = 2e5
[approach]
initial_velocity_m_per_s = 0.2
initial_gap_m = 0.002
[rig]
sample_rate_hz = 1000.0
sensor_delay_s = 0.004
[table]
response_hz = "inf"
[compensator]
name = "SDC"
lead_time_s = 0.003
force_deadband_n = 1.5
"""


def test_the_shipped_scenario_is_the_table1_point():
    assert load_loop_scenario(EXAMPLE) == table1_params("SDMDC")


def test_the_1d_and_6dof_loops_read_the_shared_sections_alike():
    raw = tomllib.loads(SHARED)
    one = parse_loop_scenario(raw)
    six = parse_scenario(raw)
    k = 2e5
    assert one.contact_stiffness_n_per_m == six.contact.contact_stiffness_n_per_m == k
    mass = k / (2.0 * math.pi * 0.5) ** 2
    assert one.spacecraft_mass_kg == six.spacecraft.mass_kg == mass
    assert one.initial_velocity_m_per_s == six.approach.initial_velocity_m_per_s == 0.2
    assert one.initial_gap_m == six.approach.initial_gap_m == 0.002
    assert one.sample_rate_hz == six.sample_rate_hz == 1000.0
    assert one.sensor_delay_s == six.sensor_delay_s == 0.004
    assert one.table_response_hz == six.table_response_hz == math.inf
    assert one.compensator == six.compensator == "SDC"
    assert one.lead_time_s == six.lead_time_s == 0.003
    assert one.force_deadband_n == six.force_deadband_n == 1.5


@pytest.mark.parametrize(
    "text, words",
    [
        ("[rig]\nfoo = 1", r"\[rig\] unknown key 'foo'"),
        ("[rig]\nsensor_delay_s = 2.0", r"\[rig\] sensor_delay_s: .*plausible range"),
        ("[table]\ndamping_ratio = 'x'", r"\[table\] damping_ratio must be a number"),
        ("[compensator]\nname = 'nonesuch'", r"\[compensator\] name: .*SDMDC"),
        ("[compensator]\nstiffness_n_per_m = -1.0", r"\[compensator\] stiffness_n_per_m:"),
        ("[compensator]\npassivity = 1", r"\[compensator\] passivity must be true or false"),
        ("[compensator]\ncontact_gate = 'nope'", r"\[compensator\] contact_gate: .*table_position"),
        ("[spacecraft]\nmass_kg = 10.0\ncontact_frequency_hz = 1.0", "exactly one"),
        ("[spacecraft]\ncontact_frequency_hz = 1e-9", r"\[spacecraft\]: spacecraft_mass_kg"),
        ("nonsense = 3", "unknown section or key 'nonsense'"),
    ],
)
def test_a_wrong_scenario_is_one_line_naming_the_file_and_key(text, words):
    head = "" if "[contact]" in text else "[contact]\ncontact_stiffness_n_per_m = 1e5\n"
    if "[spacecraft]" not in text:
        head += "[spacecraft]\nmass_kg = 2533.0\n"
    with pytest.raises(SpecError, match=words) as err:
        # A top-level key goes before the sections (after one, it would be the section's).
        whole = text + "\n" + head if not text.startswith("[") else head + text
        parse_loop_scenario(tomllib.loads(whole), "rig.toml")
    assert str(err.value).startswith("rig.toml: ") and "\n" not in str(err.value)


def test_a_scenario_needs_the_contact_stiffness():
    with pytest.raises(SpecError, match="contact_stiffness_n_per_m is required"):
        parse_loop_scenario(tomllib.loads("[spacecraft]\nmass_kg = 10.0"))


def test_simulate_takes_a_scenario_and_the_options_given_over_it(tmp_path, capsys):
    from hybridtable.cli import main
    from hybridtable.loop.simulation import simulate

    out = tmp_path / "run.json"
    argv = ["simulate", "--scenario", str(EXAMPLE), "--sensor-delay-s", "0.003"]
    assert main([*argv, "--contact-frequency-hz", "0.8", "--json", str(out)]) == 0
    expected = simulate(
        paper_params(compensator="SDMDC", sensor_delay_s=0.003, contact_frequency_hz=0.8)
    )
    assert json.loads(out.read_text())["cor"] == expected.metrics.cor
    assert main(["simulate", "--scenario", str(EXAMPLE), "--record", str(tmp_path / "r")]) == 2
    assert "--scenario sets one simulation" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[rig]\nsample_rate_hz = 'fast'\n")
    assert main(["simulate", "--scenario", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[rig] sample_rate_hz must be a number" in err[0]
