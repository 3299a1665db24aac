"""The seed paper's parameter sets and tables.

The package ships the paper's tables (``hybridtable/data/paper_tables.json``,
schema in ``docs/paper.md``); a file given explicitly is preferred.
"""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path
from typing import Any

from hybridtable._files import read_user_json
from hybridtable.errors import ParameterError
from hybridtable.limits import TABLE1_DEFAULTS
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "TABLE1_DEFAULTS",
    "cor_estimate",
    "load_tables",
    "paper_params",
    "table1_params",
    "table2_params",
    "table2_rows",
]


def load_tables(path: str | Path | None = None) -> dict[str, Any]:
    """The paper's tables as a dict (the ``tables.json`` schema): ``path``, or
    the copy the package ships.

    Raises
    ------
    ParameterError
        One line naming ``path``: not a readable file, not JSON, or not the
        schema (Table 1's parameters and CoRs, Table 2's rows, each a plausible
        loop).
    """
    if path is None:
        text = resources.files("hybridtable.data").joinpath("paper_tables.json").read_text()
        return json.loads(text)
    tables = read_user_json(path, ParameterError)
    try:
        for c in ("none", "SDC", "MDC", "SDMDC"):
            float(tables["table1_simulation"]["cor"][c])
            table1_params(c, tables)
        rows = table2_rows(tables)
        for row in rows:
            float(row["cor_sdmdc"])
            table2_params(row)
        if not rows:
            raise ValueError("Table 2 has no rows")
    except ParameterError as err:
        raise ParameterError(f"{path}: {err}") from None
    except (KeyError, TypeError, ValueError, AttributeError) as err:
        raise ParameterError(
            f"{path}: not the paper's tables ({type(err).__name__}: {err}); see "
            "hybridtable/data/paper_tables.json for the schema"
        ) from None
    return tables


def paper_params(compensator: str = "none", **kwargs: Any) -> HybridLoopParams:
    """Loop parameters of a paper-style run (continuous, T_lead = T_fms): the
    Table 1 point (:data:`~hybridtable.limits.TABLE1_DEFAULTS`) with ``kwargs``
    (any field of :class:`~hybridtable.loop.params.HybridLoopParams`, or
    ``contact_frequency_hz``, which sets the mass with the stiffness)."""
    values = {**TABLE1_DEFAULTS, **kwargs}
    frequency = values.pop("contact_frequency_hz")
    stiffness = values.pop("contact_stiffness_n_per_m")
    return HybridLoopParams.from_contact_frequency(
        frequency, stiffness, compensator=compensator, **values
    )


def table1_params(
    compensator: str, tables: dict[str, Any] | None = None, **kwargs: Any
) -> HybridLoopParams:
    """Parameters of Table 1 for one compensator; ``kwargs`` change any
    quantity (e.g. ``table_response_hz=math.inf``, ``sample_rate_hz=1000.0``)."""
    tables = tables or load_tables()
    p = dict(tables["table1_simulation"]["parameters"])
    return paper_params(compensator=compensator, **{**p, **kwargs})


def table2_rows(tables: dict[str, Any] | None = None) -> list[dict[str, float]]:
    """Rows of Table 2, in the paper's order, with the paper's units."""
    tables = tables or load_tables()
    t2 = tables["table2_simulation_sdmdc"]
    return [dict(zip(t2["columns"], row, strict=True)) for row in t2["rows"]]


def table2_params(row: dict[str, float], **kwargs: Any) -> HybridLoopParams:
    """Loop parameters (SDMDC, table damping 0.8) of one Table 2 row."""
    return paper_params(
        compensator="SDMDC",
        sensor_delay_s=row["sensor_delay_ms"] * 1e-3,
        table_response_hz=row["table_response_hz"],
        contact_frequency_hz=row["contact_frequency_hz"],
        contact_stiffness_n_per_m=row["contact_stiffness_n_per_mm"] * 1e3,
        initial_velocity_m_per_s=row["initial_velocity_mm_per_s"] * 1e-3,
        **kwargs,
    )


def cor_estimate(params: HybridLoopParams) -> float:
    """First-order CoR estimate exp(pi^2 f_con tau_eff) of an uncompensated,
    undamped loop with small effective delay tau_eff."""
    return math.exp(math.pi**2 * params.contact_frequency_hz * params.effective_delay_s)
