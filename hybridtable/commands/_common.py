"""Helpers every command uses: number parsing, JSON output (atomic), the run
inputs of the commands that read recorded runs, and the checks that no output
replaces an input or a user's folder."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from hybridtable._files import regular_file_problem, writable_problem
from hybridtable.commands._json import command_inputs, note_unset, write_json
from hybridtable.errors import CommandError

__all__ = [
    "number_type",
    "range_words",
    "number_list",
    "integer_type",
    "SEED_RANGE",
    "flag_words",
    "UNIT_METAVARS",
    "write_json",
    "command_inputs",
    "note_unset",
    "input_paths",
    "read_run_arguments",
    "add_axial_argument",
    "log_layout_of",
    "log_map_entry",
    "add_run_arguments",
    "add_log_arguments",
    "check_outputs",
    "declared_inputs",
    "add_force_argument",
    "check_suffix",
    "figure_suffixes",
]


#: ``argparse`` metavar of an option by its unit.
UNIT_METAVARS: dict[str, str] = {
    "s": "SECONDS",
    "Hz": "HZ",
    "N/m": "N_PER_M",
    "N s/m": "N_S_PER_M",
    "m/s": "M_PER_S",
    "m": "METRES",
    "N": "NEWTONS",
    "1": "RATIO",
}

_RANGES = {
    ">0": (lambda x: x > 0.0 and math.isfinite(x), "> 0"),
    ">=0": (lambda x: x >= 0.0 and math.isfinite(x), ">= 0"),
    ">0|inf": (lambda x: x > 0.0, "> 0 (or inf)"),
    "any": (math.isfinite, "finite"),
    "(-1,1)": (lambda x: -1.0 < x < 1.0, "in (-1, 1)"),
}


def _range(accepted: str, unit: str) -> tuple[Any, str, str]:
    """(check, words, unit) of a range code of :data:`_RANGES` or a quantity
    of :data:`hybridtable.limits.LIMITS` (whose unit wins)."""
    from hybridtable.limits import LIMITS

    if accepted in LIMITS:
        limit = LIMITS[accepted]
        return limit.contains, limit.words(unit=False), limit.unit
    if ".." in accepted:  # "low..high", both included
        low, high = (float(x) for x in accepted.split(".."))
        return (lambda x: low <= x <= high), f"{low:g} to {high:g}", unit
    check, words = _RANGES[accepted]
    return check, words, unit


def number_type(accepted: str, unit: str = "1"):
    """argparse type: a float in the range ``accepted``: a range code (``">0"``,
    ``">=0"``, ``">0|inf"``, ``"any"``, ``"(-1,1)"``, ``"LOW..HIGH"`` both included) or the name of a quantity with a
    plausible range (``"sensor_delay_s"``, :data:`hybridtable.limits.LIMITS`, whose
    unit is used). argparse names the flag in the error, e.g.
    ``argument --sensor-delay-s: must be 0 to 1 [s] (got 1e300)``."""
    check, words, unit = _range(accepted, unit)
    unit_text = "" if unit == "1" else f" [{unit}]"

    def number(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if math.isinf(value) and "inf" not in text.lower():
            raise argparse.ArgumentTypeError(f"too large (got {text[:20]}...)")
        if math.isnan(value) or not check(value):
            raise argparse.ArgumentTypeError(f"must be {words}{unit_text} (got {text[:40]})")
        return value

    number.__name__ = "number"
    return number


#: The seeds numpy's generators accept from a command line (0 to 2**32 - 1).
SEED_RANGE: tuple[int, int] = (0, 2**32 - 1)


def integer_type(low: int, high: int):
    """argparse type: a whole number from ``low`` to ``high`` (both included);
    argparse names the flag in the error, e.g.
    ``argument --workers: must be a whole number from 1 to 256 (got 0)``."""

    def integer(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"must be a whole number from {low} to {high} (got {text.strip()})"
            )
        return value

    integer.__name__ = "integer"
    return integer


def flag_words(text: str, fields: Iterable[str]) -> str:
    """``text`` with every whole word among ``fields`` (``sensor_delay_s``) written
    as its flag (``--sensor-delay-s``): a library's message in the command line's
    words. Use it on the messages of one call whose fields the flags set."""
    names = sorted(set(fields), key=len, reverse=True)
    if not names:
        return text
    pattern = re.compile(r"(?<![\w.-])(" + "|".join(map(re.escape, names)) + r")(?![\w-])")
    return pattern.sub(lambda m: "--" + m.group(1).replace("_", "-"), text)


def number_list(accepted: str = ">0", unit: str = "1"):
    """argparse type: a comma-separated list of numbers, each in the range
    ``accepted`` of :func:`number_type` (``1000,5000``)."""
    one = number_type(accepted, unit)

    def numbers(text: str) -> tuple[float, ...]:
        items = [x.strip() for x in text.split(",") if x.strip()]
        if not items:
            raise argparse.ArgumentTypeError("empty list")
        return tuple(one(x) for x in items)

    numbers.__name__ = "numbers"
    return numbers


def range_words(accepted: str) -> str:
    """The words of a range of :func:`number_type` (``"> 0"``, ``"0 to 1"``)."""
    return _range(accepted, "1")[1]


def read_run_arguments(args: argparse.Namespace, tail_s: float | None = None):
    """The runs of ``RUN...`` read through :func:`log_layout_of`, every long
    log split into its contact events
    (:func:`hybridtable.measurement.events.split_runs`, each cut ``tail_s``
    after its contact if given): ``(runs, splits, layout)``."""
    from hybridtable.measurement.events import split_runs
    from hybridtable.measurement.run_reader import read_runs

    if getattr(args, "axial", False):
        return _axial_runs(args, tail_s)
    layout = log_layout_of(args)
    runs, splits = split_runs(read_runs(args.runs, layout=layout), tail_s)
    return runs, splits, layout


def _axial_runs(args: argparse.Namespace, tail_s: float | None):
    """``--axial``: 6-DoF runs on the docking axis read as the 1-D runs they
    are (:func:`hybridtable.six_dof.axial.axial_run`), with the 1-D channels'
    checks."""
    from hybridtable.measurement.channels import check_channels
    from hybridtable.measurement.events import split_runs
    from hybridtable.six_dof.axial import axial_run
    from hybridtable.six_dof.run6 import RUN6_COLUMNS, read_runs6

    layout = log_layout_of(args, RUN6_COLUMNS)
    runs = [axial_run(r) for r in read_runs6(args.runs, layout)]
    for r in runs:
        check_channels(r)
    runs, splits = split_runs(runs, tail_s)
    return runs, splits, layout


def add_axial_argument(parser: argparse.ArgumentParser) -> None:
    """``--axial``: read 6-DoF runs on the docking axis as 1-D runs."""
    parser.add_argument(
        "--axial",
        action="store_true",
        help="6-DoF runs (hybridtable-run6/1) on the docking axis, read as the 1-D runs they "
        "are (the z components: p = pz, f = -fz), for the 1-D tools (default: off; a run off "
        "the axis is refused)",
    )


def log_map_entry(layout, runs) -> dict | None:
    """The ``log_map`` entry of a command's JSON: the mapping ``layout`` the
    logs were read with and each log's columns not read; ``None`` for logs in
    the format's own CSV."""
    skipped = {str(r.csv_path): list(r.skipped_columns) for r in runs if r.skipped_columns}
    if layout.plain and not skipped:
        return None
    return {**layout.to_dict(), "skipped_columns": skipped}


