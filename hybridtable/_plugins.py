"""The one guard around a call into a user's code: a plug-in module's import,
an effect's functions (its ``apply``, its starts, its bounds), the systems and
loop changes they return, and the simulation that runs a user's systems.

Whatever the user's code does — raise any exception, call ``sys.exit``, return
NaN or infinity where a number is due — the user sees one line naming the
plug-in and what it did:

- an exception or ``sys.exit`` in a user's code, at set-up (import, an
  effect's functions) or while a run simulates (a user's system raising
  inside Drake): :class:`~hybridtable.errors.PluginError` naming the plug-in,
  or the user's file and line, exit 2 (the plug-in is bad); no fit takes it
  for a model that failed;
- a run that failed otherwise (Drake's own error, a NaN reaching the loop's
  laws): :func:`simulation_failure` makes a
  :class:`~hybridtable.errors.SimulationError`, exit 1 (the run failed).

What a user's code prints while it is called here goes to standard error, so
a command's ``--json -`` output stays JSON.

Our own errors raised on purpose by a user's code (a ``ParameterError`` for a
value it refuses) pass through unchanged. ``KeyboardInterrupt`` is never caught.
"""

from __future__ import annotations

import contextlib
import math
import sys
import traceback
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from hybridtable.errors import CommandError, ParameterError, PluginError, SimulationError

__all__ = [
    "PluginError",
    "Guarded",
    "call_user",
    "drake_system",
    "finite_numbers",
    "simulation_failure",
]

#: The folder of the package: a traceback frame outside it is a user's.
_PACKAGE = Path(__file__).resolve().parent

#: Our errors, which a user's code may raise on purpose: they pass unchanged.
_OURS = (ParameterError, CommandError, SimulationError)


def _what(err: BaseException) -> str:
    if isinstance(err, SystemExit):
        return f"called sys.exit({err.code!r})"
    text = str(err).strip()
    where = _user_frame(err)
    return f"raised {type(err).__name__}" + (f": {text}" if text else "") + where


def _user_frame(err: BaseException) -> str:
    """`` (FILE, line N)`` of the innermost frame outside the package, or ``""``."""
    frames = traceback.extract_tb(err.__traceback__)
    for frame in reversed(frames):
        try:
            inside = Path(frame.filename).resolve().is_relative_to(_PACKAGE)
        except (OSError, ValueError):
            inside = False
        if not inside and not frame.filename.startswith("<frozen"):
            return f" ({frame.filename}, line {frame.lineno})"
    return ""


def call_user(who: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)``, a user's function; any exception or
    ``sys.exit`` it raises becomes one :class:`PluginError` line naming ``who``.
    What it prints goes to standard error: a command's ``--json -`` stays JSON."""
    try:
        with contextlib.redirect_stdout(sys.stderr):
            return fn(*args, **kwargs)
    except _OURS:
        raise
    except KeyboardInterrupt:
        raise
    except BaseException as err:  # noqa: BLE001 - every failure of a user's code, SystemExit too
        raise PluginError(f"{who} {_what(err)}") from None


def finite_numbers(who: str, value: Any) -> Any:
    """``value`` if every number in it (a number, or a mapping or sequence of
    them) is finite; else a :class:`PluginError` naming ``who``."""
    if isinstance(value, Mapping):
        items = list(value.values())
    elif isinstance(value, str) or not isinstance(value, Iterable):
        items = [value]
    else:
        items = list(value)
    for x in items:
        try:
            ok = math.isfinite(float(x))
        except (TypeError, ValueError, OverflowError):
            raise PluginError(f"{who} returned {x!r:.80}, not a number") from None
        if not ok:
            raise PluginError(f"{who} returned {x!r}, not a finite number")
    return value


class Guarded:
    """A user's function called through :func:`call_user` (picklable, so a
    worker process can run it), its result checked by ``check`` when given."""

    def __init__(
        self,
        fn: Callable[..., Any],
        who: str,
        check: Callable[[str, Any], Any] | None = None,
    ) -> None:
        self.fn, self.who, self.check = fn, who, check

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        value = call_user(self.who, self.fn, *args, **kwargs)
        return value if self.check is None else self.check(self.who, value)

    def __repr__(self) -> str:
        return f"Guarded({self.fn!r}, {self.who!r})"


def drake_system(who: str, value: Any) -> Any:
    """``value`` if it is a Drake system (what a user's wrapper or compensator
    factory must return); else a :class:`PluginError` naming ``who``."""
    from pydrake.systems.framework import System

    if not isinstance(value, System):
        raise PluginError(f"{who} returned {type(value).__name__}, not a Drake system")
    return value


def simulation_failure(err: BaseException, what: str = "simulation failed") -> Exception:
    """The error of a run that a system's callback (Drake's, ours or a user's)
    ended with ``err``, in one line starting with ``what``: a
    :class:`~hybridtable.errors.PluginError` naming the user's file and line
    where a user's code raised, else a :class:`~hybridtable.errors.SimulationError`."""
    if isinstance(err, _OURS):  # ours, raised on purpose (a Stewart leg out of its stroke)
        return err
    if _user_frame(err):
        return PluginError(f"{what}: a user's system {_what(err)}")
    return SimulationError(f"{what}: {' '.join(str(err).split())}")
