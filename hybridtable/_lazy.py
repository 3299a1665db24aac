"""Lazy re-exports of a package's public names (the pattern of SPEC 1).

A package ``__init__`` names its public API in ``__all__`` but imports the
module that defines a name only when the name is first used, so importing one
module of a package (``hybridtable.systems.sensor``) does not import all of its
siblings, and the command line starts fast. ``tests/test_architecture.py``
reads the ``lazy_exports`` call as the package's arrows to its children.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

__all__ = ["lazy_exports", "register_entry_points"]


def lazy_exports(
    package: str, exports: Mapping[str, Sequence[str]]
) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` of ``package``, whose
    ``exports`` map a child module's name to the public names it defines.

    Use as ``__all__, __getattr__, __dir__ = lazy_exports(__name__, {...})``.
    """
    where = {name: f"{package}.{module}" for module, names in exports.items() for name in names}

    def __getattr__(name: str) -> Any:
        try:
            module = where[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        return getattr(importlib.import_module(module), name)

    def __dir__() -> list[str]:
        return sorted(where)

    return sorted(where), __getattr__, __dir__


def register_entry_points(group: str, registry: dict[str, Any], kind: str) -> None:
    """Load every entry point of ``group`` into ``registry`` (name -> loaded
    object), refusing a name already taken (``ParameterError`` naming the
    ``kind`` and the entry point). ``importlib.metadata`` (25 ms) is imported
    only here, when a registry's names are first asked for."""
    from importlib.metadata import entry_points

    from hybridtable._plugins import Guarded, call_user
    from hybridtable.errors import ParameterError

    for ep in entry_points(group=group):
        if ep.name in registry:
            raise ParameterError(
                f"{kind} {ep.name!r} of entry point {ep.value} is already registered"
            )
        who = f"{kind} {ep.name!r} (entry point {ep.value} of {group})"
        loaded = call_user(who, ep.load)
        registry[ep.name] = Guarded(loaded, who) if callable(loaded) else loaded
