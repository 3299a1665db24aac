"""A rig engineer's own log of a run: the run's channels under other column
names, in other units, with extra columns, another delimiter, decimal commas
and comment lines, as ``docs/run-format.md`` ("Reading a rig's own log")
describes; with the mapping TOML and the equivalent command-line flags that
read it back.

Written from the documentation only: it reads a run with plain ``csv``/``json``
and ``numpy`` and imports nothing from ``hybridtable``, so the reader's tests
check the implementation against the spec, not against itself.

A log value is the run's SI value divided by its unit's factor and by the
column's ``scale`` (the reader multiplies by both), written with ``repr`` of
the float (decimal comma: the ``.`` replaced by ``,``), so the round trip is
exact to a few ulp.
"""

from __future__ import annotations

import csv
import json
import math
import random
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "EXTRA_KINDS",
    "FORMAT_COLUMNS",
    "NAME_POOLS",
    "UNITS",
    "Layout",
    "RigLog",
    "flags_of",
    "mapping_of",
    "random_layout",
    "read_log",
    "read_run",
    "to_toml",
    "write_log",
    "write_toml",
]

#: The format's columns, in the order of the spec's table.
FORMAT_COLUMNS = ("time_s", "p_des_m", "p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s")

#: Each format column's units and their factor to the format's SI unit.
UNITS: dict[str, dict[str, float]] = {
    "time_s": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "p_des_m": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "p_act_m": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "f_mea_n": {"N": 1.0, "kN": 1e3, "mN": 1e-3},
    "f_comp_n": {"N": 1.0, "kN": 1e3, "mN": 1e-3},
    "v_des_m_per_s": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
}

#: The format's own unit of each column.
SI_UNIT = {
    "time_s": "s",
    "p_des_m": "m",
    "p_act_m": "m",
    "f_mea_n": "N",
    "f_comp_n": "N",
    "v_des_m_per_s": "m/s",
}

#: The delimiters the spec allows.
DELIMITERS = (",", ";", "\t", "|", " ")

#: Log column names a rig's logger might use (no delimiter, comment or flag
#: syntax characters in them; none is a format column's name or another pool's).
NAME_POOLS: dict[str, tuple[str, ...]] = {
    "time_s": ("Zeit", "timestamp", "t_log", "clock"),
    "p_des_m": ("x_cmd", "pos_cmd", "table_cmd", "p_set"),
    "p_act_m": ("x_act", "pos_meas", "table_pos", "p_is"),
    "f_mea_n": ("F_sensor", "load", "Fz_meas", "force"),
    "f_comp_n": ("F_fed", "load_comp", "Fz_model", "f_comp"),
    "v_des_m_per_s": ("v_cmd", "vel", "v_model", "xdot"),
}

#: Kinds of extra column: a drifting temperature, a tick counter, a raw force
#: in ADC counts, a text status word.
EXTRA_KINDS = ("temperature", "tick", "raw_force", "text")

#: Extra columns of the random layouts (name, kind).
EXTRA_POOL = (
    ("temperature_c", "temperature"),
    ("tick", "tick"),
    ("f_raw", "raw_force"),
    ("T_amb", "temperature"),
    ("loop_count", "tick"),
)

#: Comment prefixes of the random layouts.
COMMENT_PREFIXES = ("#", "//", "%")


