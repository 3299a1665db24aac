"""The ``hybridtable`` command-line tool.

Every command has ``--help`` and ``--json FILE``. Bad input (a parameter out of
range, a malformed file) prints one line ``hybridtable: error: ...`` to stderr
and exits with code 2, never a traceback.

Commands are registered by the modules of :mod:`hybridtable.commands`: each provides ``register(subparsers)``
adding its sub-parser with ``set_defaults(func=...)``; ``func(args)`` returns
the exit code.
"""

from __future__ import annotations

import argparse
import sys

from hybridtable.commands import (
    compare,
    compensators,
    diagnose,
    effects,
    margins,
    reproduce,
    simulate,
)
from hybridtable.errors import CommandError, ParameterError, SimulationError

__all__ = [
    "main",
    "COMMANDS",
    "build_parser",
]


#: Modules that register sub-commands, in the order ``--help`` lists them.
#: Each keeps its heavy imports inside ``run`` so that ``--help`` starts fast.
COMMANDS = (simulate, reproduce, compare, diagnose, effects, compensators, margins)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="hybridtable",
        description="Hybrid-simulation motion tables: delay compensation, margins, measurements.",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for command in COMMANDS:
        command.register(sub)
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
