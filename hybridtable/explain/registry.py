"""The registry of CoR effects: name -> :class:`~hybridtable.explain.effects.CorEffect`.

The built-ins come from :mod:`hybridtable.explain.library`, in its order; a
user adds one with :func:`register_cor_effect` (a module of their own that
registers itself when imported), another package through the entry-point group
``hybridtable.cor_effects`` (loaded on first use).
"""

from __future__ import annotations

from hybridtable._lazy import register_entry_points
from hybridtable.errors import ParameterError
from hybridtable.explain.effects import CorEffect
from hybridtable.explain.library import builtin_cor_effects

__all__ = ["ENTRY_POINT_GROUP", "register_cor_effect", "cor_effect_names", "get_cor_effect"]

#: Entry-point group of CoR effects that other packages provide.
ENTRY_POINT_GROUP = "hybridtable.cor_effects"

_EFFECTS: dict[str, CorEffect] = {}
_LOADED = False


def register_cor_effect(effect: CorEffect, *, replace: bool = False) -> CorEffect:
    """Add ``effect`` to the registry (after the built-ins, in order of registration).

    Raises
    ------
    ParameterError
        Not a :class:`CorEffect`, or its name is taken and ``replace`` is false.
    """
    _load()
    if not isinstance(effect, CorEffect):
        raise ParameterError(f"register_cor_effect needs a CorEffect, got {type(effect).__name__}")
    if effect.name in _EFFECTS and not replace:
        raise ParameterError(f"CoR effect {effect.name!r} is already registered")
    _EFFECTS[effect.name] = effect
    return effect


def _load() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    for effect in builtin_cor_effects():
        _EFFECTS[effect.name] = effect
    found: dict[str, CorEffect] = {}
    register_entry_points(ENTRY_POINT_GROUP, found, "CoR effect")
    for name, effect in found.items():
        if name in _EFFECTS or not isinstance(effect, CorEffect):
            raise ParameterError(f"CoR effect entry point {name!r} is taken or not a CorEffect")
        _EFFECTS[name] = effect


def cor_effect_names() -> list[str]:
    """The registered CoR effects, built-ins first."""
    _load()
    return list(_EFFECTS)


def get_cor_effect(name: str) -> CorEffect:
    """The registered effect ``name``.

    Raises
    ------
    ParameterError
        Unknown name (the message lists the known ones).
    """
    _load()
    if name not in _EFFECTS:
        raise ParameterError(f"unknown CoR effect {name!r}; known: {', '.join(_EFFECTS)}")
    return _EFFECTS[name]
