"""Shared test set-up: the Agg backend, and the tests measured slow."""

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
