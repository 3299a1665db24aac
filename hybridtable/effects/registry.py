"""The one registry of effects: name -> :class:`~hybridtable.effects.effect.Effect`,
for ``diagnose``, ``compare --add`` and ``explain`` alike.

The built-in effects come from :mod:`hybridtable.effects.library` (one module
each, imported statically), registered in its order. Other packages add
theirs through the entry-point group ``hybridtable.effects`` (loaded on first
use), a script through :func:`register_effect`, a command through
``--plugin``. The old group of CoR effects, ``hybridtable.cor_effects``, and
:func:`register_cor_effect` still load old
:class:`~hybridtable.effects.legacy.CorEffect` s, with a deprecation warning.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from hybridtable._plugins import Guarded, PluginError, call_user, drake_system, finite_numbers
from hybridtable.effects.effect import FRONT_ENDS, Effect
from hybridtable.effects.legacy import CorEffect, as_effect
from hybridtable.effects.library import builtin_effects
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError

__all__ = [
    "EFFECTS",
    "ENTRY_POINT_GROUP",
    "OLD_ENTRY_POINT_GROUP",
    "register_effect",
    "register_cor_effect",
    "default_effects",
    "unregister_effect",
    "effect_names",
    "get_effect",
    "parse_effect_spec",
    "parse_effect_specs",
    "build_spec",
    "apply_in_order",
    "load_plugin",
    "guarded",
    "user_effect",
    "effect_source",
    "SOURCES",
]


#: The registry: effect name -> Effect.
EFFECTS: dict[str, Effect] = {}

#: Entry-point group of effects that other packages provide: each entry point
#: loads an :class:`~hybridtable.effects.effect.Effect`.
ENTRY_POINT_GROUP = "hybridtable.effects"

#: The old entry-point group of ``explain``'s CoR effects (loaded, deprecated).
OLD_ENTRY_POINT_GROUP = "hybridtable.cor_effects"

_entry_points_loaded = False

#: The source file of each effect registered by an entry point (to recognise
#: the same plug-in given again with ``--plugin``).
_ENTRY_POINT_FILES: dict[str, Path] = {}

#: Each plug-in effect registered guarded -> the effect its module defines.
_GUARDED_FROM: dict[str, Effect] = {}

#: Where an effect comes from: a built-in, an installed package's entry point,
#: a ``--plugin``, or a script's :func:`register_effect`.
SOURCES: tuple[str, ...] = ("built-in", "entry point", "plug-in", "script")

#: Each registered effect -> its source (one of :data:`SOURCES`).
_SOURCE: dict[str, str] = {}


def _module_file(module_name: str) -> Path | None:
    module = sys.modules.get(module_name)
    path = getattr(module, "__file__", None)
    return Path(path) if path else None


def _same_source(a: Path | None, b: Path | None) -> bool:
    """Whether two module files hold the same code (an installed copy of a file)."""
    try:
        return a is not None and b is not None and a.read_bytes() == b.read_bytes()
    except OSError:
        return False


def _load_entry_points() -> None:
    """Register the effects of installed packages (entry-point groups
    :data:`ENTRY_POINT_GROUP` and, deprecated, :data:`OLD_ENTRY_POINT_GROUP`),
    once; a name already taken is refused.

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

    found = [(ep, ENTRY_POINT_GROUP) for ep in entry_points(group=ENTRY_POINT_GROUP)]
    found += [(ep, OLD_ENTRY_POINT_GROUP) for ep in entry_points(group=OLD_ENTRY_POINT_GROUP)]
    for ep, group in found:
        effect = call_user(f"entry point {ep.name} = {ep.value} of {group}", ep.load)
        if group == OLD_ENTRY_POINT_GROUP:
            warnings.warn(
                f"entry point {ep.name} of {OLD_ENTRY_POINT_GROUP} is deprecated: give the "
                f"effect as an Effect in {ENTRY_POINT_GROUP}",
                DeprecationWarning,
                stacklevel=2,
            )
            effect = as_effect(effect) if isinstance(effect, CorEffect | Effect) else effect
        if not isinstance(effect, Effect):
            raise ParameterError(f"entry point {ep.name} = {ep.value} of {group} is not an Effect")
        if effect.name in EFFECTS:
            raise ParameterError(
                f"effect {effect.name!r} of entry point {ep.name} = {ep.value} "
                "is already registered"
            )
        EFFECTS[effect.name] = guarded(effect, f"effect {effect.name!r} of entry point {ep.value}")
        _GUARDED_FROM[effect.name] = effect
        _SOURCE[effect.name] = "entry point"
        module_file = _module_file(ep.module)
        if module_file is not None:
            _ENTRY_POINT_FILES[effect.name] = module_file


