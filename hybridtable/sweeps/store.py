"""The campaign's Parquet file: one row per run, the spec in its metadata.

Columns, in order: ``run``, ``point``, ``sample``, ``seed``; one per swept
input, named as the loop's parameters; ``compensator``; one per metric;
``status``, ``message``, ``engine``, ``seconds``. Rows are sorted by ``run``.
The file's key-value metadata ``hybridtable.sweep`` holds the spec (JSON), its
fingerprint and the tool's version, so a campaign can be resumed only from a
file of the same spec, and a file says what made it.

Every write replaces the whole file through a temporary file and a rename:
whatever kills the campaign, the file on disk is a valid Parquet file of the
runs finished at its last write.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from hybridtable.errors import ParameterError
from hybridtable.sweeps.metrics import METRICS
from hybridtable.sweeps.plan import SweepSpec
from hybridtable.sweeps.runner import ID_COLUMNS

__all__ = [
    "RESULTS_FORMAT",
    "METADATA_KEY",
    "TIMING_COLUMNS",
    "results_schema",
    "write_results",
    "read_results",
    "read_metadata",
]

#: Format name in the metadata.
RESULTS_FORMAT = "hybridtable-sweep-results/1"

#: The metadata key of the file.
METADATA_KEY = b"hybridtable.sweep"

#: Columns that depend on the machine, not on the spec.
TIMING_COLUMNS: tuple[str, ...] = ("seconds",)

_TYPES = {"number": pa.float64(), "text": pa.string(), "bool": pa.bool_()}


def results_schema(spec: SweepSpec) -> pa.Schema:
    """The Parquet schema of ``spec``'s results, with its metadata."""
    cols = [(name, pa.int64()) for name in ID_COLUMNS]
    cols += [(name, _TYPES[spec.input(name).kind]) for name in spec.swept if name != "compensator"]
    cols.append(("compensator", pa.string()))
    cols += [(m, _TYPES[METRICS[m].kind]) for m in spec.metrics]
    cols += [
        ("status", pa.string()),
        ("message", pa.string()),
        ("engine", pa.string()),
        ("seconds", pa.float64()),
    ]
    meta = {
        "format": RESULTS_FORMAT,
        "fingerprint": spec.fingerprint(),
        "spec": spec.to_json(),
        "tool_version": _tool_version(),
    }
    return pa.schema(cols, metadata={METADATA_KEY: json.dumps(meta, sort_keys=True)})


def _tool_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("hybridtable")
    except PackageNotFoundError:
        return "unknown"


def write_results(
    path: str | Path, spec: SweepSpec, rows: Iterable[dict[str, Any]], replace: bool | None = None
) -> int:
    """Write ``rows`` (any order) sorted by run, atomically; return their count.
    ``replace``: whether an existing file is replaced (default: the command's
    ``--force``, :func:`~hybridtable._files.overwrite_policy`)."""
    from hybridtable._files import atomic_path

    schema = results_schema(spec)
    ordered = sorted(rows, key=lambda r: r["run"])
    table = pa.Table.from_pylist(ordered, schema=schema)
    with atomic_path(path, replace=replace) as tmp:
        pq.write_table(table, tmp, compression="zstd")
    return len(ordered)


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The ``hybridtable.sweep`` metadata of a results file.

    Raises
    ------
    ParameterError
        If the file is not a campaign's Parquet file.
    """
    try:
        meta = pq.read_schema(path).metadata or {}
    except (OSError, pa.ArrowException) as err:
        raise ParameterError(f"{path}: not a Parquet file ({' '.join(str(err).split())})") from None
    if METADATA_KEY not in meta:
        raise ParameterError(f"{path}: a Parquet file, but not the results of hybridtable sweep")
    try:
        data = json.loads(meta[METADATA_KEY])
    except ValueError:
        raise ParameterError(f"{path}: its hybridtable.sweep metadata is not JSON") from None
    if not isinstance(data, dict) or data.get("format") != RESULTS_FORMAT:
        raise ParameterError(f"{path}: not a {RESULTS_FORMAT} file")
    return data


def read_results(path: str | Path, spec: SweepSpec | None = None) -> pa.Table:
    """The results table of ``path``; with ``spec``, only if it is that spec's
    (same fingerprint).

    Raises
    ------
    ParameterError
        If the file is not a campaign's results, or another spec's.
    """
    meta = read_metadata(path)
    if spec is not None and meta.get("fingerprint") != spec.fingerprint():
        raise ParameterError(
            f"{path}: holds the runs of another spec ({meta.get('spec', {}).get('name')!r}, "
            "its runs or metrics differ): give --force to start over, or another --out"
        )
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as err:
        raise ParameterError(f"{path}: unreadable ({' '.join(str(err).split())})") from None
    if (
        spec is not None
        and table.schema.remove_metadata() != results_schema(spec).remove_metadata()
    ):
        raise ParameterError(f"{path}: its columns are not those of this spec")
    return table
