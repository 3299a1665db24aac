"""A command's JSON document: plain values (NaN -> null, inf -> "inf"), the
numbers it leaves unset said why, the inputs it was asked, written atomically
or to stdout."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from hybridtable._files import write_text_atomic

__all__ = ["command_inputs", "note_unset", "write_json"]


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


def _is_unset(value: Any) -> bool:
    """None, NaN or an infinity, or a list or array holding one."""
    if value is None:
        return True
    if isinstance(value, float):
        return not math.isfinite(value)
    if isinstance(value, str):
        return value in ("inf", "-inf", "nan")
    if isinstance(value, list | tuple) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else value
        items = items if isinstance(items, list) else [items]
        return any(_is_unset(v) for v in items)
    return False


def note_unset(document: dict, reasons: Mapping[str, str]) -> dict:
    """Say why values are missing or infinite: for every key of ``reasons`` whose
    value in ``document`` is None, NaN or infinite (or a list holding one), its
    reason is added to ``document["note"]`` (one string, sentences joined by
    "; "). A JSON reader then never meets a null or an infinity without a word
    why. Returns ``document``."""
    why = [text for key, text in reasons.items() if key in document and _is_unset(document[key])]
    if why:
        old = document.get("note")
        document["note"] = "; ".join(([old] if old else []) + why)
    return document


def command_inputs(args: argparse.Namespace) -> dict[str, Any]:
    """What the command was asked: its name and every option as parsed
    (defaults applied), as plain JSON values."""

    def plain(value: Any) -> Any:
        if value is None or isinstance(value, bool | int | float | str):
            return value
        if isinstance(value, list | tuple):
            return [plain(v) for v in value]
        if isinstance(value, dict):
            return {str(k): plain(v) for k, v in value.items()}
        return str(value)

    out: dict[str, Any] = {"command": getattr(args, "command", None)}
    for name, value in sorted(vars(args).items()):
        if name not in ("command", "func") and not name.startswith("_") and not callable(value):
            out[name] = plain(value)
    return out


def write_json(path: str | Path, data: Any, args: argparse.Namespace | None = None) -> None:
    """Write ``data`` as JSON (NaN -> null, inf -> "inf"); ``-`` is stdout.
    With the command's ``args``, a document (a dict) opens with ``inputs``:
    what it was asked (:func:`command_inputs`).

    A file is written through a temporary file and a rename: a reader never
    sees half a file, and an error leaves the old one in place."""
    if args is not None and isinstance(data, dict):
        data = {"inputs": command_inputs(args), **data}
    text = _json_text(data)
    if str(path) == "-":
        sys.stdout.write(text)
        return
    write_text_atomic(path, text)
