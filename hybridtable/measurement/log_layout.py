"""How a rig's own log maps to the run format: columns, units, delimiter, comments.

A rig's logger rarely writes ``hybridtable-run/1`` as it stands: other column
names, extra columns, ``;`` with decimal commas, ``#`` comment lines, time in
ms, forces in kN. A :class:`LogLayout` says once how a log maps to the format
(``docs/run-format.md``, "Reading a rig's own log"): for every format column
the log column it is read from (:class:`ColumnSource`: name, unit, scale), and
how the file is written (delimiter, decimal mark, comment prefix, columns to
skip). It is read from a TOML file (``--log-map``, :func:`read_log_map`) and
the flags that override it (:func:`log_layout`); every defect is one
:class:`~hybridtable.errors.MeasurementError` line naming the file or flag and
the key. The run reader (:mod:`~hybridtable.measurement.run_reader`) reads
through it, and :mod:`~hybridtable.measurement.log_units` checks the units
against the run's JSON.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

from hybridtable.errors import MeasurementError
from hybridtable.measurement.run_format import RUN_COLUMNS

__all__ = [
    "UNITS",
    "ColumnSource",
    "LogLayout",
    "DEFAULT_LAYOUT",
    "read_log_map",
    "log_layout",
    "parse_pairs",
]

#: The units a log may hold a channel in, by the format's (SI) unit: name ->
#: factor to SI.
UNITS: Mapping[str, Mapping[str, float]] = MappingProxyType(
    {
        "s": MappingProxyType({"s": 1.0, "ms": 1e-3, "us": 1e-6}),
        "m": MappingProxyType({"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6}),
        "N": MappingProxyType({"N": 1.0, "kN": 1e3, "mN": 1e-3}),
        "m/s": MappingProxyType({"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3}),
        # The 6-DoF format's (hybridtable.six_dof.run6).
        "1": MappingProxyType({"1": 1.0}),
        "rad/s": MappingProxyType({"rad/s": 1.0, "deg/s": math.pi / 180.0}),
        "N m": MappingProxyType({"N m": 1.0, "kN m": 1e3, "N mm": 1e-3}),
    }
)

#: Delimiters a log may use, with the words that name one on the command line.
_DELIMITERS = {",": ",", ";": ";", "\t": "\t", "|": "|", " ": " "}
_DELIMITER_WORDS = {"\\t": "\t", "tab": "\t", "space": " ", "comma": ",", "semicolon": ";"}

#: Keys of a log-map file.
_KEYS = ("delimiter", "decimal", "comment", "ignore", "columns")


def _units_of(column: str, format_columns: Mapping[str, str] = RUN_COLUMNS) -> Mapping[str, float]:
    return UNITS[format_columns[column]]


@dataclass(frozen=True)
class ColumnSource:
    """Where a format column comes from in a log.

    Parameters
    ----------
    column : str
        The log's column name.
    unit : str
        The unit the log holds it in (one of :data:`UNITS` for the format
        column's SI unit).
    scale : float
        A further factor (``-1`` for a sign the other way round, a calibration
        factor): the SI value is ``value * unit factor * scale``.
    """

    column: str
    unit: str
    scale: float = 1.0

    @property
    def plain(self) -> bool:
        """True if the value is read as it stands (SI, scale 1)."""
        return self.scale == 1.0 and self.unit in UNITS


def _over(
    columns: Mapping[str, ColumnSource],
    names: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    format_columns: Mapping[str, str] = RUN_COLUMNS,
) -> dict[str, ColumnSource]:
    """``columns`` (format column -> source; a column not there is read from
    its own name in SI) with the log names ``names`` and the units ``units``
    of format columns over them; an unknown format column is refused."""
    out = dict(columns)
    for changes, field_name in ((names, "column"), (units, "unit")):
        for fmt, value in (changes or {}).items():
            if fmt not in format_columns:
                raise MeasurementError(
                    f"{fmt!r} is not a column of the format (one of {', '.join(format_columns)})"
                )
            old = out.get(fmt, ColumnSource(fmt, format_columns[fmt]))
            out[fmt] = replace(old, **{field_name: value})
    return out


def _default_columns(format_columns: Mapping[str, str] = RUN_COLUMNS) -> Mapping[str, ColumnSource]:
    return MappingProxyType({c: ColumnSource(c, u) for c, u in format_columns.items()})


@dataclass(frozen=True)
class LogLayout:
    """How a log maps to the run format (see the module).

    Parameters
    ----------
    columns : mapping
        Format column -> :class:`ColumnSource`; a column not given is read
        from the log column of its own name, in SI.
    delimiter : str
        The cell delimiter, one of ``, ; tab | space``.
    decimal : str
        The decimal mark, ``.`` or ``,`` (``,`` needs another delimiter).
    comment : str or None
        Lines starting with it (after leading blanks) are skipped.
    ignore : tuple of str
        Log columns never read (one that would collide with a format column's name).
    source : str
        Where the mapping was given, for messages (``rig-b.toml``, or the flags).
    format_columns : mapping
        The format's columns and their SI units (default: the 1-D format's
        :data:`~hybridtable.measurement.run_format.RUN_COLUMNS`; the 6-DoF
        format's are :data:`hybridtable.six_dof.run6.RUN6_COLUMNS`).
    """

    columns: Mapping[str, ColumnSource] = field(default_factory=dict)
    delimiter: str = ","
    decimal: str = "."
    comment: str | None = None
    ignore: tuple[str, ...] = ()
    source: str = "the flags"
    format_columns: Mapping[str, str] = field(default_factory=lambda: RUN_COLUMNS)

    def __post_init__(self) -> None:
        known = self.format_columns
        cols = dict(_default_columns(known))
        for name, src in dict(self.columns).items():
            if name not in known:
                raise MeasurementError(
                    f"{self.source}: {name!r} is not a column of the format "
                    f"(one of {', '.join(known)})"
                )
            if src.unit not in _units_of(name, known):
                raise MeasurementError(
                    f"{self.source}: unknown unit {src.unit!r} for {name} "
                    f"(one of {', '.join(_units_of(name, known))})"
                )
            if not math.isfinite(src.scale) or src.scale == 0.0:
                raise MeasurementError(
                    f"{self.source}: the scale of {name} must be a finite non-zero number "
                    f"(got {src.scale!r})"
                )
            if not src.column.strip():
                raise MeasurementError(f"{self.source}: empty log column name for {name}")
            cols[name] = src
        logs = [s.column for s in cols.values()]
        twice = sorted({c for c in logs if logs.count(c) > 1})
        if twice:
            users = [n for n, s in cols.items() if s.column == twice[0]]
            raise MeasurementError(
                f"{self.source}: log column {twice[0]!r} is read for {' and '.join(users)}"
            )
        if self.delimiter not in _DELIMITERS:
            raise MeasurementError(
                f"{self.source}: delimiter {self.delimiter!r} is not one of , ; tab | space"
            )
        if self.decimal not in (".", ","):
            raise MeasurementError(
                f"{self.source}: decimal must be '.' or ',' (got {self.decimal!r})"
            )
        if self.decimal == self.delimiter:
            raise MeasurementError(
                f"{self.source}: a decimal comma needs another delimiter than ',' "
                '(give delimiter = ";", for example)'
            )
        if self.comment is not None and not self.comment.strip():
            raise MeasurementError(f"{self.source}: the comment prefix must not be empty")
        read = [i for i in self.ignore if i in logs]
        if read:
            raise MeasurementError(f"{self.source}: column {read[0]!r} is both read and ignored")
        object.__setattr__(self, "columns", MappingProxyType(cols))
        object.__setattr__(self, "ignore", tuple(self.ignore))

    # -- reading ---------------------------------------------------------------
    def rename(self) -> dict[str, str]:
        """Log column name -> format column name."""
        return {src.column: name for name, src in self.columns.items()}

    def factor(self, column: str) -> float:
        """The factor from the log's number to SI for format ``column``."""
        src = self.columns[column]
        return _units_of(column, self.format_columns)[src.unit] * src.scale

    @property
    def plain(self) -> bool:
        """True if the log is the format's own CSV (names, units, delimiter)."""
        return all(s.column == n and s.plain for n, s in self.columns.items()) and (
            self.delimiter,
            self.decimal,
            self.comment,
            self.ignore,
        ) == (",", ".", None, ())

    def read_as(self, column: str) -> str:
        """``f_mea_n (log column 'Fz', read in kN)`` for messages."""
        src = self.columns[column]
        named = "" if src.column == column else f"log column {src.column!r}, "
        scaled = "" if src.scale == 1.0 else f" times {src.scale:g}"
        return f"{column} ({named}read in {src.unit}{scaled})"

    def unit_advice(self, units: Mapping[str, str]) -> str:
        """How to state that each column of ``units`` is in its unit, in the user's words."""
        flag = "--unit " + ",".join(f"{c}={u}" for c, u in units.items())
        toml = ", ".join(f'unit = "{u}" for {c}' for c, u in units.items())
        if len(units) > 1:
            toml = "these units"
        if self.source.lower().endswith(".toml"):
            return f"give {toml} in {self.source} (or {flag})"
        return f"give {flag} (or {toml} in a --log-map file)"

    def with_columns(
        self, names: Mapping[str, str] | None = None, source: str | None = None
    ) -> LogLayout:
        """This layout with the log names ``names`` (format column -> log
        column) over its own, said to come from ``source``."""
        return replace(
            self,
            columns=_over(self.columns, names, format_columns=self.format_columns),
            source=source or self.source,
        )

    def to_dict(self) -> dict:
        """The mapping as the JSON outputs list it (``comment`` only if given)."""
        return {
            "source": self.source,
            "delimiter": self.delimiter,
            "decimal": self.decimal,
            **({} if self.comment is None else {"comment": self.comment}),
            "ignore": list(self.ignore),
            "columns": {
                n: {"column": s.column, "unit": s.unit, "scale": s.scale}
                for n, s in self.columns.items()
            },
        }


#: The format's own CSV.
DEFAULT_LAYOUT = LogLayout(source="the format")


# -- from a file and flags -------------------------------------------------------
def _delimiter(text: str, where: str) -> str:
    d = _DELIMITER_WORDS.get(text.strip().lower(), text) if len(text) != 1 else text
    if d not in _DELIMITERS:
        raise MeasurementError(f"{where}: delimiter {text!r} is not one of , ; tab | space")
    return d


def _source(
    name: str, value: object, where: str, format_columns: Mapping[str, str] = RUN_COLUMNS
) -> ColumnSource:
    if name not in format_columns:
        raise MeasurementError(
            f"{where}: {name!r} is not a column of the format (one of {', '.join(format_columns)})"
        )
    si = format_columns[name]
    if isinstance(value, str):
        return ColumnSource(value.strip(), si)
    if not isinstance(value, dict):
        raise MeasurementError(
            f"{where}: columns.{name} must be a log column name or a table {{column, unit, scale}}"
        )
    unknown = [k for k in value if k not in ("column", "unit", "scale")]
    if unknown:
        raise MeasurementError(
            f"{where}: columns.{name}: unknown key {unknown[0]!r} (column, unit, scale)"
        )
    column = value.get("column", name)
    unit = value.get("unit", si)
    scale = value.get("scale", 1.0)
    if not isinstance(column, str) or not column.strip():
        raise MeasurementError(f"{where}: columns.{name}.column must be a non-empty string")
    if not isinstance(unit, str):
        raise MeasurementError(f"{where}: columns.{name}.unit must be a string")
    if isinstance(scale, bool) or not isinstance(scale, int | float):
        raise MeasurementError(f"{where}: columns.{name}.scale must be a number")
    return ColumnSource(column.strip(), unit.strip(), float(scale))


def read_log_map(path: str | Path, format_columns: Mapping[str, str] = RUN_COLUMNS) -> dict:
    """The entries of a log-map TOML file (checked key by key; see the module)
    as keyword arguments of :class:`LogLayout`, for the format of
    ``format_columns``.

    Raises
    ------
    MeasurementError
        One line naming the file and the key.
    """
    from hybridtable._files import read_user_toml

    where = str(path)
    raw = read_user_toml(path, MeasurementError)
    unknown = [k for k in raw if k not in _KEYS]
    if unknown:
        raise MeasurementError(f"{where}: unknown key {unknown[0]!r} (one of {', '.join(_KEYS)})")
    out: dict = {"source": where}
    for key in ("delimiter", "decimal", "comment"):
        if key in raw:
            if not isinstance(raw[key], str):
                raise MeasurementError(f"{where}: {key} must be a string")
            out[key] = _delimiter(raw[key], where) if key == "delimiter" else raw[key]
    if "ignore" in raw:
        ignore = raw["ignore"]
        if not isinstance(ignore, list) or not all(isinstance(i, str) for i in ignore):
            raise MeasurementError(f"{where}: ignore must be a list of log column names")
        out["ignore"] = tuple(i.strip() for i in ignore)
    columns = raw.get("columns", {})
    if not isinstance(columns, dict):
        raise MeasurementError(f"{where}: columns must be a table (format column = log column)")
    out["columns"] = {name: _source(name, v, where, format_columns) for name, v in columns.items()}
    return out


def parse_pairs(
    items: Iterable[str] | None,
    flag: str,
    value: str,
    format_columns: Mapping[str, str] = RUN_COLUMNS,
) -> dict[str, str]:
    """``FORMAT=VALUE`` items of ``flag`` (each may hold several, comma
    separated) as ``{format_column: value}``.

    Raises
    ------
    MeasurementError
        For an item without ``=``, an unknown format column, or one given twice.
    """
    pairs: dict[str, str] = {}
    for item in items or ():
        for part in str(item).split(","):
            part = part.strip()
            if not part:
                continue
            if "=" not in part:
                raise MeasurementError(
                    f"{flag} item {part!r} must be FORMAT_COLUMN={value} "
                    f"(format columns: {', '.join(format_columns)})"
                )
            fmt, given = (s.strip() for s in part.split("=", 1))
            if fmt not in format_columns:
                raise MeasurementError(
                    f"{flag}: {fmt!r} is not a column of the format "
                    f"(one of {', '.join(format_columns)})"
                )
            if not given:
                raise MeasurementError(f"{flag}: empty {value.lower().replace('_', ' ')} for {fmt}")
            if fmt in pairs:
                raise MeasurementError(f"{flag}: {fmt} is mapped twice")
            pairs[fmt] = given
    return pairs


def log_layout(
    log_map: str | Path | None = None,
    column_map: Iterable[str] | Mapping[str, str] | None = None,
    units: Iterable[str] | Mapping[str, str] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    comment: str | None = None,
    ignore: Iterable[str] | None = None,
    format_columns: Mapping[str, str] = RUN_COLUMNS,
) -> LogLayout:
    """The layout of a log from a ``--log-map`` file and the flags that
    override its entries (``--column-map FORMAT=LOG``, ``--unit FORMAT=UNIT``,
    ``--delimiter``, ``--decimal``, ``--comment``, ``--ignore-column``); with
    none of them, the format's own CSV (:data:`DEFAULT_LAYOUT` for the 1-D
    format; ``format_columns`` names another's columns and units).

    Raises
    ------
    MeasurementError
        One line naming the file or flag and the entry at fault.
    """
    if log_map is None and not any((column_map, units, delimiter, decimal, comment, ignore)):
        if format_columns is RUN_COLUMNS:
            return DEFAULT_LAYOUT
        return LogLayout(source="the format", format_columns=format_columns)
    kwargs = read_log_map(log_map, format_columns) if log_map is not None else {}
    columns: dict[str, ColumnSource] = dict(kwargs.get("columns", {}))
    names = column_map if isinstance(column_map, Mapping) else None
    names = (
        dict(names)
        if names is not None
        else parse_pairs(column_map, "--column-map", "LOG_COLUMN", format_columns)
    )
    given_units = units if isinstance(units, Mapping) else None
    if given_units is None:
        given_units = parse_pairs(units, "--unit", "UNIT", format_columns)
    flags = [
        f
        for f, v in (
            ("--column-map", names),
            ("--unit", given_units),
            ("--delimiter", delimiter),
            ("--decimal", decimal),
            ("--comment", comment),
            ("--ignore-column", list(ignore or ())),
        )
        if v
    ]
    where = " and ".join([str(log_map)] * (log_map is not None) + flags) or "the format"
    for fmt, unit in given_units.items():
        known = _units_of(fmt, format_columns)
        if unit not in known:
            raise MeasurementError(
                f"--unit: unknown unit {unit!r} for {fmt} (one of {', '.join(known)})"
            )
    kwargs["columns"] = _over(columns, names, given_units, format_columns)
    kwargs["format_columns"] = format_columns
    kwargs["source"] = where
    if delimiter is not None:
        kwargs["delimiter"] = _delimiter(delimiter, "--delimiter")
    if decimal is not None:
        kwargs["decimal"] = decimal
    if comment is not None:
        kwargs["comment"] = comment
    if ignore:
        kwargs["ignore"] = tuple(kwargs.get("ignore", ())) + tuple(i.strip() for i in ignore)
    return LogLayout(**kwargs)
