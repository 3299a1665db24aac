"""A run's inputs -> the loop's parameters: the derived inputs' physics and the
paper's points bit for bit.

Written from the docstrings of :mod:`hybridtable.sweeps.inputs`,
:mod:`hybridtable.sweeps.spec` and :class:`~hybridtable.loop.params.HybridLoopParams`
only: ``m = k / (2 pi f)^2``, ``c = 2 zeta sqrt(k m)``, the believed stiffness
``ratio * k``, the Table 1 defaults, and "a spec of the paper's points gives the
paper's runs bit for bit" (dataclass equality with
:func:`~hybridtable.studies.paper.table1_params` and
:func:`~hybridtable.studies.paper.paper_params`).
"""

from __future__ import annotations

import math

import pytest

from hybridtable.errors import ParameterError
from hybridtable.loop.params import HybridLoopParams
from hybridtable.studies.paper import load_tables, paper_params, table1_params
from hybridtable.sweeps.inputs import DEFAULTS, check_value, loop_params, noise_params
from hybridtable.sweeps.spec import parse_spec

__all__: list[str] = []

PAPER = ("none", "SDC", "MDC", "SDMDC")


@pytest.mark.parametrize("frequency_hz", [0.5, 1.0, 3.0, 25.0])
@pytest.mark.parametrize("stiffness_n_per_m", [2e4, 1e5, 5e6])
def test_contact_frequency_sets_the_mass(frequency_hz, stiffness_n_per_m):
    params = loop_params(
        {"contact_frequency_hz": frequency_hz, "contact_stiffness_n_per_m": stiffness_n_per_m}
    )
    mass_kg = stiffness_n_per_m / (2 * math.pi * frequency_hz) ** 2
    assert params.spacecraft_mass_kg == pytest.approx(mass_kg, rel=1e-12)
    assert params.contact_stiffness_n_per_m == stiffness_n_per_m
    # the contact rings at the frequency asked for
    assert params.contact_frequency_hz == pytest.approx(frequency_hz, rel=1e-12)


def test_an_explicit_mass_is_kept():
    params = loop_params({"spacecraft_mass_kg": 1234.5, "contact_stiffness_n_per_m": 2e5})
    assert params.spacecraft_mass_kg == 1234.5
    expected_hz = math.sqrt(2e5 / 1234.5) / (2 * math.pi)
    assert params.contact_frequency_hz == pytest.approx(expected_hz, rel=1e-12)


@pytest.mark.parametrize("zeta", [0.0, 0.02, 0.3, 1.0])
@pytest.mark.parametrize(
    "given",
    [
        {"contact_frequency_hz": 2.0, "contact_stiffness_n_per_m": 3e5},
        {"spacecraft_mass_kg": 800.0, "contact_stiffness_n_per_m": 5e4},
    ],
)
def test_contact_damping_ratio_sets_the_damping(zeta, given):
    params = loop_params(given | {"contact_damping_ratio": zeta})
    k, m = params.contact_stiffness_n_per_m, params.spacecraft_mass_kg
    assert params.contact_damping_n_s_per_m == pytest.approx(
        2 * zeta * math.sqrt(k * m), rel=1e-12, abs=0.0
    )
    # the same as the loop's own definition
    undamped = loop_params(given)
    assert params == undamped.with_contact_damping_ratio(zeta)


@pytest.mark.parametrize("ratio", [0.5, 1.0, 1.3])
def test_compensator_stiffness_ratio_scales_the_believed_stiffness(ratio):
    params = loop_params(
        {
            "compensator": "MDC",
            "contact_stiffness_n_per_m": 1e5,
            "compensator_stiffness_ratio": ratio,
        }
    )
    assert params.contact_stiffness_n_per_m == 1e5  # the truth is unchanged
    assert params.compensator_stiffness_n_per_m == pytest.approx(ratio * 1e5, rel=1e-12)


def test_without_a_ratio_the_compensator_believes_the_truth():
    params = loop_params({"compensator": "MDC"})
    assert params.compensator_stiffness_n_per_m in (None, params.contact_stiffness_n_per_m)


def test_defaults_are_the_table_1_point():
    table1 = load_tables()["table1_simulation"]["parameters"]
    for name, value in DEFAULTS.items():
        assert table1[name] == value, name
    for compensator in PAPER:
        assert loop_params({"compensator": compensator}) == table1_params(compensator)


