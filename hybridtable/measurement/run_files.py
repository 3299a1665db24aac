"""Which files are runs: a run's ``.csv`` or ``.json`` names its pair, a
folder every pair in it (:func:`find_run_files`, used by
:func:`hybridtable.measurement.run_reader.read_runs`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from hybridtable._files import regular_file_problem
from hybridtable.errors import MeasurementError
from hybridtable.measurement.run_format import FORMAT

__all__ = ["find_run_files"]


def _looks_like_run(path: Path, formats: Sequence[str]) -> bool:
    """True if ``path`` is a JSON object with one of ``formats`` as its ``format``."""
    if regular_file_problem(path):
        return False
    try:
        raw = json.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError, RecursionError):
        return False
    return isinstance(raw, dict) and raw.get("format") in formats


def find_run_files(
    paths: Sequence[str | Path], formats: Sequence[str] = (FORMAT,)
) -> list[tuple[Path, Path]]:
    """The ``(csv, json)`` pairs named by ``paths``: a CSV or JSON file names its
    pair, a folder every pair in it (sorted by name, not recursive). A JSON
    file alone in a folder is a run without its CSV if its ``format`` is one of
    ``formats``, else another file (skipped).

    Raises
    ------
    MeasurementError
        For a missing path, a file of another kind, a folder without runs, a
        CSV or run JSON file in a folder without its partner (other JSON files
        in a folder, e.g. results of ``compare --json``, are ignored).
    """
    pairs: list[tuple[Path, Path]] = []
    if not paths:
        raise MeasurementError("no runs given")
    for raw in paths:
        p = Path(raw)
        if p.is_dir():
            try:
                names = list(p.iterdir())
            except OSError as err:
                raise MeasurementError(f"{p}: cannot list the folder ({err.strerror})") from None
            stems = sorted({q.stem for q in names if q.suffix in (".csv", ".json")})
            if not stems:
                raise MeasurementError(f"{p}: folder holds no runs (no .csv/.json pairs)")
            found = len(pairs)
            for stem in stems:
                c, j = p / f"{stem}.csv", p / f"{stem}.json"
                for q in (c, j):
                    problem = regular_file_problem(q)
                    if problem and problem != "no such file":
                        raise MeasurementError(f"{q}: {problem}")
                if not c.is_file():
                    if not _looks_like_run(j, formats):
                        continue  # another JSON file (e.g. results of compare)
                    raise MeasurementError(f"{j}: no {c.name} beside it")
                if not j.is_file():
                    raise MeasurementError(f"{c}: no {j.name} beside it")
                pairs.append((c, j))
            if len(pairs) == found:
                raise MeasurementError(f"{p}: folder holds no runs (no .csv/.json pairs)")
        elif p.is_file() or p.suffix in (".csv", ".json"):
            if p.suffix not in (".csv", ".json"):
                raise MeasurementError(f"{p}: not a run file (expected .csv or .json)")
            c, j = p.with_suffix(".csv"), p.with_suffix(".json")
            if not p.is_file():
                raise MeasurementError(f"{p}: no such file")
            other = j if p == c else c
            if not other.is_file():
                raise MeasurementError(f"{p}: no {other.name} beside it")
            pairs.append((c, j))
        else:
            raise MeasurementError(f"{p}: no such file or folder")
    seen: dict[Path, int] = {}
    unique = []
    for c, j in pairs:
        key = c.resolve()
        if key not in seen:
            seen[key] = len(unique)
            unique.append((c, j))
    return unique
