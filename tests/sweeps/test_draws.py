"""The draws and the enumeration of a campaign's runs, as the docstrings state them.

Written from the docstrings of :mod:`hybridtable.sweeps.spec` and
:mod:`hybridtable.sweeps.distributions` only: the distributions' laws (KS and
chi-square tests on 4000 draws), the draws' determinism (a function of the
spec's seed and the sample's index), common random numbers across
compensators, points and grid cells, the run count and order (points x samples
x grid cells, the last grid axis then ``compensators`` varying fastest), and
log ranges. :meth:`~hybridtable.sweeps.spec.SweepSpec.run_inputs` is pure
Python: nothing here simulates or starts Dask.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from hybridtable.limits import limit_of
from hybridtable.sweeps.spec import parse_spec

__all__: list[str] = []

N = 4000
P_MIN = 1e-3  # a correct law fails one of these tests once in a thousand seeds

UNIFORM = {"distribution": "uniform", "low": 0.05, "high": 0.2}
LOG_UNIFORM = {"distribution": "log_uniform", "low": 1e4, "high": 1e6}
NORMAL = {"distribution": "normal", "mean": 0.8, "std": 0.05}
TRUNCATED = {"distribution": "normal", "mean": 0.004, "std": 0.002, "low": 0.001, "high": 0.006}
CHOICE = {"distribution": "choice", "values": [10.0, 25.0, 100.0], "weights": [1.0, 2.0, 5.0]}

DRAWS = {
    "initial_velocity_m_per_s": UNIFORM,
    "contact_stiffness_n_per_m": LOG_UNIFORM,
    "table_damping_ratio": NORMAL,
    "sensor_delay_s": TRUNCATED,
    "table_response_hz": CHOICE,
}


def monte_carlo(samples: int = N, seed: int = 11, draws: dict | None = None, **more):
    """A spec of ``samples`` draws of :data:`DRAWS` (or ``draws``)."""
    raw = {
        "name": "draws",
        "seed": seed,
        "metrics": ["cor"],
        "monte_carlo": {"samples": samples, "draw": DRAWS if draws is None else draws},
    }
    raw.update(more)
    return parse_spec(raw, source="draws.toml")


@pytest.fixture(scope="module")
def drawn() -> dict[str, np.ndarray]:
    """Every input of :data:`DRAWS`, one value per sample (one run each)."""
    spec = monte_carlo()
    assert spec.n_runs == N
    runs = [spec.run_inputs(i) for i in range(N)]
    assert [r.sample for r in runs] == list(range(N))
    return {name: np.array([r.values[name] for r in runs]) for name in DRAWS}


# -- the laws


def test_uniform_is_uniform(drawn):
    x = drawn["initial_velocity_m_per_s"]
    low, high = UNIFORM["low"], UNIFORM["high"]
    assert stats.kstest(x, "uniform", args=(low, high - low)).pvalue > P_MIN
    assert low <= x.min() and x.max() <= high


def test_log_uniform_is_uniform_in_log(drawn):
    x = drawn["contact_stiffness_n_per_m"]
    low, high = math.log(LOG_UNIFORM["low"]), math.log(LOG_UNIFORM["high"])
    assert stats.kstest(np.log(x), "uniform", args=(low, high - low)).pvalue > P_MIN
    # the median is the geometric mean of the ends, not their mean
    assert abs(math.log(np.median(x)) - (low + high) / 2) < 0.1


def test_normal_mean_and_std(drawn):
    x = drawn["table_damping_ratio"]
    mean, std = NORMAL["mean"], NORMAL["std"]
    assert abs(x.mean() - mean) < 4 * std / math.sqrt(N)
    assert abs(x.std(ddof=1) - std) < 4 * std / math.sqrt(2 * (N - 1))
    assert stats.kstest(x, "norm", args=(mean, std)).pvalue > P_MIN


def test_truncated_normal_is_truncnorm(drawn):
    x = drawn["sensor_delay_s"]
    low, high = TRUNCATED["low"], TRUNCATED["high"]
    mean, std = TRUNCATED["mean"], TRUNCATED["std"]
    assert low <= x.min() and x.max() <= high
    a, b = (low - mean) / std, (high - mean) / std
    assert stats.kstest(x, "truncnorm", args=(a, b, mean, std)).pvalue > P_MIN
    # asymmetric truncation moves the mean: the untruncated normal does not fit
    assert stats.kstest(x, "norm", args=(mean, std)).pvalue < P_MIN


def test_choice_frequencies_follow_weights(drawn):
    x = drawn["table_response_hz"]
    values, weights = CHOICE["values"], np.array(CHOICE["weights"])
    assert set(np.unique(x)) <= set(values)
    counts = np.array([(x == v).sum() for v in values])
    expected = N * weights / weights.sum()
    assert stats.chisquare(counts, expected).pvalue > P_MIN


def test_choice_without_weights_is_equally_likely():
    spec = monte_carlo(
        draws={
            "contact_gate": {
                "distribution": "choice",
                "values": ["measured_force", "table_position"],
            }
        }
    )
    x = [spec.run_inputs(i).values["contact_gate"] for i in range(N)]
    counts = [x.count("measured_force"), x.count("table_position")]
    assert sum(counts) == N
    assert stats.chisquare(counts).pvalue > P_MIN


def test_every_draw_is_plausible(drawn):
    for name, x in drawn.items():
        limit = limit_of(name)
        assert all(limit.contains(float(v)) for v in x), name


def test_inputs_of_a_sample_are_independent(drawn):
    """Two inputs of one sample, and one input in consecutive samples, are
    uncorrelated (|r| within 4 standard errors of 0)."""
    bound = 4 / math.sqrt(N)
    names = list(drawn)
    for first, second in itertools.combinations(names, 2):
        r = stats.spearmanr(drawn[first], drawn[second]).statistic
        assert abs(r) < bound, (first, second, r)
    for name in names:
        r = stats.spearmanr(drawn[name][:-1], drawn[name][1:]).statistic
        assert abs(r) < bound, (name, r)


# -- determinism


def values_of(spec) -> list[dict]:
    return [spec.run_inputs(i).values for i in range(spec.n_runs)]


def test_same_spec_same_inputs_on_a_second_parse():
    first, second = monte_carlo(200), monte_carlo(200)
    assert first == second
    for i in range(first.n_runs):
        assert first.run_inputs(i) == second.run_inputs(i)


def test_same_inputs_in_another_process(tmp_path):
    """Nothing depends on the process (hash seeds, import order): a fresh
    interpreter with another PYTHONHASHSEED draws the same."""
    spec = monte_carlo(50)
    here = [[r.seed, r.values] for r in map(spec.run_inputs, range(spec.n_runs))]
    script = tmp_path / "draw.py"
    script.write_text(
        "import json, sys\n"
        "from hybridtable.sweeps.spec import parse_spec\n"
        "raw = json.loads(sys.argv[1])\n"
        "spec = parse_spec(raw, source='draws.toml')\n"
        "print(json.dumps([[r.seed, r.values] for r in map(spec.run_inputs, range(spec.n_runs))]))\n",
        encoding="utf-8",
    )
    raw = {"name": "draws", "seed": 11, "metrics": ["cor"]}
    raw["monte_carlo"] = {"samples": 50, "draw": DRAWS}
    env = dict(os.environ, PYTHONHASHSEED="12345")
    done = subprocess.run(
        [sys.executable, str(script), json.dumps(raw)],
        capture_output=True,
        text=True,
        env=env,
        cwd=Path(__file__).parents[2],
        check=True,
    )
    assert json.loads(done.stdout) == json.loads(json.dumps(here))


def test_another_seed_draws_otherwise():
    a, b = monte_carlo(200, seed=11), monte_carlo(200, seed=12)
    x = np.array([v["initial_velocity_m_per_s"] for v in values_of(a)])
    y = np.array([v["initial_velocity_m_per_s"] for v in values_of(b)])
    assert (x != y).all()
    assert abs(np.corrcoef(x, y)[0, 1]) < 4 / math.sqrt(200)
    seeds_a = {a.run_inputs(i).seed for i in range(a.n_runs)}
    seeds_b = {b.run_inputs(i).seed for i in range(b.n_runs)}
    assert not seeds_a & seeds_b


def test_draws_do_not_depend_on_the_number_of_samples():
    """Sample i's draws come from the seed and i only: a longer campaign
    starts with the shorter one's draws (and the same runs' seeds)."""
    short, long = monte_carlo(10), monte_carlo(20)
    for i in range(10):
        assert short.run_inputs(i).values == long.run_inputs(i).values
        assert short.run_inputs(i).seed == long.run_inputs(i).seed
    assert long.run_inputs(10).values != long.run_inputs(0).values


def test_per_run_seeds_are_distinct():
    spec = monte_carlo(
        500,
        grid={"sensor_delay_s": [0.001, 0.003]},
        draws={"initial_velocity_m_per_s": UNIFORM},
        compensators=["none", "SDC", "MDC", "SDMDC"],
    )
    seeds = [spec.run_inputs(i).seed for i in range(spec.n_runs)]
    assert len(seeds) == 500 * 2 * 4
    assert len(set(seeds)) == len(seeds)
    assert all(isinstance(s, int) and s >= 0 for s in seeds)


# -- enumeration and common random numbers

GRID = {
    "sensor_delay_s": [0.001, 0.003, 0.005],
    "table_response_hz": {"start": 10.0, "stop": 1000.0, "num": 5, "scale": "log"},
}
COMPENSATORS = ["none", "SDC", "MDC", "SDMDC"]
POINTS = [{"contact_stiffness_n_per_m": 1e5}, {"contact_stiffness_n_per_m": 3e5}]


@pytest.fixture(scope="module")
def campaign():
    return monte_carlo(
        7,
        grid=GRID,
        points=POINTS,
        compensators=COMPENSATORS,
        draws={
            "initial_velocity_m_per_s": UNIFORM,
            "contact_frequency_hz": LOG_UNIFORM | {"low": 0.5, "high": 5.0},
        },
    )


def test_run_count_is_points_samples_cells(campaign):
    cells = 3 * 5 * 4
    assert campaign.cells == cells
    assert campaign.n_runs == len(POINTS) * 7 * cells
    runs = [campaign.run_inputs(i) for i in range(campaign.n_runs)]
    assert [r.index for r in runs] == list(range(campaign.n_runs))
    # every (point, sample, cell) once
    keys = {
        (
            r.point,
            r.sample,
            r.values["sensor_delay_s"],
            r.values["table_response_hz"],
            r.values["compensator"],
        )
        for r in runs
    }
    assert len(keys) == campaign.n_runs


def test_order_points_then_samples_then_cells(campaign):
    """Point slowest, then sample, then the grid axes in the spec's order,
    then the compensators fastest."""
    delays = GRID["sensor_delay_s"]
    responses = list(np.geomspace(10.0, 1000.0, 5))
    expected = itertools.product(range(len(POINTS)), range(7), delays, responses, COMPENSATORS)
    for i, (point, sample, delay, response, compensator) in enumerate(expected):
        r = campaign.run_inputs(i)
        assert (r.point, r.sample) == (point, sample), i
        assert r.values["sensor_delay_s"] == delay, i
        assert r.values["table_response_hz"] == pytest.approx(response, rel=1e-12), i
        assert r.values["compensator"] == compensator, i
        assert r.values["contact_stiffness_n_per_m"] == POINTS[point]["contact_stiffness_n_per_m"]


def test_one_draw_per_sample_shared_by_every_point_and_cell(campaign):
    """Common random numbers: the compensators (and points, cells) are
    compared on the same draws; different samples draw differently."""
    by_sample: dict[int, set] = {}
    for i in range(campaign.n_runs):
        r = campaign.run_inputs(i)
        drawn = (r.values["initial_velocity_m_per_s"], r.values["contact_frequency_hz"])
        by_sample.setdefault(r.sample, set()).add(drawn)
    assert sorted(by_sample) == list(range(7))
    assert all(len(d) == 1 for d in by_sample.values()), by_sample
    assert len({d for s in by_sample.values() for d in s}) == 7


def test_the_grid_does_not_change_the_draws(campaign):
    """Sample i draws the same in a campaign with or without a grid."""
    bare = monte_carlo(
        7,
        draws={
            "initial_velocity_m_per_s": UNIFORM,
            "contact_frequency_hz": LOG_UNIFORM | {"low": 0.5, "high": 5.0},
        },
    )
    names = ("initial_velocity_m_per_s", "contact_frequency_hz")
    for i in range(campaign.n_runs):
        r = campaign.run_inputs(i)
        alone = bare.run_inputs(r.sample).values
        assert [r.values[n] for n in names] == [alone[n] for n in names]


def test_log_range_is_geometric_with_exact_ends(campaign):
    axes = dict(campaign.grid)
    values = np.array(axes["table_response_hz"], dtype=float)
    assert len(values) == 5
    assert values[0] == pytest.approx(10.0, rel=1e-12)
    assert values[-1] == pytest.approx(1000.0, rel=1e-12)
    ratios = values[1:] / values[:-1]
    assert ratios == pytest.approx(np.full(4, 10**0.5), rel=1e-12)
    assert axes["sensor_delay_s"] == tuple(GRID["sensor_delay_s"])


def test_swept_lists_what_varies(campaign):
    assert set(campaign.swept) == {
        "contact_stiffness_n_per_m",
        "sensor_delay_s",
        "table_response_hz",
        "compensator",
        "initial_velocity_m_per_s",
        "contact_frequency_hz",
    }


def test_no_monte_carlo_is_one_sample():
    spec = parse_spec(
        {
            "name": "grid",
            "grid": {"sensor_delay_s": [0.001, 0.002]},
            "compensators": ["none", "SDC"],
        },
        source="grid.toml",
    )
    assert spec.samples == 1
    assert spec.n_runs == 4
    assert {spec.run_inputs(i).sample for i in range(4)} == {0}