@dataclass(frozen=True)
class Layout:
    """How a rig's logger writes a run.

    ``columns``: format column -> log column name (default: the format's name);
    ``units``: format column -> unit (default: the format's unit, not written);
    ``scales``: format column -> scale (default 1, not written);
    ``extras``: extra columns as (name, kind) pairs, ``kind`` one of
    ``EXTRA_KINDS``; an extra may carry a format column's name if that column
    is read from another log column and the extra is in ``ignore``;
    ``ignore``: log columns listed under ``ignore`` / ``--ignore-column``;
    ``comment``: the comment prefix; ``comments_above``: comment lines above
    the header; ``comments_between``: comment lines among the data rows (and
    between the header and the first row);
    ``shuffle``: shuffle the log's columns (with ``seed``);
    ``explicit_defaults``: also write ``delimiter`` and ``decimal`` when they
    are the defaults, and each column's unit when it is the format's;
    ``joined_flags``: one comma-separated ``--column-map``/``--unit`` flag
    instead of one flag per column;
    ``seed``: draws the extra columns' values, the comment positions and the
    column order.
    """

    delimiter: str = ","
    decimal: str = "."
    comment: str | None = None
    comments_above: int = 0
    comments_between: int = 0
    columns: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    scales: dict[str, float] = field(default_factory=dict)
    extras: tuple[tuple[str, str], ...] = ()
    ignore: tuple[str, ...] = ()
    shuffle: bool = False
    explicit_defaults: bool = False
    joined_flags: bool = False
    seed: int = 0

    def __post_init__(self) -> None:
        if self.delimiter not in DELIMITERS:
            raise ValueError(f"delimiter {self.delimiter!r} is not one of {DELIMITERS}")
        if self.decimal not in (".", ","):
            raise ValueError(f"decimal {self.decimal!r} is not '.' or ','")
        if self.decimal == "," and self.delimiter == ",":
            raise ValueError("decimal ',' needs another delimiter")
        if (self.comments_above or self.comments_between) and not self.comment:
            raise ValueError("comment lines need a comment prefix")
        for table in (self.columns, self.units, self.scales):
            unknown = set(table) - set(FORMAT_COLUMNS)
            if unknown:
                raise ValueError(f"not format columns: {sorted(unknown)}")
        for name, unit in self.units.items():
            if unit not in UNITS[name]:
                raise ValueError(f"{name}: unit {unit!r} is not one of {sorted(UNITS[name])}")
        for name, scale in self.scales.items():
            if not math.isfinite(scale) or scale == 0.0:
                raise ValueError(f"{name}: scale {scale!r} is 0 or not finite")
        names = self.log_names()
        if len(set(names)) != len(names):
            raise ValueError(f"log column named twice: {names}")
        for extra, kind in self.extras:
            if kind not in EXTRA_KINDS:
                raise ValueError(f"extra column {extra!r}: unknown kind {kind!r}")
            if extra in FORMAT_COLUMNS and extra not in self.ignore:
                raise ValueError(f"extra column {extra!r} collides with a format column")
        if not set(self.ignore) <= {name for name, _ in self.extras}:
            raise ValueError("only extra columns can be ignored")
        for name in names:
            bad = set(name) & set(self.delimiter + "\"'=,")
            if bad or not name or (self.comment and name.startswith(self.comment)):
                raise ValueError(f"log column name {name!r} cannot be written in this layout")

    def log_name(self, column: str) -> str:
        """The log's name of format column ``column``."""
        return self.columns.get(column, column)

    def unit(self, column: str) -> str:
        return self.units.get(column, SI_UNIT[column])

    def scale(self, column: str) -> float:
        return float(self.scales.get(column, 1.0))

    def log_names(self) -> list[str]:
        """The log's columns before shuffling: the format's, then the extras."""
        return [self.log_name(c) for c in FORMAT_COLUMNS] + [name for name, _ in self.extras]


@dataclass(frozen=True)
class RigLog:
    """A written log: its CSV, the run's unchanged JSON, the mapping TOML, the
    mapping as a dict (as ``tomllib`` reads the TOML), the equivalent flags
    (``None`` when a scale other than 1 has no flag), the log's header and the
    log columns the format does not need."""

    csv: Path
    json: Path
    toml: Path
    mapping: dict
    flags: list[str] | None
    header: list[str]
    skipped: list[str]


# --- reading ------------------------------------------------------------------


def read_run(csv_path: Path | str) -> dict[str, np.ndarray]:
    """A run in the format: its CSV's columns as float arrays, in the file's
    column order."""
    with open(csv_path, newline="", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], rows[1:]
    return {
        name: np.array([float(row[i]) for row in body], dtype=float)
        for i, name in enumerate(header)
    }


def read_log(csv_path: Path | str, mapping: dict) -> dict[str, np.ndarray]:
    """Read a log with a mapping (a dict as ``tomllib`` reads the TOML), as the
    spec says: comment lines skipped above and below the header, cells split at
    ``delimiter``, decimal commas, each value times its unit's factor and then
    times ``scale``. Returns the format's six columns in SI units."""
    delimiter = mapping.get("delimiter", ",")
    decimal = mapping.get("decimal", ".")
    comment = mapping.get("comment")
    text = Path(csv_path).read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if not (comment and line.startswith(comment))]
    rows = list(csv.reader(lines, delimiter=delimiter))
    header, body = rows[0], rows[1:]
    out = {}
    for column in FORMAT_COLUMNS:
        entry = mapping.get("columns", {}).get(column, column)
        if isinstance(entry, str):
            entry = {"column": entry}
        name = entry.get("column", column)
        factor = UNITS[column][entry.get("unit", SI_UNIT[column])]
        scale = float(entry.get("scale", 1.0))
        i = header.index(name)
        values = [float(row[i].replace(decimal, ".")) for row in body]
        out[column] = np.array(values, dtype=float) * factor * scale
    return out


# --- the mapping --------------------------------------------------------------


