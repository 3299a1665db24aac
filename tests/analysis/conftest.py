"""Fixtures of the analysis tests."""

import pytest

from hybridtable.analysis.blockwise import ContactLoopLinearizer


@pytest.fixture(scope="module")
def lin() -> ContactLoopLinearizer:
    """The block-wise linearizer with a third-order Pade delay (one per test module)."""
    return ContactLoopLinearizer(3)