def register_effect(effect: Effect, replace_existing: bool = False) -> Effect:
    """Add ``effect`` to :data:`EFFECTS` (the commands of its ``default_for`` try it
    unless told which effects to try).

    Raises
    ------
    ParameterError
        If the name is taken and ``replace_existing`` is false.
    """
    if effect.name in EFFECTS and not replace_existing:
        raise ParameterError(f"effect {effect.name!r} is already registered")
    EFFECTS[effect.name] = effect
    _SOURCE[effect.name] = "script"
    _GUARDED_FROM.pop(effect.name, None)
    return effect


def effect_source(name: str) -> str:
    """Where the registered effect ``name`` comes from (:data:`SOURCES`)."""
    get_effect(name)
    return _SOURCE[name]


def register_cor_effect(effect: CorEffect | Effect, *, replace: bool = False) -> Effect:
    """Register an old CoR effect (deprecated: write an
    :class:`~hybridtable.effects.effect.Effect` and call :func:`register_effect`)."""
    warnings.warn(
        "register_cor_effect and CorEffect are deprecated: write an Effect "
        "(hybridtable.effects) and register it with register_effect",
        DeprecationWarning,
        stacklevel=2,
    )
    return register_effect(as_effect(effect), replace_existing=replace)


def default_effects(front_end: str) -> tuple[str, ...]:
    """The registered effects that ``front_end`` (``"diagnose"`` or ``"explain"``)
    tries when the user names none, in registration order
    (:attr:`~hybridtable.effects.effect.Effect.default_for`)."""
    if front_end not in FRONT_ENDS:
        raise ParameterError(f"front end must be one of {', '.join(FRONT_ENDS)}")
    return tuple(n for n in effect_names() if front_end in EFFECTS[n].default_for)


def unregister_effect(name: str) -> None:
    """Remove an effect from the registry (no error if absent)."""
    EFFECTS.pop(name, None)
    _GUARDED_FROM.pop(name, None)
    _SOURCE.pop(name, None)


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


def parse_effect_specs(
    texts: Sequence[str], flag: str = "--add"
) -> list[tuple[Effect, dict[str, float]]]:
    """Several ``EFFECT[:param=value,...]`` (a repeated ``--add``), in order.

    Raises
    ------
    ParameterError
        For a malformed spec, or an effect given twice or two effects that
        change the same part of the model (e.g. two contact laws).
    """
    out: list[tuple[Effect, dict[str, float]]] = []
    for text in texts:
        if not str(text).strip():
            raise ParameterError(f"{flag}: empty; give EFFECT[:param=value,...]")
        effect, values = parse_effect_spec(text)
        for other, _ in out:
            if other.name == effect.name:
                raise ParameterError(f"{flag} {effect.name}: given twice (give it once)")
            if effect.conflicts_with(other):
                raise ParameterError(
                    f"{flag} {effect.name} and {other.name} both change "
                    f"{', '.join(sorted(set(effect.touches) & set(other.touches)))}; "
                    "give one of them"
                )
        out.append((effect, values))
    return out


