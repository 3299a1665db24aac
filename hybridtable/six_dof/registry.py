"""Registry of wrench compensators: name -> factory of a 6-DoF compensator system.

A factory ``factory(params, stiffness) -> System`` gets the
:class:`~hybridtable.six_dof.params.DockingLoopParams` and the MDC's
stiffness model (:data:`~hybridtable.six_dof.compensator.StiffnessModel`) and
returns a system with the ports of
:class:`~hybridtable.six_dof.compensator.WrenchCompensator`
(``measured_wrench``, ``table_state``, ``commanded_state`` ->
``compensated_wrench``). The paper's four are built in, and ``sdmdc-online``
(SDMDC whose contact stiffness is identified online and scales the 6x6 K,
:mod:`~hybridtable.six_dof.identification`); other packages add
theirs through the entry-point group ``hybridtable.wrench_compensators``, a
script through :func:`register_wrench_compensator`.

Each name may also say which of the paper's laws its loop is once linearized
(:class:`LinearLaw`): the margins of :mod:`~hybridtable.six_dof.linear` are
that law's. ``sdmdc-online`` is SDMDC whose stiffness converges to the
contact's; a plug-in that declares none has no linear model (its margins are
not computed, not guessed).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pydrake.systems.framework import System

from hybridtable._lazy import register_entry_points
from hybridtable._validation import check_choice
from hybridtable.six_dof.compensator import StiffnessModel, WrenchCompensator
from hybridtable.six_dof.identification import make_online_sdmdc

__all__ = [
    "LinearLaw",
    "linear_law",
    "WrenchCompensatorFactory",
    "ENTRY_POINT_GROUP",
    "PAPER_WRENCH_COMPENSATORS",
    "register_wrench_compensator",
    "wrench_compensator_names",
    "make_wrench_compensator",
]

WrenchCompensatorFactory = Callable[[Any, StiffnessModel], System]
ENTRY_POINT_GROUP = "hybridtable.wrench_compensators"
PAPER_WRENCH_COMPENSATORS: tuple[str, ...] = ("none", "SDC", "MDC", "SDMDC")


def _paper(params: Any, stiffness: StiffnessModel) -> System:
    kind = params.compensator
    return WrenchCompensator(
        params.sample_period_s,
        lead_time_s=params.effective_lead_time_s if kind in ("SDC", "SDMDC") else 0.0,
        stiffness=stiffness if kind in ("MDC", "SDMDC") else None,
        force_deadband_n=params.force_deadband_n,
        axial_deadband=params.deadband_reading == "axial_force",
        clamp_nonnegative=params.clamp_nonnegative,
    )


@dataclass(frozen=True)
class LinearLaw:
    """What a wrench compensator is, linearized in contact.

    Attributes
    ----------
    law : str
        One of the paper's four (:data:`PAPER_WRENCH_COMPENSATORS`).
    identifies_stiffness : bool
        Its stiffness converges to the contact's (an online identifier), so
        its MDC term is the contact's ``K``, not the believed one's.
    """

    law: str
    identifies_stiffness: bool = False

    def __post_init__(self) -> None:
        check_choice("law", self.law, PAPER_WRENCH_COMPENSATORS)


_REGISTRY: dict[str, WrenchCompensatorFactory] = {
    **{name: _paper for name in PAPER_WRENCH_COMPENSATORS},
    "sdmdc-online": make_online_sdmdc,
}
_LINEAR: dict[str, LinearLaw] = {
    **{name: LinearLaw(name) for name in PAPER_WRENCH_COMPENSATORS},
    "sdmdc-online": LinearLaw("SDMDC", identifies_stiffness=True),
}
_entry_points_loaded = False


def _load_entry_points() -> None:
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    register_entry_points(ENTRY_POINT_GROUP, _REGISTRY, "wrench compensator")


def register_wrench_compensator(
    name: str,
    factory: WrenchCompensatorFactory,
    replace: bool = False,
    linear: LinearLaw | None = None,
) -> None:
    """Make ``name`` a choice of ``DockingLoopParams.compensator``;
    ``linear``: the paper's law its loop is once linearized (None: the
    factory's ``linear`` attribute if it has one, else no linear model, and
    ``simulate6`` reports no margins for it).

    Raises
    ------
    ValueError
        If ``name`` is taken (unless ``replace``) or is one of the paper's.
    """
    if name in PAPER_WRENCH_COMPENSATORS or (name in _REGISTRY and not replace):
        raise ValueError(f"wrench compensator {name!r} is already registered")
    _REGISTRY[name] = factory
    _LINEAR.pop(name, None)
    if linear is not None:
        _LINEAR[name] = linear


def linear_law(name: str) -> LinearLaw | None:
    """The :class:`LinearLaw` of the compensator ``name``: the one it was
    registered with, else its factory's ``linear`` attribute (how an
    entry-point plug-in declares it); None: a plug-in that declared none."""
    _load_entry_points()
    found = _LINEAR.get(name)
    if found is None:
        found = getattr(_REGISTRY.get(name), "linear", None)
    return found if isinstance(found, LinearLaw) else None


def wrench_compensator_names() -> tuple[str, ...]:
    """Names of the registered wrench compensators (the paper's first)."""
    _load_entry_points()
    return tuple(_REGISTRY)


def make_wrench_compensator(params: Any, stiffness: StiffnessModel) -> System:
    """The compensator ``params.compensator`` built by its factory."""
    check_choice("compensator", params.compensator, wrench_compensator_names())
    return _REGISTRY[params.compensator](params, stiffness)
