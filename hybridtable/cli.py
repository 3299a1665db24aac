"""The ``hybridtable`` command-line tool.

Every command has ``--help`` and ``--json FILE``. Bad input (a parameter out of
range, a malformed file) prints one line ``hybridtable: error: ...`` to stderr
and exits with code 2, never a traceback.

Commands are registered by modules: each provides ``register(subparsers)``
adding its sub-parser with ``set_defaults(func=...)``; ``func(args)`` returns
the exit code.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
from pathlib import Path
from typing import Any

from hybridtable._validation import ParameterError
from hybridtable.simulation import SimulationError

__all__ = ["main", "CommandError", "write_json", "parse_float", "COMMAND_MODULES"]

#: Modules that register sub-commands, in the order ``--help`` lists them.
COMMAND_MODULES: tuple[str, ...] = (
    "hybridtable.commands.simulate",
    "hybridtable.commands.reproduce",
    "hybridtable.commands.compare",
    "hybridtable.commands.diagnose",
    "hybridtable.commands.compensators",
    "hybridtable.commands.margins",
)


class CommandError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


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


def write_json(path: str | Path, data: Any) -> None:
    """Write ``data`` as JSON (NaN -> null, inf -> "inf"); ``-`` is stdout."""
    text = json.dumps(_jsonable(data), indent=2)
    if str(path) == "-":
        sys.stdout.write(text + "\n")
        return
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="hybridtable",
        description="Hybrid-simulation motion tables: delay compensation, margins, measurements.",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hybridtable`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ParameterError, CommandError) as err:
        print(f"hybridtable {args.command}: error: {err}", file=sys.stderr)
        return 2
    except SimulationError as err:
        print(f"hybridtable {args.command}: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hybridtable: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
