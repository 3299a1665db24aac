"""Small diagram blocks: a stage behind one output port (:func:`chain_output`),
a recorded series added to a signal (:class:`RecordedOffset`).
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, System
from pydrake.systems.primitives import (
    Adder,
    TrajectorySource,
)
from pydrake.trajectories import PiecewisePolynomial

from hybridtable._validation import check_positive
from hybridtable.errors import ParameterError

__all__ = [
    "ChainedOutput",
    "chain_output",
    "RecordedOffset",
]


# -- user stages ---------------------------------------------------------------
class ChainedOutput(Diagram):
    """The ports of ``inner``, with its output ``port_name`` passed through
    ``stage`` (one input, one output of the same size).

    A table's ``set_initial_state`` is forwarded to ``inner``.

    Raises
    ------
    ParameterError
        If ``inner`` has no output ``port_name``.
    """

    def __init__(self, inner: System, stage: System, port_name: str) -> None:
        Diagram.__init__(self)
        if not inner.HasOutputPort(port_name):
            raise ParameterError(f"{inner.get_name() or 'system'} has no output port {port_name!r}")
        builder = DiagramBuilder()
        self.inner = builder.AddNamedSystem("inner", inner)
        self.stage = builder.AddNamedSystem("stage", stage)
        for i in range(inner.num_input_ports()):
            port = inner.get_input_port(i)
            builder.ExportInput(port, port.get_name())
        for i in range(inner.num_output_ports()):
            port = inner.get_output_port(i)
            if port.get_name() == port_name:
                builder.Connect(port, self.stage.get_input_port(0))
                builder.ExportOutput(self.stage.get_output_port(0), port_name)
            else:
                builder.ExportOutput(port, port.get_name())
        builder.BuildInto(self)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        setter = getattr(self.inner, "set_initial_state", None)
        if setter is not None:
            setter(self.GetSubsystemContext(self.inner, context), position_m, velocity_m_per_s)


def chain_output(inner: System, stage: System, port_name: str) -> ChainedOutput:
    """``inner`` with its output ``port_name`` passed through ``stage``
    (:class:`ChainedOutput`)."""
    return ChainedOutput(inner, stage, port_name)


class RecordedOffset(Diagram):
    """Adds a recorded series to a signal: ``y(t) = u(t) + r[k]`` for ``t``
    within half a tick of tick ``k`` (constant pieces centred on the ticks,
    so a reader at tick ``k`` gets ``r[k]`` whatever the rounding of the
    event time); ``r`` is held after its last tick.

    Ports
    -----
    Input ``u`` (size 1), output ``y`` (size 1), same unit.
    """

    def __init__(self, sample_period_s: float, values: np.ndarray) -> None:
        Diagram.__init__(self)
        h = check_positive("sample_period_s", sample_period_s)
        r = np.asarray(values, dtype=float).ravel()
        if r.size < 1 or not np.isfinite(r).all():
            raise ParameterError("RecordedOffset: values must be finite and not empty")
        breaks = h * (np.arange(r.size + 1) - 0.5)
        builder = DiagramBuilder()
        source = builder.AddNamedSystem(
            "recorded",
            TrajectorySource(
                PiecewisePolynomial.ZeroOrderHold(breaks, np.append(r, r[-1])[None, :])
            ),
        )
        adder = builder.AddNamedSystem("add", Adder(2, 1))
        builder.Connect(source.get_output_port(), adder.get_input_port(1))
        builder.ExportInput(adder.get_input_port(0), "u")
        builder.ExportOutput(adder.get_output_port(), "y")
        builder.BuildInto(self)
