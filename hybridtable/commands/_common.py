"""Helpers every command uses: number parsing, JSON output (atomic), the run
inputs of the commands that read recorded runs, and the checks that no output
replaces an input or a user's folder."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from hybridtable._files import write_text_atomic
from hybridtable.errors import CommandError

__all__ = [
    "parse_float",
    "write_json",
    "write_json_atomic",
    "input_paths",
    "add_run_arguments",
    "check_outputs",
]


def parse_float(text: str) -> float:
    """argparse type: a float ("inf" allowed, NaN refused by the parameter checks)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, float) and not math.isfinite(obj):
        return None if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if hasattr(obj, "tolist"):
        return _jsonable(obj.tolist())
    if hasattr(obj, "item"):
        return obj.item()
    return obj


def _json_text(data: Any) -> str:
    return json.dumps(_jsonable(data), indent=2) + "\n"


def write_json(path: str | Path, data: Any) -> None:
    """Write ``data`` as JSON (NaN -> null, inf -> "inf"); ``-`` is stdout."""
    text = _json_text(data)
    if str(path) == "-":
        sys.stdout.write(text)
        return
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def input_paths(runs) -> list[Path]:
    """The files the recorded ``runs`` were read from (resolved), which no output may replace."""
    return [p.resolve() for r in runs for p in (r.csv_path, r.json_path) if p is not None]


def check_outputs(
    json_path: str | None,
    report_dir: str | None,
    inputs: list[Path],
    command: str,
    report_marker: str,
) -> None:
    """Refuse outputs that would write over an input or a user's folder.

    ``report_marker`` is the file by which ``command``'s reports mark their
    folders.

    Raises
    ------
    CommandError
        If ``json_path`` is an input file or a folder, or ``report_dir`` is a
        file, holds an input, or is a non-empty folder not written by an
        earlier ``command --report``.
    """
    if json_path and json_path != "-":
        target = Path(json_path).resolve()
        if target in inputs:
            raise CommandError(f"--json {json_path} is one of the input files; not writing over it")
        if target.is_dir():
            raise CommandError(f"--json {json_path} is a folder")
    if report_dir:
        d = Path(report_dir).resolve()
        if d.exists() and not d.is_dir():
            raise CommandError(f"--report {report_dir} is a file, not a folder")
        if any(d == p.parent or d in p.parents for p in inputs):
            raise CommandError(f"--report {report_dir} holds input runs; choose another folder")
        if d.is_dir() and any(d.iterdir()) and not (d / report_marker).is_file():
            raise CommandError(
                f"--report {report_dir} is not empty and not an earlier {command} report; "
                "choose a new or empty folder"
            )


def write_json_atomic(path: str, data) -> None:
    """:func:`write_json` through a temporary file and a rename: a reader never
    sees half a file, and an error leaves the old one in place."""
    if path == "-":
        write_json(path, data)
        return
    write_text_atomic(path, _json_text(data))


def add_run_arguments(parser: argparse.ArgumentParser, report: str) -> None:
    """The inputs and outputs of a command that reads recorded runs: ``RUN...``,
    ``--json``, ``--report`` (``report`` says what it writes) and ``--column-map``."""
    parser.add_argument("runs", nargs="+", metavar="RUN", help="a run's .csv or .json, or a folder")
    parser.add_argument("--json", metavar="FILE", help="write the results as JSON (- for stdout)")
    parser.add_argument("--report", metavar="DIR", help=report)
    parser.add_argument(
        "--column-map",
        metavar="FORMAT=LOG",
        action="append",
        default=[],
        help="read the format's column FORMAT from the log's column LOG (repeatable, or "
        "comma separated), e.g. --column-map f_mea_n=force,time_s=t",
    )
