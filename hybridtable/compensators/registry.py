"""Registry of compensators: name -> factory of a Drake system with the ports of
:class:`~hybridtable.compensators.paper.Compensator`.

The built-in compensators are imported here, statically (:data:`BUILTIN`); they
never import this module. Other packages add theirs through the entry-point
group ``hybridtable.compensators`` (loaded on first use), a script through
:func:`register_compensator`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydrake.systems.framework import DiagramBuilder, System

from hybridtable._lazy import register_entry_points
from hybridtable._plugins import Guarded, PluginError, drake_system
from hybridtable._validation import check_choice
from hybridtable.compensators.online import make_online_sdmdc
from hybridtable.compensators.paper import COMPENSATORS, paper_compensator
from hybridtable.compensators.polynomial import make_polynomial
from hybridtable.compensators.smith import make_smith, make_smith_online
from hybridtable.laws.compiled import LawSystem

__all__ = [
    "CompensatorFactory",
    "BUILTIN",
    "ENTRY_POINT_GROUP",
    "register_compensator",
    "compensator_names",
    "compensator_factory",
    "make_compensator",
]


#: ``factory(params, derivative_period_s) -> System``: a compensator with the
#: ports of :class:`Compensator` for a :class:`~hybridtable.loop.params.HybridLoopParams`;
#: ``derivative_period_s`` is the period of the rig computer's discrete updates.
CompensatorFactory = Callable[[Any, float | None], System]


#: Entry-point group of compensators that other packages provide: each entry
#: point names a compensator and loads its factory (a ``CompensatorFactory``).
ENTRY_POINT_GROUP = "hybridtable.compensators"

#: The built-in compensators: the paper's four, then the plug-ins, in the order
#: ``--help`` lists them.
BUILTIN: dict[str, CompensatorFactory] = {
    **{name: paper_compensator for name in COMPENSATORS},
    "sdmdc-online": make_online_sdmdc,
    "polynomial": make_polynomial,
    "smith": make_smith,
    "smith-online": make_smith_online,
}

_REGISTRY: dict[str, CompensatorFactory] = dict(BUILTIN)
_entry_points_loaded = False


def _load_entry_points() -> None:
    """Register the compensators of installed packages (entry-point group
    :data:`ENTRY_POINT_GROUP`), once; a name already taken is refused."""
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    register_entry_points(ENTRY_POINT_GROUP, _REGISTRY, "compensator")


def register_compensator(name: str, factory: CompensatorFactory, replace: bool = False) -> None:
    """Make ``name`` a choice of ``HybridLoopParams.compensator``.

    Raises
    ------
    ValueError
        If ``name`` is taken (unless ``replace``) or is one of the paper's
        compensators.
    """
    if name in COMPENSATORS or (name in _REGISTRY and not replace):
        raise ValueError(f"compensator {name!r} is already registered")
    _REGISTRY[name] = factory


def compensator_names() -> tuple[str, ...]:
    """Names of the registered compensators (the paper's first)."""
    _load_entry_points()
    return tuple(_REGISTRY)


def compensator_factory(name: str) -> CompensatorFactory:
    """The factory registered under ``name`` (ParameterError if none)."""
    check_choice("compensator", name, compensator_names())
    return _REGISTRY[name]


def _checked(system: System, who: str) -> System:
    """A user's compensator ``system`` with its ``compensated_force`` passed through
    a law that refuses a non-finite value (:class:`~hybridtable.laws.compiled.LawSystem`):
    a NaN would otherwise reach the spacecraft's integrator, whose error control
    then shrinks its step without end."""
    if not system.HasOutputPort("compensated_force"):
        names = [system.get_output_port(i).get_name() for i in range(system.num_output_ports())]
        raise PluginError(f"{who} has no output port 'compensated_force' (its outputs: {names})")
    builder = DiagramBuilder()
    inner = builder.AddNamedSystem("user_compensator", system)
    check = builder.AddNamedSystem(
        "finite_force",
        LawSystem({"force": 1}, {"force": lambda s: s["force"][0]}, {}, {"force": 1}),
    )
    builder.Connect(inner.GetOutputPort("compensated_force"), check.GetInputPort("force"))
    for i in range(inner.num_input_ports()):
        builder.ExportInput(inner.get_input_port(i), inner.get_input_port(i).get_name())
    builder.ExportOutput(check.GetOutputPort("force"), "compensated_force")
    for i in range(inner.num_output_ports()):
        port = inner.get_output_port(i)
        if port.get_name() != "compensated_force":
            builder.ExportOutput(port, port.get_name())
    diagram = builder.Build()
    diagram.set_name(system.get_name() or "compensator")
    return diagram


def make_compensator(
    params: Any, derivative_period_s: float | None, system: System | None = None
) -> System:
    """The loop's compensator for ``params``: ``system`` if given, else the one
    registered under ``params.compensator``; wrapped in the time-domain
    passivity guard (:mod:`hybridtable.compensators.passivity`) when
    ``params.passivity`` is true."""
    if system is None:
        factory = compensator_factory(params.compensator)
        if factory is BUILTIN.get(params.compensator):
            system = factory(params, derivative_period_s)
        else:  # a user's: guarded, and its force checked before the spacecraft
            who = f"compensator {params.compensator!r}"
            made = Guarded(factory, f"the factory of {who}", drake_system)
            system = _checked(made(params, derivative_period_s), who)
    if getattr(params, "passivity", False):
        # Imported here, not at the top: a loop without the guard never pays for it.
        from hybridtable.compensators.passivity import passivity_guarded

        system = passivity_guarded(system, params, derivative_period_s)
    return system
