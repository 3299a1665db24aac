"""The header row of a run's CSV: which format column each log column is.

:func:`format_names` renames the log's columns by a
:class:`~hybridtable.measurement.log_layout.LogLayout` and checks that the
header holds every column of the layout's format once (the 1-D format's
:data:`~hybridtable.measurement.run_format.RUN_COLUMNS` unless the layout
names another; other columns are skipped); a missing column's message names the log's columns and proposes the
``--column-map`` that reads it, by name and by the usual other names of each
column (:data:`_ALIASES`), or names the delimiter or comment prefix the
header shows.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from hybridtable.errors import MeasurementError
from hybridtable.measurement.log_layout import LogLayout

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
        difflib.SequenceMatcher(None, name, log).ratio()
        for name in (column, *_ALIASES.get(column, ()))  # the 1-D format's usual other names
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


#: Prefixes that start a comment line in the logs of common loggers.
_COMMENT_MARKS = ("#", "%", "//", ";", "!")


def _layout_hint(header: list[str], layout: LogLayout) -> str:
    """Why a header lacks the format's columns, if the header shows it (a
    comment line taken for the header, a delimiter other than the layout's),
    as the message's text; else ``""``."""
    first = header[0] if header else ""
    for mark in _COMMENT_MARKS:
        if first.startswith(mark) and layout.comment != mark:
            return (
                f"the format's columns are missing and the first line starts with {mark!r} "
                f"like a comment line: give --comment '{mark}' "
                f'(comment = "{mark}" in a --log-map file)'
            )
    joined = layout.delimiter.join(header)
    for d, word in ((";", ";"), ("\t", "\\t"), ("|", "|"), (",", ",")):
        if d != layout.delimiter and joined.count(d) >= len(layout.format_columns) - 1:
            return (
                f"the format's columns are missing and the header ({shown(joined)!r}) looks "
                f"separated by '{word}': give --delimiter '{word}' "
                f'(delimiter = "{word}" in a --log-map file)'
            )
    return ""


def format_names(
    path: Path, header: list[str], header_line: int, layout: LogLayout
) -> list[str | None]:
    """The format name of every header cell (``None`` for a column not read),
    once the header holds every format column once.

    Parameters
    ----------
    path : path
        The CSV file (named in the messages).
    header : list of str
        The header's cells, stripped.
    header_line : int
        The header's file line (named in the messages).
    layout : LogLayout
        How the log's columns map to the format's.

    Returns
    -------
    list of str or None
        The format name of each cell, in file order; ``None`` for a column the
        format does not need or the layout ignores.

    Raises
    ------
    MeasurementError
        For an empty or repeated column name, a mapped column not in the
        header, a missing format column (naming the log's columns and
        proposing the ``--column-map`` that would read it, or the delimiter or
        comment prefix the header shows).
    """
    rename = layout.rename()
    names: list[str | None] = []
    for c in header:
        if not c:
            raise MeasurementError(f"{path} line {header_line}: empty column name in the header")
        name = None if c in layout.ignore else rename.get(c)
        if name is not None and name in names:
            raise MeasurementError(f"{path} line {header_line}: column {shown(c)!r} appears twice")
        names.append(name)
    mapped = [
        f"{fmt}={src.column}"
        for fmt, src in layout.columns.items()
        if src.column != fmt and src.column not in header
    ]
    missing = [c for c in layout.format_columns if c not in names]
    if (mapped or missing) and (hint := _layout_hint(header, layout)):
        raise MeasurementError(f"{path} line {header_line}: {hint}")
    if mapped:
        raise MeasurementError(
            f"{path} line {header_line}: {layout.source} names log column(s) not in the header: "
            f"{', '.join(mapped)} (has: {_column_list(header)})"
        )
    if missing:
        leftover = [c for c, name in zip(header, names, strict=True) if name is None]
        raise MeasurementError(
            f"{path} line {header_line}: {_missing_message(missing, header, leftover)}"
        )
    return names