def mapping_of(layout: Layout) -> dict:
    """The mapping that reads ``layout``'s log, as ``tomllib`` would read its
    TOML: top-level ``delimiter``, ``decimal``, ``comment``, ``ignore`` when
    not the defaults (or always with ``explicit_defaults``), and ``[columns]``
    with a plain name for a renamed column in the format's unit and a table
    ``{column, unit, scale}`` otherwise (without ``column`` when the log keeps
    the format's name)."""
    mapping: dict = {}
    if layout.explicit_defaults or layout.delimiter != ",":
        mapping["delimiter"] = layout.delimiter
    if layout.explicit_defaults or layout.decimal != ".":
        mapping["decimal"] = layout.decimal
    if layout.comment:
        mapping["comment"] = layout.comment
    if layout.ignore:
        mapping["ignore"] = list(layout.ignore)
    columns: dict = {}
    for column in FORMAT_COLUMNS:
        name = layout.log_name(column)
        entry: dict = {}
        if name != column:
            entry["column"] = name
        if column in layout.units and (
            layout.explicit_defaults or layout.units[column] != SI_UNIT[column]
        ):
            entry["unit"] = layout.units[column]
        if column in layout.scales and layout.scales[column] != 1.0:
            entry["scale"] = float(layout.scales[column])
        if set(entry) == {"column"}:
            columns[column] = name
        elif entry:
            columns[column] = entry
    if columns:
        mapping["columns"] = columns
    return mapping


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)  # 1.0, -1.0, 1e-05, inf, nan are TOML floats
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return (
            "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
        )
    raise TypeError(f"no TOML for {value!r}")


def _toml_key(key: str) -> str:
    if key and all(c.isalnum() or c in "_-" for c in key) and key.isascii():
        return key
    return json.dumps(key)


def to_toml(mapping: dict, title: str = "how this rig's logger writes a run") -> str:
    """The mapping as TOML text (top-level keys, then ``[columns]``)."""
    lines = [f"# {title}"]
    for key, value in mapping.items():
        if key != "columns":
            lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    if "columns" in mapping:
        lines += ["", "[columns]"]
        for key, value in mapping["columns"].items():
            lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def write_toml(mapping: dict, path: Path | str) -> Path:
    path = Path(path)
    path.write_text(to_toml(mapping), encoding="utf-8")
    return path


def flags_of(mapping: dict, joined: bool = False) -> list[str] | None:
    """The command-line flags equivalent to ``mapping`` (``--column-map``,
    ``--unit``, ``--delimiter``, ``--decimal``, ``--comment``,
    ``--ignore-column``), or ``None`` when it has a scale other than 1 (no flag
    gives a scale). ``joined``: one comma-separated ``--column-map`` and one
    ``--unit`` instead of one flag per column."""
    renames, units = [], []
    for column, entry in mapping.get("columns", {}).items():
        if isinstance(entry, str):
            entry = {"column": entry}
        if float(entry.get("scale", 1.0)) != 1.0:
            return None
        if "column" in entry:
            renames.append(f"{column}={entry['column']}")
        if "unit" in entry:
            units.append(f"{column}={entry['unit']}")
    flags: list[str] = []
    for option, items in (("--column-map", renames), ("--unit", units)):
        if joined and items:
            flags += [option, ",".join(items)]
        else:
            for item in items:
                flags += [option, item]
    for key, option in (("delimiter", "--delimiter"), ("decimal", "--decimal")):
        if key in mapping:
            flags += [option, mapping[key]]
    if "comment" in mapping:
        flags += ["--comment", mapping["comment"]]
    for name in mapping.get("ignore", []):
        flags += ["--ignore-column", name]
    return flags


# --- writing ------------------------------------------------------------------


def _number(value: float, decimal: str) -> str:
    text = repr(float(value))
    return text.replace(".", ",") if decimal == "," else text


def _extra_values(kind: str, columns: dict[str, np.ndarray], rng: random.Random) -> list:
    n = len(columns["time_s"])
    if kind == "temperature":
        start = 21.0 + rng.random()
        return [start + 0.002 * k + 0.01 * rng.gauss(0.0, 1.0) for k in range(n)]
    if kind == "tick":
        offset = rng.randrange(0, 100000)
        return [offset + k for k in range(n)]
    if kind == "raw_force":  # ADC counts: gain and offset of a load cell's amplifier
        gain, offset = 2.048 + rng.random(), 2048.0 + rng.randrange(-50, 50)
        return [offset + gain * f for f in columns["f_mea_n"]]
    if kind == "text":
        return ["CONTACT" if f > 10.0 else "FREE" for f in columns["f_mea_n"]]
    raise ValueError(kind)


