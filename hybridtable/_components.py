"""A component: a few of Drake's primitives behind named ports, built alone
or added flat into a parent diagram.

Each of the loop's library parts (the spacecraft, the table, the sensor's
delay line, a compiled law) is one or a few C++ primitives (a
``LinearSystem``, a ``DiscreteTimeDelay``, a ``SymbolicVectorSystem`` fed by
a ``Multiplexer``). As a :class:`Component` it is a ``Diagram`` with named
ports, usable alone (``CreateDefaultContext``, ``Linearize``, a test); and
:func:`add_component` adds its primitives straight into a parent builder and
returns a :class:`Block` with the same port names. The simulator then steps
one flat diagram: every level of nesting costs it time at every step (a
Table 1 run through the nested loop takes 1.27x as long with SDMDC, 1.38x
with none, 1.43x with a 1 kHz rig computer: medians of 7 alternating pairs).

A subclass states its primitives once, in ``_add(builder, name)``, which both
the ``Diagram`` and the flat :class:`Block` are built from.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from pydrake.systems.framework import (
    Context,
    Diagram,
    DiagramBuilder,
    InputPort,
    OutputPort,
    System,
)
from pydrake.systems.primitives import PassThrough

__all__ = [
    "Block",
    "Component",
    "add_component",
    "connect_input",
    "eval_output",
    "export_input",
    "input_ports",
]


class Block:
    """The primitives a :class:`Component` added to a builder, seen through
    its named ports.

    Attributes
    ----------
    component : Component
        The component it was added from; its attributes (``params``, laws,
        ``sampled``...) are read through the block.
    inputs : mapping of str to tuple of InputPort
        Each named input and the primitives' input ports it feeds (none for an
        input no primitive reads: the component's diagram keeps it as a port,
        the flat block leaves it unconnected).
    outputs : mapping of str to OutputPort
    state_system : System or None
        The primitive holding the component's state, if any.
    """

    def __init__(
        self,
        component: Any,
        inputs: Mapping[str, Sequence[InputPort]],
        outputs: Mapping[str, OutputPort],
        state_system: System | None = None,
    ) -> None:
        self.component = component
        self.inputs = {n: tuple(ports) for n, ports in inputs.items()}
        self.outputs = dict(outputs)
        self.state_system = state_system

    #: The name the block was added under (:func:`add_component`).
    name: str = ""

    def __getattr__(self, name: str) -> Any:
        if name == "component":  # not yet set (copying, unpickling)
            raise AttributeError(name)
        if hasattr(System, name):  # the component's own diagram is not in the loop
            raise AttributeError(
                f"{self.name or 'a block'} is a component added flat: it has no System "
                f"method {name}(); use its ports (eval_output, input_ports) or add it "
                "with flat=False"
            )
        return getattr(self.component, name)

    def get_name(self) -> str:
        return self.name

    def HasInputPort(self, name: str) -> bool:
        return name in self.inputs

    def HasOutputPort(self, name: str) -> bool:
        return name in self.outputs

    def GetInputPort(self, name: str) -> InputPort:
        """The one primitive input port ``name`` feeds (see :func:`input_ports`
        for an input read by several primitives)."""
        ports = self.inputs[name]
        if len(ports) != 1:
            raise ValueError(f"input {name!r} feeds {len(ports)} ports: use input_ports()")
        return ports[0]

    def GetOutputPort(self, name: str) -> OutputPort:
        return self.outputs[name]

    def set_initial_state(self, root_context: Context, *state: float) -> None:
        """The component's ``set_initial_state`` on the root context of the
        diagram the block is in."""
        if self.state_system is not None:
            self.component._write_state(
                self.state_system.GetMyMutableContextFromRoot(root_context), *state
            )


class Component(Diagram):
    """A ``Diagram`` of primitives that :func:`add_component` can add flat.

    A subclass sets its attributes, then calls ``self._build(name)`` (the
    name of its primitives inside the diagram); it defines
    ``_add(builder, name) -> Block`` and, if it has a state,
    ``_write_state(primitive_context, *state)``; ``_input_sizes`` gives the
    size of an input no primitive reads.
    """

    _input_sizes: Mapping[str, int] = {}

    def _build(self, name: str) -> None:
        builder = DiagramBuilder()
        block = self._block = self._add(builder, name)
        for port_name, ports in block.inputs.items():
            if not ports:  # read by no primitive: still a port of the diagram
                unread = PassThrough(self._input_sizes[port_name])
                unread = builder.AddNamedSystem(f"{port_name}_unread", unread)
                block.inputs[port_name] = (unread.get_input_port(),)
            export_input(builder, block, port_name, port_name)
        for port_name, port in block.outputs.items():
            builder.ExportOutput(port, port_name)
        builder.BuildInto(self)

    def _add(self, builder: DiagramBuilder, name: str) -> Block:
        raise NotImplementedError

    def _write_state(self, context: Context, *state: float) -> None:
        raise NotImplementedError

    def set_initial_state(self, context: Context, *state: float) -> None:
        """Write the state into this diagram's (sub)context."""
        if self._block.state_system is not None:
            self._write_state(self.GetSubsystemContext(self._block.state_system, context), *state)


def add_component(
    builder: DiagramBuilder, name: str, system: System, flat: bool = True
) -> System | Block:
    """Add ``system`` to ``builder`` under ``name``: a :class:`Component`'s
    primitives flat (a :class:`Block`), any other system (or ``flat=False``)
    whole."""
    if flat and isinstance(system, Component):
        block = system._add(builder, name)
        block.name = name
        return block
    return builder.AddNamedSystem(name, system)


def input_ports(part: System | Block, name: str) -> tuple[InputPort, ...]:
    """The input ports that the named input of a system or block feeds."""
    return part.inputs[name] if isinstance(part, Block) else (part.GetInputPort(name),)


def connect_input(
    builder: DiagramBuilder, source: OutputPort, part: System | Block, name: str
) -> None:
    """Connect ``source`` to the input ``name`` of a system or block."""
    for port in input_ports(part, name):
        builder.Connect(source, port)


def export_input(builder: DiagramBuilder, part: System | Block, name: str, as_name: str) -> None:
    """Export the input ``name`` of a system or block as the diagram's ``as_name``."""
    first, *rest = input_ports(part, name)
    builder.ExportInput(first, as_name)
    for port in rest:
        builder.ConnectInput(as_name, port)


def eval_output(part: System | Block, name: str, root_context: Context) -> Any:
    """The value of the output ``name`` of a system or block in a root context."""
    port = part.GetOutputPort(name)
    return port.Eval(port.get_system().GetMyContextFromRoot(root_context))
