"""Shared test set-up: the Agg backend, the tests measured slow, and the
session's shared results (the paper's Table 1 and Table 2 runs, each simulated
once)."""

import functools
import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")


#: Node ids measured slow (tests/slow_tests.txt): marked ``slow`` at collection.
MEASURED_SLOW: frozenset[str] = frozenset(
    line.strip()
    for line in (Path(__file__).parent / "slow_tests.txt").read_text().splitlines()
    if line.strip() and not line.startswith("#")
)


def pytest_collection_modifyitems(config, items):
    """Mark the tests measured slow, so ``make check`` (-m "not slow") leaves them."""
    for item in items:
        if item.nodeid in MEASURED_SLOW:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def paper_run():
    """The paper's Table 1 run of one compensator through the Drake diagram
    (``simulate(table1_params(name))``), simulated once per session:
    ``paper_run("SDMDC").metrics.cor``. Read it; never change it."""
    from hybridtable import simulate
    from hybridtable.studies.paper import table1_params

    @functools.cache
    def run(compensator: str):
        return simulate(table1_params(compensator))

    return run


@pytest.fixture(scope="session")
def table2_run():
    """The paper's Table 2 row ``i`` (SDMDC, ``table2_rows()[i]``) through the
    Drake diagram, simulated once per session: ``table2_run(0).metrics.cor``.
    Read it; never change it."""
    from hybridtable import simulate
    from hybridtable.studies.paper import table2_params, table2_rows

    rows = table2_rows()

    @functools.cache
    def run(i: int):
        return simulate(table2_params(rows[i]))

    return run
