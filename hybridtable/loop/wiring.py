"""The hybrid loop's wiring, written once: which output port feeds which input port.

:func:`~hybridtable.loop.builder.add_hybrid_loop` connects the Drake systems
from :data:`LOOP_WIRING`; the linear models of :mod:`hybridtable.analysis`
wire their linearized blocks channel by channel from the same table
(:func:`channel_wiring`), so the loop and its analysis cannot drift apart.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from pydrake.systems.framework import DiagramBuilder, System

from hybridtable._components import Block, connect_input
from hybridtable.errors import ParameterError

__all__ = ["Edge", "LOOP_WIRING", "PORT_SIZES", "edge", "channel_wiring", "connect"]

#: ``(source system, output port, sink system, input port)``.
Edge = tuple[str, str, str, str]

#: Every connection of the loop, in the order the builder makes them.
LOOP_WIRING: tuple[Edge, ...] = (
    ("spacecraft", "state", "table", "commanded_state"),
    ("table", "motion", "contact", "motion"),
    ("contact", "force", "force_sensor", "force"),
    ("force_sensor", "measured_force", "compensator", "measured_force"),
    ("table", "motion", "compensator", "table_motion"),
    ("spacecraft", "state", "compensator", "commanded_state"),
    ("compensator", "compensated_force", "spacecraft", "force"),
)

#: Size of each port of :data:`LOOP_WIRING` (``state``: p m, v m/s; ``motion``:
#: p m, v m/s, a m/s^2; forces: N).
PORT_SIZES: dict[str, int] = {
    "state": 2,
    "state_next": 2,
    "commanded_state": 2,
    "motion": 3,
    "table_motion": 3,
    "force": 1,
    "measured_force": 1,
    "compensated_force": 1,
}


def edge(source: str, sink: str) -> Edge:
    """The edge of :data:`LOOP_WIRING` from ``"system.port"`` to ``"system.port"``."""
    for e in LOOP_WIRING:
        if f"{e[0]}.{e[1]}" == source and f"{e[2]}.{e[3]}" == sink:
            return e
    raise KeyError(f"the loop has no connection {source} -> {sink}")


def channel_wiring(
    edges: Iterable[Edge] = LOOP_WIRING, sizes: Mapping[str, int] = PORT_SIZES
) -> dict[str, str]:
    """Sink channel -> source channel of ``edges``, one entry per scalar:
    ``{"table.commanded_state[0]": "spacecraft.state[0]", ...}``."""
    out = {}
    for src, out_port, dst, in_port in edges:
        for i in range(sizes[in_port]):
            out[f"{dst}.{in_port}[{i}]"] = f"{src}.{out_port}[{i}]"
    return out


def connect(
    builder: DiagramBuilder,
    systems: Mapping[str, System | Block],
    edges: Iterable[Edge] = LOOP_WIRING,
) -> None:
    """Connect ``systems`` (by name; whole systems or the flat blocks of
    :func:`~hybridtable._components.add_component`) in ``builder`` along ``edges``."""
    for src, out_port, dst, in_port in edges:
        try:
            connect_input(builder, systems[src].GetOutputPort(out_port), systems[dst], in_port)
        except RuntimeError as err:  # a given system without the loop's ports (Drake says which)
            raise ParameterError(
                f"cannot wire the loop's {src}.{out_port} to {dst}.{in_port}: {err} "
                f"(a {dst} must have the ports in docs/plugins.md)"
            ) from None
