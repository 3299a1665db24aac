"""A measured CoR table: its rows, the conditions each states, and its noise.

The CSV has a header and a row per measured run or per compensator:
``compensator`` (none, SDC, MDC, SDMDC) and ``cor`` are required;
``cor_std`` and the fields of :class:`~hybridtable.explain.conditions.Conditions`
are optional columns (an empty cell: not stated for that row). What a row does
not state comes from the flags, else from the paper's Table 1
(:data:`~hybridtable.explain.conditions.PAPER_CONDITIONS`), and is reported so.

The noise of a row's ln CoR is, in this order: its ``cor_std``; the scatter of
repeated rows (same compensator and conditions), pooled; the rounding of the
``cor`` column (its most decimals ``d``: a uniform error of one unit of the
last digit, std ``10^-d / sqrt(12)``), which is also the floor of the first two.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hybridtable._files import read_user_text
from hybridtable._validation import check_choice
from hybridtable.errors import MeasurementError, ParameterError
from hybridtable.explain.conditions import CONDITION_FIELDS, PAPER_CONDITIONS, Conditions

__all__ = ["COMPENSATOR_NAMES", "CorRow", "CorTable", "read_cor_table", "cor_table"]

#: The compensators a CoR table may name (the paper's four), in their order.
COMPENSATOR_NAMES: tuple[str, ...] = ("none", "SDC", "MDC", "SDMDC")
_COLUMNS = ("compensator", "cor", "cor_std", *CONDITION_FIELDS)


@dataclass(frozen=True)
class CorRow:
    """One measured CoR.

    Parameters
    ----------
    compensator : str
        none, SDC, MDC or SDMDC.
    cor : float
        The measured coefficient of restitution, > 0.
    conditions : Conditions
        What the row states (the flags and the paper's Table 1 for the rest).
    cor_std : float or None
        The CoR's standard deviation the lab gives, if any.
    decimals : int
        Decimals written in the ``cor`` cell (0 when not known).
    line : int
        The row's line in the CSV (0 when built in code).
    """

    compensator: str
    cor: float
    conditions: Conditions
    cor_std: float | None = None
    decimals: int = 0
    line: int = 0

    @property
    def label(self) -> str:
        """The row as a reader names it: the compensator, and the line if any."""
        return f"{self.compensator} (line {self.line})" if self.line else self.compensator


@dataclass(frozen=True)
class CorTable:
    """The rows of a measured CoR table and where their conditions came from.

    Parameters
    ----------
    rows : tuple of CorRow
        The measured CoRs.
    source : str
        The file, or a description.
    stated : dict
        Condition field -> ``"table"``, ``"flag"``, ``"table and flag"`` or ``"assumed"``.
    """

    rows: tuple[CorRow, ...]
    source: str = "table"
    stated: Mapping[str, str] | None = None

    def __post_init__(self) -> None:
        if not self.rows:
            raise ParameterError(f"{self.source}: the table has no rows")

    @property
    def ln_cor(self) -> np.ndarray:
        """ln CoR of every row."""
        return np.log([r.cor for r in self.rows])

    @property
    def assumed(self) -> list[str]:
        """The condition fields no row or flag states (taken from the paper's Table 1)."""
        return [k for k, v in (self.stated or {}).items() if v == "assumed"]

    @property
    def rounding_std(self) -> float:
        """The std of the ``cor`` column's rounding, ``10^-d / sqrt(12)`` (0 if unknown)."""
        d = max(r.decimals for r in self.rows)
        return 0.0 if d <= 0 else 10.0 ** (-d) / math.sqrt(12.0)

    def groups(self) -> list[list[int]]:
        """Row indices of each set of repeated rows (same compensator and conditions)."""
        keys: dict[tuple, list[int]] = {}
        for i, r in enumerate(self.rows):
            keys.setdefault((r.compensator, r.conditions), []).append(i)
        return list(keys.values())

    def noise(self) -> tuple[np.ndarray, str]:
        """The std of each row's CoR, and where it comes from, in words."""
        rounding = self.rounding_std
        given = [r.cor_std for r in self.rows]
        if all(g is not None for g in given):
            std = np.maximum(np.array(given, float), rounding)
            return std, "the table's cor_std"
        repeated = [g for g in self.groups() if len(g) > 1]
        if repeated:
            dev = [
                self.rows[i].cor - np.mean([self.rows[j].cor for j in g])
                for g in repeated
                for i in g
            ]
            dof = sum(len(g) - 1 for g in repeated)
            scatter = math.sqrt(float(np.sum(np.square(dev))) / dof)
            std = np.array([g if g is not None else max(scatter, rounding) for g in given], float)
            n = sum(len(g) for g in repeated)
            return std, f"the scatter of {n} repeated rows (std {scatter:.2g})"
        if rounding > 0.0:
            std = np.array([g if g is not None else rounding for g in given], float)
            d = max(r.decimals for r in self.rows)
            return std, f"the rounding to {d} decimals (std {rounding:.2g})"
        raise ParameterError(
            f"{self.source}: no cor_std, no repeated rows and no known rounding; give --cor-std"
        )

    def with_cor_std(self, cor_std: float) -> CorTable:
        """The table with ``cor_std`` given for every row that has none."""
        rows = tuple(r if r.cor_std is not None else replace(r, cor_std=cor_std) for r in self.rows)
        return replace(self, rows=rows)


def _decimals(cell: str) -> int:
    text = cell.strip().lower()
    if "e" in text:
        mantissa, _, exponent = text.partition("e")
        return max(0, _decimals(mantissa) - int(exponent))
    return len(text.partition(".")[2])


def _number(path: str, line: int, column: str, cell: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise MeasurementError(f"{path}:{line}: {column} {cell!r} is not a number") from None
    if not math.isfinite(value) and not (column == "table_response_hz" and value == math.inf):
        raise MeasurementError(f"{path}:{line}: {column} {cell!r} is not finite")
    return value


def _compensator(path: str, line: int, cell: str) -> str:
    try:  # any letter case, as everywhere a compensator is named
        return check_choice("compensator", cell.strip(), COMPENSATOR_NAMES, any_case=True)
    except ParameterError:
        raise MeasurementError(
            f"{path}:{line}: compensator {cell!r} is not one of {', '.join(COMPENSATOR_NAMES)}"
        ) from None


def cor_table(
    records: list[Mapping[str, str | float | None]],
    defaults: Mapping[str, float | None] | None = None,
    source: str = "table",
    lines: list[int] | None = None,
) -> CorTable:
    """A :class:`CorTable` from rows of cells (``str`` as read from a CSV, or numbers).

    Parameters
    ----------
    records : list of mapping
        Column -> cell; ``None`` or ``""``: not stated.
    defaults : mapping, optional
        Condition field -> value stated once for the table (the flags).
    source : str
        The file the rows come from, for messages.
    lines : list of int, optional
        Each record's line in the file.

    Raises
    ------
    MeasurementError
        One line naming the file, the line and the column.
    """
    defaults = {k: v for k, v in (defaults or {}).items() if v is not None}
    for key in defaults:
        if key not in CONDITION_FIELDS:
            raise ParameterError(f"unknown condition {key!r}; known: {', '.join(CONDITION_FIELDS)}")
    lines = lines or list(range(2, len(records) + 2))
    rows = []
    from_table: dict[str, int] = dict.fromkeys(CONDITION_FIELDS, 0)
    for record, line in zip(records, lines, strict=True):
        cells = {k: ("" if v is None else str(v)).strip() for k, v in record.items()}
        for key in ("compensator", "cor"):
            if not cells.get(key):
                raise MeasurementError(f"{source}:{line}: the row has no {key}")
        cor = _number(source, line, "cor", cells["cor"])
        if not 0.0 < cor < 10.0:
            raise MeasurementError(f"{source}:{line}: cor {cor:g} is not a CoR (0 < CoR < 10)")
        std = None
        if cells.get("cor_std"):
            std = _number(source, line, "cor_std", cells["cor_std"])
            if std <= 0.0:
                raise MeasurementError(f"{source}:{line}: cor_std {std:g} must be > 0")
        values = dict(PAPER_CONDITIONS)
        values.update(defaults)
        for key in CONDITION_FIELDS:
            if cells.get(key):
                values[key] = _number(source, line, key, cells[key])
                from_table[key] += 1
        try:
            conditions = Conditions(**values)
        except ParameterError as err:
            raise MeasurementError(f"{source}:{line}: {err}") from None
        rows.append(
            CorRow(
                compensator=_compensator(source, line, cells["compensator"]),
                cor=cor,
                conditions=conditions,
                cor_std=std,
                decimals=_decimals(cells["cor"]) if isinstance(record["cor"], str) else 0,
                line=line,
            )
        )
    stated = {}
    for key in CONDITION_FIELDS:
        n = from_table[key]
        if n == len(rows):
            stated[key] = "table"
        elif n and key in defaults:
            stated[key] = "table and flag"
        elif n:
            stated[key] = "table and assumed"
        elif key in defaults:
            stated[key] = "flag"
        else:
            stated[key] = "assumed"
    if stated["lead_time_s"] == "assumed":
        stated["lead_time_s"] = "the sensor delay (assumed)"
    return CorTable(rows=tuple(rows), source=source, stated=stated)


def read_cor_table(
    path: str | Path, defaults: Mapping[str, float | None] | None = None
) -> CorTable:
    """Read a CoR table's CSV (see the module's docstring).

    Raises
    ------
    MeasurementError
        One line naming the file (and the line, the column): not UTF-8 text, no
        header, an unknown or missing column, a cell that is not a number, a CoR
        or a condition out of its range.
    """
    text = read_user_text(path, MeasurementError)
    reader = csv.reader(io.StringIO(text))
    try:
        table = [(reader.line_num, row) for row in reader]
    except csv.Error as err:
        raise MeasurementError(f"{path}: not a CSV table ({err})") from None
    table = [(n, row) for n, row in table if any(c.strip() for c in row)]
    if not table:
        raise MeasurementError(f"{path}: empty file; expected a header with compensator,cor")
    header = [c.strip() for c in table[0][1]]
    unknown = [c for c in header if c not in _COLUMNS]
    if unknown:
        raise MeasurementError(
            f"{path}: unknown column {unknown[0]!r}; the columns are {', '.join(_COLUMNS)} (SI units)"
        )
    for key in ("compensator", "cor"):
        if key not in header:
            raise MeasurementError(f"{path}: no {key!r} column (header: {', '.join(header)})")
    if len(set(header)) != len(header):
        raise MeasurementError(f"{path}: a column appears twice in the header")
    records, lines = [], []
    for n, row in table[1:]:
        if len(row) != len(header):
            raise MeasurementError(f"{path}:{n}: {len(row)} cells for {len(header)} columns")
        records.append(dict(zip(header, row, strict=True)))
        lines.append(n)
    if not records:
        raise MeasurementError(f"{path}: the table has a header but no rows")
    return cor_table(records, defaults, source=str(path), lines=lines)