def log_layout_of(args: argparse.Namespace, format_columns=None):
    """How the logs of ``RUN...`` map to the format (the 1-D format's, else
    the one of ``format_columns``): the ``--log-map`` file and the flags over
    it (:func:`hybridtable.measurement.log_layout.log_layout`)."""
    from hybridtable.measurement.log_layout import log_layout
    from hybridtable.measurement.run_format import RUN_COLUMNS

    return log_layout(
        format_columns=RUN_COLUMNS if format_columns is None else format_columns,
        log_map=args.log_map,
        column_map=args.column_map,
        units=args.unit,
        delimiter=args.delimiter,
        decimal=args.decimal,
        comment=args.comment,
        ignore=args.ignore_column,
    )


def input_paths(runs) -> list[Path]:
    """The files the recorded ``runs`` were read from (resolved), which no output may replace."""
    return [p.resolve() for r in runs for p in (r.csv_path, r.json_path) if p is not None]


def declared_inputs(args: argparse.Namespace) -> list[Path]:
    """The files a command's flags name as inputs: ``--model``, ``--tables``,
    ``--log-map`` and the ``.py`` files of ``--plugin`` (resolved; those that exist)."""
    paths = [getattr(args, name, None) for name in ("model", "tables", "log_map")]
    for text in getattr(args, "plugin", None) or ():
        head = str(text).rsplit(":", 1)[0]  # ./backlash.py:EFFECT
        if head.endswith(".py"):
            paths.append(head)
    return [Path(p).resolve() for p in paths if p and Path(p).is_file()]


