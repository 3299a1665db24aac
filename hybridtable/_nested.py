"""A scenario nested one config per component, each quantity also reachable
by one flat name.

Tedrake's ``manipulation`` scenarios nest one config per component; command
lines, plausible ranges, sweep axes and files speak of single quantities.
:class:`NestedParams` holds both: a frozen dataclass of component configs
(``plant``, ``rig``, ``approach``...), and a map ``FIELDS`` from each flat
name to its path in the tree. The 1-D loop's
:class:`~hybridtable.loop.params.HybridLoopParams` and the 6-DoF loop's
:class:`~hybridtable.six_dof.params.DockingLoopParams` are the two trees: one
way to build a scenario, change it and read it, and one way its errors are
worded.

- build: ``Params(plant=..., rig=...)``, or by flat names
  (``Params(sensor_delay_s=0.005, ...)``), or both (the names change the
  configs given, or the defaults);
- change: ``params.with_(sensor_delay_s=...)`` rebuilds only the configs on
  the changed paths (each validates itself again), ``with_(rig=...)``
  replaces a whole config;
- read: ``params.sensor_delay_s``, a property made from the map
  (:func:`flat_properties`); ``params.quantities()`` gives them all.

An error a config raises about its own field is said with the field's flat
name (``spacecraft_mass_kg must be > 0``, not ``mass_kg``).
"""

from __future__ import annotations

from dataclasses import MISSING, fields, replace
from typing import Any, ClassVar, get_type_hints

from hybridtable.errors import ParameterError

__all__ = ["NestedParams", "build_config", "flat_properties"]

_HINTS: dict[type, dict[str, Any]] = {}


def build_config(
    cls: type,
    prefix: tuple[str, ...],
    base: Any,
    changes: dict[tuple[str, ...], Any],
    flat_name: dict[tuple[str, ...], str],
) -> Any:
    """Config ``cls`` at ``prefix``: ``base`` (an instance, or ``None``: the
    defaults) with ``changes`` ({path below ``prefix``: value}). A config's
    error that names its own field is said with the field's flat name
    (``flat_name``: path -> flat name)."""
    hints = _HINTS.get(cls) or _HINTS.setdefault(cls, get_type_hints(cls))
    values: dict[str, Any] = {}
    for f in fields(cls):
        below = {path[1:]: v for path, v in changes.items() if path[0] == f.name}
        if () in below:
            values[f.name] = below.pop(())
        if below:
            inner = values.get(f.name, getattr(base, f.name) if base is not None else None)
            if inner is None and f.default is not MISSING:
                inner = f.default
            elif inner is None and f.default_factory is not MISSING:
                inner = f.default_factory()
            values[f.name] = build_config(hints[f.name], (*prefix, f.name), inner, below, flat_name)
    try:
        return replace(base, **values) if base is not None else cls(**values)
    except ParameterError as err:
        text = str(err)
        for key in values:
            flat = flat_name.get((*prefix, key))
            if flat and text.startswith(key + " "):
                raise ParameterError(flat + text[len(key) :]) from None
        raise


def _flat_property(name: str, path: tuple[str, ...]) -> property:
    def read(params: Any) -> Any:
        value: Any = params
        for key in path:
            value = getattr(value, key)
        return value

    return property(read, doc=f"``{'.'.join(path)}`` (flat name ``{name}``).")


def flat_properties(cls: type) -> type:
    """Class decorator: a read-only property per flat name of ``cls.FIELDS``."""
    for name, path in cls.FIELDS.items():
        setattr(cls, name, _flat_property(name, path))
    cls._FLAT_NAME = {path: name for name, path in cls.FIELDS.items()}
    return cls


class NestedParams:
    """Base of a frozen dataclass whose fields are component configs
    (:data:`PARTS`), built and changed by config or by flat name
    (:data:`FIELDS`). A subclass is ``@flat_properties @dataclass(frozen=True,
    init=False)`` with one field per part."""

    #: Each part's name -> its config type, in the dataclass's field order.
    PARTS: ClassVar[dict[str, type]] = {}
    #: Each quantity's flat name -> its path in the tree.
    FIELDS: ClassVar[dict[str, tuple[str, ...]]] = {}
    #: Parts with no default: what to say when one is missing.
    REQUIRED: ClassVar[dict[str, str]] = {}
    #: A flat name to give as an example in errors.
    EXAMPLE: ClassVar[str] = ""
    _FLAT_NAME: ClassVar[dict[tuple[str, ...], str]] = {}

    def __init__(self, *parts: Any, **named: Any) -> None:
        kind = type(self).__name__
        if len(parts) > len(self.PARTS):
            raise TypeError(f"{kind} takes at most {len(self.PARTS)} configs by position")
        given = dict(zip(self.PARTS, parts, strict=False))
        for name in list(named):
            if name in self.PARTS:
                if name in given:
                    raise TypeError(f"{kind} got {name} twice")
                given[name] = named.pop(name)
        unknown = sorted(set(named) - set(self.FIELDS))
        if unknown:
            raise TypeError(
                f"{kind} got unknown {', '.join(unknown)} "
                f"(known: {', '.join(self.PARTS)}, {', '.join(self.FIELDS)})"
            )
        changes = {self.FIELDS[name]: value for name, value in named.items()}
        for name, kind_of in self.PARTS.items():
            config = given.get(name)
            if config is None and name not in self.REQUIRED:
                config = kind_of()
            below = {path[1:]: v for path, v in changes.items() if path[0] == name}
            if below:
                try:
                    config = build_config(kind_of, (name,), config, below, self._FLAT_NAME)
                except TypeError:
                    config = None
            if not isinstance(config, kind_of):
                if name in self.REQUIRED and config is None:
                    raise TypeError(f"{kind} needs {self.REQUIRED[name]}")
                raise ParameterError(
                    f"{name} must be a {kind_of.__name__} (got {type(config).__name__}; "
                    f"give single quantities by name, e.g. {self.EXAMPLE}=...)"
                )
            object.__setattr__(self, name, config)

    def with_(self, **changes: Any):
        """A copy with some quantities (flat names, :data:`FIELDS`) or whole
        configs (:data:`PARTS`) changed, validated again."""
        parts = [changes.pop(name, getattr(self, name)) for name in self.PARTS]
        return type(self)(*parts, **changes)

    def quantities(self) -> dict[str, Any]:
        """Every quantity by its flat name (:data:`FIELDS`, in that order)."""
        return {name: getattr(self, name) for name in self.FIELDS}
