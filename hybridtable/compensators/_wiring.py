"""Wiring helpers shared by the compensator plug-ins."""

from __future__ import annotations

from pydrake.systems.framework import DiagramBuilder, InputPort, OutputPort, System

from hybridtable.compensators.paper import COMPENSATOR_INPUTS
from hybridtable.systems.sensor import ForceSensorDelay

__all__ = ["COMPENSATOR_INPUTS", "export_compensator_ports", "sensor_like_delay"]


def export_compensator_ports(
    builder: DiagramBuilder,
    inputs: dict[str, list[InputPort]],
    output: OutputPort,
    extra_outputs: dict[str, OutputPort] | None = None,
) -> None:
    """Export the compensator's four inputs (each fanned out to the listed
    inner ports, at least one each) and its ``compensated_force`` output."""
    for name in COMPENSATOR_INPUTS:
        ports = inputs[name]
        index = builder.ExportInput(ports[0], name)
        for port in ports[1:]:
            builder.ConnectInput(index, port)
    builder.ExportOutput(output, "compensated_force")
    for name, port in (extra_outputs or {}).items():
        builder.ExportOutput(port, name)


def sensor_like_delay(params, size: int = 3) -> System:
    """A delay of ``size`` channels built exactly like the loop's default
    force sensor for ``params`` (a :class:`~hybridtable.loop.params.HybridLoopParams`):
    a signal through it is read by the rig computer at the same instants as
    the measured force (same delay line, same period)."""
    if params.sample_period_s is None:
        return ForceSensorDelay(params.rig.sensor, "continuous", params.step_s, size=size)
    return ForceSensorDelay(params.rig.sensor, "sampled", params.sample_period_s, size=size)