def _import_module(where: str, text: str):
    """The module named ``where``, or the Python file at the path ``where``."""
    path = Path(where)
    if where.endswith(".py") or path.is_file():
        if not path.is_file():
            raise ParameterError(f"--plugin {text}: no such file {where}")
        name = f"hybridtable_plugin_{path.stem}_{abs(hash(str(path.resolve()))):x}"
        if name in sys.modules:
            return sys.modules[name]
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise ParameterError(f"--plugin {text}: cannot load {where} as Python")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            call_user(f"--plugin {text}: {where} failed to load:", spec.loader.exec_module, module)
        except Exception:  # PluginError: a module half loaded is no module
            del sys.modules[name]
            raise
        return module

    def load():
        try:
            return importlib.import_module(where)
        except ModuleNotFoundError as err:
            if err.name != where and not where.startswith(f"{err.name}."):
                raise  # a module the plug-in imports is missing: its failure
            raise ParameterError(
                f"--plugin {text}: no module {err.name!r} (give an importable module "
                "or the path of a .py file)"
            ) from None

    return call_user(f"--plugin {text}: module {where} failed to load:", load)


def load_plugin(text: str) -> list[Effect]:
    """Register the effect(s) of ``MODULE:ATTR`` and return them.

    ``MODULE`` is an importable module (``my_lab.effects``) or the path of a
    Python file (``./backlash.py``); ``ATTR`` names an
    :class:`~hybridtable.effects.effect.Effect` or a list or tuple of them.
    Loading the same plug-in twice registers it once; so does a file whose
    code an installed package's entry point already registered (the package
    installed from it).

    Raises
    ------
    ParameterError
        One line: a malformed spec, a module or file that does not load, a
        missing attribute, an attribute that is not an effect, a name that
        another effect already has.
    """
    where, colon, attr = text.strip().rpartition(":")
    if not colon or not where or not attr.isidentifier():
        raise ParameterError(f"--plugin {text}: expected MODULE:ATTR or FILE.py:ATTR")
    module = _import_module(where, text)
    try:
        found = getattr(module, attr)
    except AttributeError:
        raise ParameterError(f"--plugin {text}: {where} has no attribute {attr!r}") from None
    items = (
        list(found)
        if isinstance(found, Iterable) and not isinstance(found, Effect | CorEffect)
        else [found]
    )
    if any(isinstance(e, CorEffect) for e in items):
        warnings.warn(
            f"--plugin {text}: CorEffect is deprecated; write an Effect (hybridtable.effects)",
            DeprecationWarning,
            stacklevel=2,
        )
        items = [as_effect(e) if isinstance(e, CorEffect) else e for e in items]
    if not items or not all(isinstance(e, Effect) for e in items):
        raise ParameterError(
            f"--plugin {text}: {attr} is not an Effect or a list of them "
            f"(got {type(found).__name__})"
        )
    _load_entry_points()
    here = Path(module.__file__) if getattr(module, "__file__", None) else None
    out = []
    for effect in items:
        known = EFFECTS.get(effect.name)
        if known is not None and _GUARDED_FROM.get(effect.name) is effect:
            out.append(known)  # this very plug-in, loaded before
            continue
        if known is not None and _same_source(_ENTRY_POINT_FILES.get(effect.name), here):
            out.append(known)  # the installed copy of this very file: already registered
            continue
        if known is not None:
            raise ParameterError(
                f"--plugin {text}: an effect named {effect.name!r} is already "
                "registered (rename the plug-in's effect)"
            )
        out.append(register_effect(guarded(effect, f"effect {effect.name!r} (--plugin {text})")))
        _GUARDED_FROM[effect.name] = effect
        _SOURCE[effect.name] = "plug-in"
    return out


def user_effect(name: str) -> Effect:
    """The effect ``name`` as its plug-in defines it (the registry holds it
    :func:`guarded`); a built-in effect as registered."""
    return _GUARDED_FROM.get(name) or get_effect(name)


def guarded(effect: Effect, who: str) -> Effect:
    """``effect`` with every function of a user's in it called through the one
    guard (:mod:`hybridtable._plugins`): ``apply`` (and the systems' wrappers
    and loop changes the spec it returns adds), ``starts``, and each
    parameter's bounds, scale, null and initial value (a finite number each).
    A failure is one line naming ``who``."""

    def number(bound, what: str):
        return Guarded(bound, f"{who}: {what}", finite_numbers) if callable(bound) else bound

    parameters = tuple(
        replace(
            p,
            **{
                field: number(getattr(p, field), f"{p.name}'s {field}")
                for field in ("lower", "upper", "scale", "null", "initial")
            },
        )
        for p in effect.parameters
    )
    starts = effect.starts and Guarded(effect.starts, f"{who} starts", _finite_starts)
    apply = effect.apply and _GuardedApply(effect.apply, who)
    apply6 = effect.apply6 and Guarded(effect.apply6, f"{who} apply6", _physics6)
    return replace(effect, apply=apply, apply6=apply6, starts=starts, parameters=parameters)