def table1_spec(**more):
    table1 = load_tables()["table1_simulation"]["parameters"]
    raw = {"name": "table1", "seed": 3, "base": dict(table1), "compensators": list(PAPER)}
    raw.update(more)
    return parse_spec(raw, source="table1.toml")


def test_a_spec_of_table_1_gives_table1_params():
    spec = table1_spec()
    assert spec.n_runs == len(PAPER)
    for i in range(spec.n_runs):
        values = spec.run_inputs(i).values
        params = loop_params(values)
        assert isinstance(params, HybridLoopParams)
        assert params == table1_params(values["compensator"])


def test_a_spec_of_nothing_but_compensators_gives_table1_params():
    spec = parse_spec({"name": "defaults", "compensators": list(PAPER)}, source="defaults.toml")
    for i in range(spec.n_runs):
        values = spec.run_inputs(i).values
        assert loop_params(values) == table1_params(values["compensator"])


@pytest.mark.parametrize(
    "changes",
    [
        {"sensor_delay_s": 0.003},
        {"table_response_hz": 100.0, "table_damping_ratio": 0.5},
        {"contact_frequency_hz": 3.0, "contact_stiffness_n_per_m": 3e5},
        {"initial_velocity_m_per_s": 0.3},
    ],
)
@pytest.mark.parametrize("compensator", PAPER)
def test_paper_style_points_match_paper_params(changes, compensator):
    assert loop_params(changes | {"compensator": compensator}) == paper_params(
        compensator=compensator, **changes
    )


def test_a_grid_of_paper_points_gives_paper_params():
    spec = parse_spec(
        {
            "name": "table2-like",
            "grid": {"sensor_delay_s": [0.001, 0.003, 0.005], "table_response_hz": [25.0, 50.0]},
            "compensators": ["SDMDC"],
        },
        source="grid.toml",
    )
    assert spec.n_runs == 6
    for i in range(spec.n_runs):
        v = spec.run_inputs(i).values
        assert loop_params(v) == paper_params(
            compensator="SDMDC",
            sensor_delay_s=v["sensor_delay_s"],
            table_response_hz=v["table_response_hz"],
        )


def test_noise_inputs_do_not_change_the_loop():
    quiet = loop_params({"compensator": "SDMDC"})
    noisy = loop_params({"compensator": "SDMDC", "force_noise_n": 2.0, "position_noise_m": 1e-5})
    assert noisy == quiet


def test_noise_params():
    assert noise_params({}, seed=5) is None
    assert noise_params({"force_noise_n": 0.0, "position_noise_m": 0.0}, seed=5) is None
    noise = noise_params({"force_noise_n": 2.0}, seed=5)
    assert noise.force_std_n == 2.0
    assert noise.position_std_m == 0.0
    assert noise.seed == 5
    assert noise_params({"force_noise_n": 2.0}, seed=6).seed == 6
    both = noise_params({"force_noise_n": 2.0, "position_noise_m": 1e-5}, seed=5)
    assert (both.force_std_n, both.position_std_m) == (2.0, 1e-5)


def test_a_loop_that_cannot_be_is_refused_naming_the_field():
    """A rule of a sampled computer on a continuous one; a delay between ticks is
    a loop (read between two samples)."""
    with pytest.raises(ParameterError, match="computer_integrator"):
        loop_params({"computer_integrator": "trapezoid"})
    assert (
        loop_params({"sample_rate_hz": 1000.0, "sensor_delay_s": 0.0015}).sensor_delay_s == 0.0015
    )


@pytest.mark.parametrize(
    "name, value",
    [
        ("sensor_delay_s", 5.0),
        ("spacecraft_mass_kg", -1.0),
        ("contact_stiffness_n_per_m", math.nan),
        ("initial_velocity_m_per_s", True),
        ("initial_velocity_m_per_s", "0.1"),
        ("compensator", "XYZ"),
        ("passivity", 1),
    ],
)
def test_check_value_refuses_naming_the_input(name, value):
    with pytest.raises(ParameterError, match=name) as info:
        check_value(name, value)
    assert "\n" not in str(info.value)


def test_check_value_accepts():
    assert check_value("sensor_delay_s", 0.003) == 0.003
    assert check_value("table_response_hz", math.inf) == math.inf
    assert check_value("compensator", "SDMDC") == "SDMDC"
    assert check_value("passivity", True) is True
