"""The paper's operating points (hybridtable.studies.paper): the loop at the Table 1
point reproduces the paper's CoRs, and the uncompensated CoR follows the
effective-delay estimate."""

import math

import pytest

from hybridtable import simulate
from hybridtable.studies.paper import cor_estimate, load_tables, paper_params, table1_params


@pytest.mark.parametrize(
    "delay_s, table_hz, contact_hz",
    [
        (0.005, 25.0, 1.0),
        (0.001, 100.0, 1.0),
        (0.003, 50.0, 2.0),
        (0.0, 25.0, 1.0),
        (0.005, math.inf, 1.0),
    ],
)
def test_uncompensated_cor_matches_effective_delay_estimate(delay_s, table_hz, contact_hz):
    p = paper_params(
        sensor_delay_s=delay_s, table_response_hz=table_hz, contact_frequency_hz=contact_hz
    )
    r = simulate(p)
    assert r.metrics.cor == pytest.approx(cor_estimate(p), abs=0.005)
    assert r.metrics.cor > 1.0 or delay_s == 0.0 and math.isinf(table_hz)


@pytest.fixture(scope="module")
def table1(paper_run):
    paper = load_tables()["table1_simulation"]["cor"]
    runs = {}
    for c in ("none", "SDC", "MDC", "SDMDC"):
        p = table1_params(c)
        runs[c] = (
            paper_run(c).metrics.cor,
            simulate(p.with_(time_step_s=p.step_s / 2)).metrics.cor,
        )
    return paper, runs


@pytest.mark.parametrize("compensator", ["none", "SDC", "MDC", "SDMDC"])
def test_table1_within_0p003_of_paper(table1, compensator):
    paper, runs = table1
    assert runs[compensator][0] == pytest.approx(paper[compensator], abs=0.003)


@pytest.mark.parametrize("compensator", ["none", "SDC", "MDC", "SDMDC"])
def test_halving_the_step_changes_cor_by_less_than_0p0005(table1, compensator):
    _, runs = table1
    assert abs(runs[compensator][0] - runs[compensator][1]) < 5e-4


def test_compensation_ordering_of_table1(table1):
    _, runs = table1
    cor = {c: v[0] for c, v in runs.items()}
    assert cor["none"] > cor["SDC"] > cor["MDC"] > cor["SDMDC"]


def test_table1_params_takes_any_quantity_of_the_table_too():
    """A quantity Table 1 states (the table's response) and one it does not
    (the rig computer's rate) both change the point; the rest stays Table 1's
    (a stated one raised 'got multiple values for keyword argument')."""
    import math

    from hybridtable.studies.paper import table1_params

    base = table1_params("SDC")
    ideal = table1_params("SDC", table_response_hz=math.inf, sample_rate_hz=1000.0)
    assert ideal.table_response_hz == math.inf and ideal.sample_rate_hz == 1000.0
    assert ideal.with_(table_response_hz=base.table_response_hz, sample_rate_hz=None) == base
