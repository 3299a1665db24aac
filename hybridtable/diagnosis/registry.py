"""The registry of candidate effects: name -> :class:`~hybridtable.diagnosis.effects.Effect`.

The built-in effects come from :mod:`hybridtable.diagnosis.library` (one module
each, imported statically), registered in its order. Other packages add
theirs through the entry-point group ``hybridtable.effects`` (loaded on first
use), a script through :func:`register_effect`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from hybridtable.diagnosis.effects import Effect, ModelSpec, RigScale
from hybridtable.diagnosis.library import builtin_effects
from hybridtable.errors import ParameterError

__all__ = [
    "EFFECTS",
    "ENTRY_POINT_GROUP",
    "register_effect",
    "unregister_effect",
    "effect_names",
    "get_effect",
    "parse_effect_spec",
    "build_spec",
]


#: The registry: effect name -> Effect.
EFFECTS: dict[str, Effect] = {}

#: Entry-point group of effects that other packages provide: each entry point
#: loads an :class:`~hybridtable.diagnosis.effects.Effect`.
ENTRY_POINT_GROUP = "hybridtable.effects"

_entry_points_loaded = False


def _load_entry_points() -> None:
    """Register the effects of installed packages (entry-point group
    :data:`ENTRY_POINT_GROUP`), once; a name already taken is refused.

    Raises
    ------
    ParameterError
        If an entry point's effect has a registered name, or the entry point
        does not load an ``Effect``.
    """
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    from importlib.metadata import entry_points  # 25 ms: only when names are asked for

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        effect = ep.load()
        if not isinstance(effect, Effect):
            raise ParameterError(
                f"entry point {ep.name} = {ep.value} of {ENTRY_POINT_GROUP} is not an Effect"
            )
        if effect.name in EFFECTS:
            raise ParameterError(
                f"effect {effect.name!r} of entry point {ep.name} = {ep.value} "
                "is already registered"
            )
        EFFECTS[effect.name] = effect


def register_effect(effect: Effect, replace_existing: bool = False) -> Effect:
    """Add ``effect`` to :data:`EFFECTS` (diagnose fits every registered effect).

    Raises
    ------
    ParameterError
        If the name is taken and ``replace_existing`` is false.
    """
    if effect.name in EFFECTS and not replace_existing:
        raise ParameterError(f"effect {effect.name!r} is already registered")
    EFFECTS[effect.name] = effect
    return effect


def unregister_effect(name: str) -> None:
    """Remove an effect from the registry (no error if absent)."""
    EFFECTS.pop(name, None)


def effect_names() -> tuple[str, ...]:
    """Names of the registered effects, in registration order (the built-ins
    first; the effects of entry points are registered on the first use)."""
    _load_entry_points()
    return tuple(EFFECTS)


def get_effect(name: str) -> Effect:
    """The registered effect ``name``.

    Raises
    ------
    ParameterError
        If there is none.
    """
    _load_entry_points()
    try:
        return EFFECTS[name]
    except KeyError:
        raise ParameterError(
            f"unknown effect {name!r} (one of {', '.join(effect_names())})"
        ) from None


def parse_effect_spec(text: str) -> tuple[Effect, dict[str, float]]:
    """``"EFFECT[:param=value,...]"`` -> (effect, given values).

    Raises
    ------
    ParameterError
        For an unknown effect or parameter, or a malformed value.
    """
    name, _, rest = text.strip().partition(":")
    effect = get_effect(name.strip())
    values: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise ParameterError(f"--add {text}: expected param=value, got {item!r}")
        effect.parameter(key)
        try:
            values[key] = float(value)
        except ValueError:
            raise ParameterError(f"--add {text}: {key} is not a number ({value!r})") from None
    return effect, values


def build_spec(
    effects: Sequence[tuple[Effect, Mapping[str, float]]],
    scale: RigScale,
    base: ModelSpec | None = None,
) -> ModelSpec:
    """The model with ``effects`` applied in order to ``base`` (default nominal)."""
    spec = base or ModelSpec()
    for effect, values in effects:
        spec = effect.apply(spec, values, scale)
    return spec


for _effect in builtin_effects():
    register_effect(_effect)
del _effect