def _physics6(who: str, physics):
    # the six-axis rig's DockingPhysics (hybridtable.six_dof.physics6, which
    # builds on this package: known here by its parts, not imported)
    if not all(hasattr(physics, a) for a in ("changes", "sensor_gain", "table_gain", "apply")):
        raise PluginError(f"{who} returned {type(physics).__name__}, not a DockingPhysics")
    return physics


class _GuardedApply:
    """A user's ``apply`` through the guard; the wrappers and loop changes it
    adds to the spec are guarded too (picklable, for worker processes)."""

    def __init__(self, apply, who: str) -> None:
        self.apply, self.who = apply, who

    def __call__(self, spec: ModelSpec, values, scale) -> ModelSpec:
        who = self.who
        out = call_user(f"{who} apply", self.apply, spec, values, scale)
        if not isinstance(out, ModelSpec):
            raise PluginError(f"{who} apply returned {type(out).__name__}, not a ModelSpec")
        wrappers = tuple(
            (
                c,
                w
                if i < len(spec.wrappers)
                else Guarded(w, f"{who}: its {c} wrapper", drake_system),
            )
            for i, (c, w) in enumerate(out.wrappers)
        )
        loop = tuple(
            ch if i < len(spec.loop) else Guarded(ch, f"{who}: its loop change", _loop_params)
            for i, ch in enumerate(out.loop)
        )
        return replace(out, wrappers=wrappers, loop=loop)


def _loop_params(who: str, params):
    from hybridtable.loop.params import HybridLoopParams

    if not isinstance(params, HybridLoopParams):
        raise PluginError(f"{who} returned {type(params).__name__}, not the loop's parameters")
    return params


def _finite_starts(who: str, starts):
    if not isinstance(starts, list | tuple):
        raise PluginError(f"{who} returned {type(starts).__name__}, not a list of dicts")
    for start in starts:
        if not isinstance(start, Mapping):
            raise PluginError(f"{who} returned {start!r:.80}, not a dict of values")
        finite_numbers(who, start)
    return list(starts)


def build_spec(
    effects: Sequence[tuple[Effect, Mapping[str, float]]],
    scale: RigScale,
    base: ModelSpec | None = None,
) -> ModelSpec:
    """The model with ``effects`` applied in order to ``base`` (default nominal)."""
    return apply_in_order(effects, scale, base or ModelSpec(), "1-D")


#: What an effect of each loop is applied to, and where an effect without it acts.
_LOOPS = {
    "1-D": ("apply", "a six-axis rig only (6-DoF runs: simulate6 --add, compare and diagnose "
            "of hybridtable-run6/1 runs)"),
    "6-DoF": ("apply6", "the 1-D loop only (it has no apply6 for a six-axis rig)"),
}  # fmt: skip


def apply_in_order(
    effects: Sequence[tuple[Effect, Mapping[str, float]]], scale: RigScale, base, loop: str
):
    """``base`` (a :class:`~hybridtable.effects.spec.ModelSpec` for the
    ``"1-D"`` loop, a :class:`~hybridtable.six_dof.physics6.DockingPhysics`
    for ``"6-DoF"``) with ``effects`` applied in order by their ``apply`` or
    ``apply6``.

    Raises
    ------
    ParameterError
        For an effect that does not act on ``loop``.
    """
    attribute, elsewhere = _LOOPS[loop]
    model = base
    for effect, values in effects:
        apply = getattr(effect, attribute)
        if apply is None:
            raise ParameterError(f"effect {effect.name} acts on {elsewhere}")
        model = apply(model, values, scale)
    return model


for _effect in builtin_effects():
    register_effect(_effect)
    _SOURCE[_effect.name] = "built-in"
del _effect
