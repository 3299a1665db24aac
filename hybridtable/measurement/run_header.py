"""The header row of a run's CSV: which format column each log column is.

:func:`format_names` renames the log's columns by a column map and checks that
the header holds exactly the columns of
:data:`~hybridtable.measurement.run_format.RUN_COLUMNS`; a missing column's
message names the log's columns and proposes the ``--column-map`` that reads
it, by name and by the usual other names of each column (:data:`_ALIASES`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from hybridtable.errors import MeasurementError
from hybridtable.measurement.run_format import RUN_COLUMNS

__all__ = ["format_names", "shown"]

#: Other names a log may give each format column (lower case), for the
#: suggestion of a missing column's error.
_ALIASES = {
    "time_s": ("time", "t", "timestamp"),
    "p_des_m": ("p_des", "p_cmd", "position_command", "commanded_position", "command"),
    "p_act_m": ("p_act", "position", "table_position", "actual_position", "p_table"),
    "f_mea_n": ("f_mea", "force", "measured_force", "f_measured", "fz"),
    "f_comp_n": ("f_comp", "compensated_force", "f_compensated", "force_command"),
    "v_des_m_per_s": ("v_des", "velocity", "v_cmd", "commanded_velocity"),
}

#: Least :class:`difflib.SequenceMatcher` ratio of a proposed log column.
_SIMILAR = 0.6


def _similarity(column: str, log_name: str) -> float:
    import difflib

    log = log_name.strip().lower()
    return max(
        difflib.SequenceMatcher(None, name, log).ratio() for name in (column, *_ALIASES[column])
    )


def shown(text: str, most: int = 40) -> str:
    """``text`` cut to ``most`` characters for a one-line message (a log's cell
    or column name may be a megabyte long)."""
    text = str(text)
    return text if len(text) <= most else f"{text[:most]}... ({len(text)} characters)"


def _column_list(header: Sequence[str], most: int = 10) -> str:
    listed = ", ".join(shown(c) for c in header[:most])
    return listed + (f", ... ({len(header)} in all)" if len(header) > most else "")


def _missing_message(missing: list[str], header: list[str], leftover: list[str]) -> str:
    """One line: the missing format columns, the log's columns and the
    ``--column-map`` that would read them, with the most similar unmapped log
    column proposed for each (by name, :data:`_ALIASES`), where one is."""
    pairs = sorted(
        ((_similarity(m, c), i, m, c) for i, m in enumerate(missing) for c in leftover),
        key=lambda x: (-x[0], x[1]),
    )
    proposed: dict[str, str] = {}
    for score, _, m, c in pairs:
        if score >= _SIMILAR and m not in proposed and c not in proposed.values():
            proposed[m] = c
    text = f"missing column(s) {', '.join(missing)} (has: {_column_list(header)})"
    if not leftover:
        return text + "; the log has no other column to read it from"
    them = "it" if len(missing) == 1 else "them"
    items = ",".join(f"{m}={proposed.get(m, 'LOG_COLUMN')}" for m in missing)
    return f"{text}; map {them} with --column-map {items}"


def format_names(
    path: Path, header: list[str], header_line: int, column_map: Mapping[str, str] | None
) -> list[str]:
    """The format name of every header cell, once the header holds exactly
    the format's columns.

    Parameters
    ----------
    path : path
        The CSV file (named in the messages).
    header : list of str
        The header's cells, stripped.
    header_line : int
        The header's file line (named in the messages).
    column_map : mapping, optional
        ``{format_column: log_column}``: log names renamed to format names.

    Returns
    -------
    list of str
        The format name of each cell, in file order.

    Raises
    ------
    MeasurementError
        For an empty or repeated column name, a ``column_map`` entry not in the
        header, a missing format column (naming the log's columns and proposing
        the ``--column-map`` that would read it) or a column the format lacks.
    """
    rename = {log: fmt for fmt, log in (column_map or {}).items()}
    names = [rename.get(c, c) for c in header]
    seen: set[str] = set()
    for c, name in zip(header, names, strict=True):
        if not c:
            raise MeasurementError(f"{path} line {header_line}: empty column name in the header")
        if name in seen:
            raise MeasurementError(f"{path} line {header_line}: column {shown(c)!r} appears twice")
        seen.add(name)
    unmatched = [f"{f}={log}" for f, log in (column_map or {}).items() if log not in header]
    if unmatched:
        raise MeasurementError(
            f"{path} line {header_line}: --column-map entries not in the header: "
            f"{', '.join(unmatched)} (has: {_column_list(header)})"
        )
    missing = [c for c in RUN_COLUMNS if c not in seen]
    if missing:
        leftover = [c for c, name in zip(header, names, strict=True) if name not in RUN_COLUMNS]
        raise MeasurementError(
            f"{path} line {header_line}: {_missing_message(missing, header, leftover)}"
        )
    extra = [c for c, name in zip(header, names, strict=True) if name not in RUN_COLUMNS]
    if extra:
        raise MeasurementError(
            f"{path} line {header_line}: unexpected column(s) {_column_list(extra)} "
            f"(the format has {', '.join(RUN_COLUMNS)}; rename with --column-map)"
        )
    return names