#: Names the output folders write (reports, figures, recorded runs): an output
#: file of the same command with such a name inside such a folder would be
#: replaced by it.
FOLDER_OUTPUT_NAMES = ("report.md", "report.html", "truth.json", "*.png", "run*.csv", "run*.json")


def _folder_would_write(d: Path, target: Path) -> bool:
    import fnmatch

    return target.parent == d and any(
        fnmatch.fnmatch(target.name, pattern) for pattern in FOLDER_OUTPUT_NAMES
    )


def _check_distinct(args, files: Mapping, folders: Mapping) -> None:
    """Refuse two outputs of one command that are the same file, or a file an
    output folder writes (one would silently replace the other). The outputs
    of earlier calls of this command are remembered on ``args``."""
    seen: dict[Path, str] = dict(getattr(args, "_outputs_seen", {}))
    dirs: dict[Path, str] = dict(getattr(args, "_folders_seen", {}))
    for flag, path in files.items():
        if path is None or str(path) == "-":
            continue
        target = Path(path).resolve()
        if target in seen and seen[target] != flag:
            raise CommandError(f"{flag} and {seen[target]} name the same file {path}")
        for d, other in dirs.items():
            if _folder_would_write(d, target):
                raise CommandError(f"{flag} {path}: the {other} folder writes that file")
        seen[target] = flag
    for flag, path in folders.items():
        if path is None:
            continue
        d = Path(path).resolve()
        for target, other in seen.items():
            if _folder_would_write(d, target):
                raise CommandError(f"{other} {target}: the {flag} folder writes that file")
        dirs[d] = flag
    args._outputs_seen, args._folders_seen = seen, dirs


def check_outputs(
    args: argparse.Namespace,
    inputs: Iterable[Path] = (),
    *,
    files: Mapping[str, str | Path | None] | None = None,
    folders: Mapping[str, str | Path | None] | None = None,
) -> None:
    """The one output policy of every command, checked before any work.

    An existing output is replaced only with ``--force``; an input (a run's CSV
    or JSON, a model file, the tables, a plug-in's file) is never written
    over, with or without it; an output that cannot be written (a parent that
    is a file, a read-only folder) is refused before anything is computed.

    Parameters
    ----------
    args
        The command's arguments: ``args.force``, and the inputs its flags name
        (:func:`declared_inputs`).
    inputs
        Other files the command reads (e.g. :func:`input_paths` of its runs).
    files
        ``{flag: path}`` of the output files (``None`` or ``-`` for stdout:
        not checked), e.g. ``{"--json": args.json}``.
    folders
        ``{flag: path}`` of the output folders (``--report DIR``): a folder
        that holds files is written into, its files of the same names replaced,
        only with ``--force``.

    Raises
    ------
    CommandError
        One line naming the flag: the output is an input, a file where a folder
        is wanted (or the other way round), cannot be written, or exists and
        ``--force`` is not given.
    """
    force = bool(getattr(args, "force", False))
    inputs = {Path(p).resolve() for p in inputs} | set(declared_inputs(args))
    _check_distinct(args, files or {}, folders or {})
    for flag, path in (files or {}).items():
        if path is None or str(path) == "-":
            continue
        problem = writable_problem(path)
        if problem:
            raise CommandError(f"{flag} {path}: cannot write it ({problem})")
        target = Path(path).resolve()
        if target in inputs:
            raise CommandError(f"{flag} {path} is one of the input files; not writing over it")
        if target.is_dir():
            raise CommandError(f"{flag} {path} is a folder; give a file name")
        kind = regular_file_problem(target)
        if kind is not None and kind != "no such file":  # a FIFO, a device, a socket
            raise CommandError(f"{flag} {path} is {kind}; not writing over it")
        if target.exists() and not force:
            raise CommandError(f"{flag} {path} exists; give --force to replace it")
    for flag, path in (folders or {}).items():
        if path is None:
            continue
        problem = writable_problem(path, folder=True) or writable_problem(path)
        if problem:
            raise CommandError(f"{flag} {path}: cannot write into it ({problem})")
        d = Path(path).resolve()
        if d.exists() and not d.is_dir():
            raise CommandError(f"{flag} {path} is a file, not a folder")
        if any(d == p.parent or d in p.parents for p in inputs):
            raise CommandError(f"{flag} {path} holds input files; choose another folder")
        if d.is_dir() and any(d.iterdir()) and not force:
            raise CommandError(
                f"{flag} {path} is not empty; choose a new folder, or give --force to "
                "write into it (its files of the same names are replaced)"
            )


