"""CoR tables for the tests of ``hybridtable.explain``, each explained once per session.

The tables come from the independent generator ``tests/generators/cortable.py``:
the rows carry the STATED conditions, the CoR comes from the TRUE rig (one
hidden effect); they are written as CSV (4 decimals, a 1 kHz rig computer) and
read back through :func:`~hybridtable.explain.table.read_cor_table`, as a lab's
file would be.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from hybridtable.explain.explain import Explanation, explain_table
from hybridtable.explain.table import CorTable, read_cor_table
from tests.generators import cortable

__all__ = ["COMPENSATORS", "SAMPLE_RATE_HZ", "TWO_FREQUENCIES", "generated_table"]

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")
#: The rig computer's rate of every generated table, Hz (1 kHz: ~10x cheaper than continuous).
SAMPLE_RATE_HZ = 1000.0
#: Two stated contact frequencies with the same spacecraft model (2533 kg): 1 Hz at
#: 1e5 N/m and 2 Hz at 4e5 N/m; the rest is the paper's Table 1 (5 ms, 25 Hz table).
TWO_FREQUENCIES: tuple[dict, ...] = (
    {},
    {"contact_frequency_hz": 2.0, "contact_stiffness_n_per_m": 4.0e5},
)


def generated_table(
    folder: Path,
    name: str,
    conditions: Sequence[dict],
    hidden: dict | None = None,
    compensators: Sequence[str] = COMPENSATORS,
) -> CorTable:
    """A generated table (4 decimals, 1 kHz), written as CSV and read back."""
    rows = cortable.make_table(
        conditions,
        compensators=compensators,
        hidden=hidden,
        sample_rate_hz=SAMPLE_RATE_HZ,
        decimals=4,
    )
    path = cortable.write_csv(rows, folder / f"{name}.csv")
    return read_cor_table(path)


@pytest.fixture(scope="session")
def explained(tmp_path_factory) -> Callable[..., Explanation]:
    """``explained(name, conditions, hidden=None, compensators=..., max_effects=2)``:
    the explanation of a generated table, computed once per ``name`` (an error
    is kept and raised again, not recomputed)."""
    folder = tmp_path_factory.mktemp("cortables")
    cache: dict[str, Explanation | Exception] = {}

    def get(
        name: str,
        conditions: Sequence[dict],
        hidden: dict | None = None,
        compensators: Sequence[str] = COMPENSATORS,
        max_effects: int = 2,
    ) -> Explanation:
        if name not in cache:
            try:
                table = generated_table(folder, name, conditions, hidden, compensators)
                cache[name] = explain_table(table, max_effects=max_effects)
            except Exception as err:
                # kept: the first test shows the whole traceback, the others one line
                cache[name] = err
                raise
        value = cache[name]
        if isinstance(value, Exception):
            where = traceback.extract_tb(value.__traceback__)[-1]
            pytest.fail(
                f"explain_table on the {name!r} table raised {type(value).__name__} "
                f"({where.filename}:{where.lineno}): {value}",
                pytrace=False,
            )
        return value

    return get
