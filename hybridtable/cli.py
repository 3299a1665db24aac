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
import os
import sys

from hybridtable._files import command_outputs, overwrite_policy
from hybridtable.commands import (
    compare,
    compensators,
    diagnose,
    diagram,
    effects,
    explain,
    margins,
    reproduce,
    simulate,
    simulate6,
    sweep,
)
from hybridtable.commands._common import add_force_argument
from hybridtable.errors import CommandError, ParameterError, SimulationError, WriteError

__all__ = [
    "main",
    "COMMANDS",
    "build_parser",
]


#: Modules that register sub-commands, in the order ``--help`` lists them.
#: Each keeps its heavy imports inside ``run`` so that ``--help`` starts fast.
COMMANDS = (
    simulate,
    simulate6,
    reproduce,
    compare,
    diagnose,
    explain,
    effects,
    compensators,
    margins,
    sweep,
    diagram,
)


class _HelpFormatter(argparse.HelpFormatter):
    """Every option's help ends with its default, unless it says it already."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default is None
            or default is False
            or default == []
            or default == argparse.SUPPRESS
            or action.nargs == 0
            or not action.option_strings
        ):
            return text
        shown = f"{default:g}" if isinstance(default, float) else str(default)
        return f"{text} (default {shown})"


class _Parser(argparse.ArgumentParser):
    """One-line errors (exit 2); every command's ``--help`` shows its defaults."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def _flag_message(err: Exception, parser: argparse.ArgumentParser | None) -> str:
    """A parameter error in the words of the command line: a field named at the
    start of the message (``sensor_delay_s must be >= 0``) becomes its flag
    (``--sensor-delay-s must be >= 0``) when the command has that flag."""
    text = str(err)
    if parser is None:
        return text
    field = text.split(" ", 1)[0]
    flag = "--" + field.replace("_", "-")
    flags = {s for a in parser._actions for s in a.option_strings}
    if field.isidentifier() and flag in flags:
        return flag + text[len(field) :]
    return text


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("hybridtable")
    except PackageNotFoundError:  # run from a checkout without an install
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="hybridtable",
        description="Hybrid-simulation motion tables: delay compensation, margins, measurements.",
        epilog="Every command: --help (units, ranges, defaults), --json FILE (- for stdout), "
        "--force to replace an existing output. New here: docs/tutorial.md; first command: "
        "hybridtable simulate --compensator SDMDC.",
    )
    parser.add_argument(
        "--version", action="version", version=f"hybridtable {_version()}", help="print the version"
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for command in COMMANDS:
        command.register(sub)
    for command_parser in sub.choices.values():
        add_force_argument(command_parser)  # one overwrite policy for every command
    return parser


def _sub_parser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(name)
    return None


#: Longest error line the command line prints (a message quoting a user's
#: megabyte-long cell or column name is cut).
_MAX_ERROR_CHARS = 500


def _one_line(text: str) -> str:
    """``text`` on one line of at most :data:`_MAX_ERROR_CHARS` characters."""
    text = " ".join(str(text).split())
    if len(text) <= _MAX_ERROR_CHARS:
        return text
    return text[: _MAX_ERROR_CHARS - 30] + f"... ({len(text)} characters)"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hybridtable`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    stdout = sys.stdout
    sys.stdout = reader = _ReaderMayLeave(stdout)
    try:
        with overwrite_policy(bool(getattr(args, "force", False))), command_outputs():
            code = int(args.func(args) or 0)
        # The files are written; only what went to the console was lost.
        return 141 if reader.gone and getattr(args, "json", None) == "-" else code
    except (ParameterError, CommandError) as err:
        sub = _sub_parser(parser, args.command)
        text = _one_line(_flag_message(err, sub))
        print(f"hybridtable {args.command}: error: {text}", file=sys.stderr)
        return 2
    except (SimulationError, WriteError) as err:
        print(f"hybridtable {args.command}: error: {_one_line(str(err))}", file=sys.stderr)
        return 1
    except MemoryError:
        print(
            f"hybridtable {args.command}: error: out of memory (the input is too large for "
            "this machine)",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        print("hybridtable: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader (``| head``) closed stdout: stop quietly
        _silence(stdout)
        return 141
    except OSError as err:  # a write that no helper wrapped: still one line
        where = f" ({err.filename})" if getattr(err, "filename", None) else ""
        why = err.strerror or " ".join(str(err).split())
        print(f"hybridtable {args.command}: error: {_one_line(why + where)}", file=sys.stderr)
        return 1
    finally:
        sys.stdout = stdout


def _silence(stream) -> None:
    """Point ``stream``'s file descriptor at /dev/null (no second error when
    Python flushes it at exit)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
    except (OSError, ValueError):  # no descriptor (a test's captured stream)
        pass


class _ReaderMayLeave:
    """``sys.stdout`` for a command: when the reader (``| head -1``) closes the
    pipe, the console text stops and the command goes on to write its files
    (``--json FILE``, ``--report``) instead of dying half way."""

    def __init__(self, stream) -> None:
        self._stream = stream
        self.gone = False

    def write(self, text: str) -> int:
        if not self.gone:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._leave()
        return len(text)

    def flush(self) -> None:
        if not self.gone:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._leave()

    def _leave(self) -> None:
        self.gone = True
        _silence(self._stream)

    def __getattr__(self, name):
        return getattr(self._stream, name)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