def check_suffix(flag: str, path: str | Path | None, suffixes: Iterable[str]) -> None:
    """Refuse an output file whose suffix is not one of ``suffixes`` (lower
    case, with the dot), before any work: ``--plot out.txt``.

    Raises
    ------
    CommandError
        One line naming the flag and the suffixes it writes.
    """
    if path is None or str(path) == "-":
        return
    allowed = sorted(set(suffixes))
    if Path(path).suffix.lower() not in allowed:
        raise CommandError(
            f"{flag} {path}: writes {', '.join(s.lstrip('.') for s in allowed)} files; "
            "give a file name with one of these suffixes"
        )


def figure_suffixes() -> list[str]:
    """The file suffixes matplotlib writes figures in (``.png``, ``.pdf``, ...)."""
    from matplotlib.figure import Figure

    return ["." + s for s in Figure().canvas.get_supported_filetypes()]


def add_force_argument(parser: argparse.ArgumentParser) -> None:
    """``--force``: the one switch by which a command replaces existing outputs."""
    parser.add_argument(
        "--force",
        action="store_true",
        help="replace existing outputs (without it, an existing output file or a "
        "non-empty output folder is an error and nothing is written)",
    )


def add_log_arguments(parser: argparse.ArgumentParser) -> None:
    """How a rig's own log maps to the format: ``--log-map`` and the flags
    over it (:func:`log_layout_of` reads them)."""
    log = parser.add_argument_group(
        "a rig's own log (docs/run-format.md, 'Reading a rig's own log'; each flag "
        "overrides the --log-map file's entry)"
    )
    log.add_argument(
        "--log-map",
        metavar="FILE",
        help="a TOML file saying how the logs map to the format: columns, units, scale, "
        "delimiter, decimal mark, comment prefix, columns to ignore",
    )
    log.add_argument(
        "--column-map",
        metavar="FORMAT=LOG",
        action="append",
        default=[],
        help="read the format's column FORMAT from the log's column LOG (repeatable, or "
        "comma separated), e.g. --column-map f_mea_n=force,time_s=t",
    )
    log.add_argument(
        "--unit",
        metavar="FORMAT=UNIT",
        action="append",
        default=[],
        help="the unit the log holds a column in (repeatable, or comma separated), e.g. "
        "--unit time_s=ms,f_mea_n=kN; time s/ms/us, positions m/cm/mm/um, forces N/kN/mN, "
        "velocity m/s, cm/s, mm/s (default: the format's SI unit)",
    )
    log.add_argument(
        "--delimiter",
        metavar="C",
        help="the log's cell delimiter: , ; | tab or space (default: ,)",
    )
    log.add_argument(
        "--decimal",
        metavar="C",
        choices=(".", ","),
        help="the log's decimal mark, . or , (default: .; , needs another delimiter)",
    )
    log.add_argument(
        "--comment",
        metavar="PREFIX",
        help="skip the log's lines that start with PREFIX, e.g. '#' (default: none)",
    )
    log.add_argument(
        "--ignore-column",
        metavar="NAME",
        action="append",
        default=[],
        help="a log column not to read (repeatable; a column no format column is read "
        "from is skipped anyway)",
    )


def add_run_arguments(parser: argparse.ArgumentParser, report: str) -> None:
    """The inputs and outputs of a command that reads recorded runs: ``RUN...``,
    ``--json``, ``--report`` (``report`` says what it writes) and how a rig's
    own log maps to the format (``--log-map`` and its flags, :func:`log_layout_of`)."""
    parser.add_argument("runs", nargs="+", metavar="RUN", help="a run's .csv or .json, or a folder")
    parser.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    parser.add_argument("--report", metavar="DIR", help=report)
    add_log_arguments(parser)