def _cell(value, decimal: str) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, int | np.integer):
        return str(int(value))
    return _number(value, decimal)


def write_log(
    run_csv: Path | str,
    layout: Layout,
    out_dir: Path | str,
    *,
    stem: str | None = None,
    toml_path: Path | str | None = None,
) -> RigLog:
    """Write the run ``run_csv`` (its JSON beside it, same stem) as ``layout``'s
    log ``out_dir/STEM.csv``, copy the JSON unchanged to ``out_dir/STEM.json``
    and write the mapping to ``toml_path`` (default ``out_dir/STEM.toml``)."""
    run_csv = Path(run_csv)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = stem or run_csv.stem
    columns = read_run(run_csv)
    rng = random.Random(layout.seed)

    # Each log column's cells.
    cells: dict[str, list] = {}
    for column in FORMAT_COLUMNS:
        divisor = UNITS[column][layout.unit(column)] * layout.scale(column)
        cells[layout.log_name(column)] = [v / divisor for v in columns[column].tolist()]
    for name, kind in layout.extras:
        cells[name] = _extra_values(kind, columns, rng)
    header = layout.log_names()
    if layout.shuffle:
        rng.shuffle(header)

    d = layout.delimiter
    n = len(columns["time_s"])
    rows = [d.join(_cell(cells[name][k], layout.decimal) for name in header) for k in range(n)]
    lines = []
    for i in range(layout.comments_above):
        text = ("rig B logger export v2.3, channels: x_cmd; x_act; Fz", "operator: A. N. Other")[
            i % 2
        ]
        lines.append(f"{layout.comment} {text} ({i + 1})")
    lines.append(d.join(header))
    # Comment lines among the data rows: before row k (k = 0 is just below the
    # header), and possibly one after the last row.
    positions = sorted(rng.randrange(0, n + 1) for _ in range(layout.comments_between))
    j = 0
    for k in range(n + 1):
        while j < len(positions) and positions[j] == k:
            lines.append(f"{layout.comment} marker {j + 1}: operator note, tick {k}")
            j += 1
        if k < n:
            lines.append(rows[k])
    csv_path = out_dir / f"{stem}.csv"
    csv_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    json_path = out_dir / f"{stem}.json"
    shutil.copyfile(run_csv.with_suffix(".json"), json_path)

    mapping = mapping_of(layout)
    toml = write_toml(mapping, toml_path or out_dir / f"{stem}.toml")
    needed = {layout.log_name(c) for c in FORMAT_COLUMNS}
    return RigLog(
        csv=csv_path,
        json=json_path,
        toml=toml,
        mapping=mapping,
        flags=flags_of(mapping, joined=layout.joined_flags),
        header=header,
        skipped=[name for name in header if name not in needed],
    )


# --- random layouts -----------------------------------------------------------


def random_layout(seed: int, *, flags: bool = True) -> Layout:
    """A random layout drawn from ``seed``: delimiter, decimal comma, comments,
    renamed columns, units, extra columns, shuffled order; with ``flags=False``
    also a sign-flipped channel or a calibration scale (which no flag gives)."""
    rng = random.Random(seed)
    delimiter = rng.choice(DELIMITERS)
    decimal = "," if delimiter != "," and rng.random() < 0.6 else "."
    comment = rng.choice(COMMENT_PREFIXES) if rng.random() < 0.6 else None
    comments_above = rng.randint(1, 3) if comment else 0
    comments_between = rng.randint(0, 5) if comment else 0
    columns = {c: rng.choice(NAME_POOLS[c]) for c in FORMAT_COLUMNS if rng.random() < 0.7}
    units = {c: rng.choice(sorted(UNITS[c])) for c in FORMAT_COLUMNS if rng.random() < 0.7}
    scales: dict[str, float] = {}
    if not flags:
        flipped = rng.choice(FORMAT_COLUMNS[1:])
        scales[flipped] = -1.0
        others = [c for c in FORMAT_COLUMNS[1:] if c != flipped]
        scales[rng.choice(others)] = rng.choice((0.5, 1.25, 2.0, 0.8))
    extras = tuple(rng.sample(EXTRA_POOL, rng.randint(0, 3)))
    ignore = tuple(name for name, _ in extras if rng.random() < 0.4)
    return Layout(
        delimiter=delimiter,
        decimal=decimal,
        comment=comment,
        comments_above=comments_above,
        comments_between=comments_between,
        columns=columns,
        units=units,
        scales=scales,
        extras=extras,
        ignore=ignore,
        shuffle=rng.random() < 0.7,
        explicit_defaults=rng.random() < 0.3,
        joined_flags=rng.random() < 0.5,
        seed=seed,
    )
