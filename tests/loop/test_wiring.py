"""One wiring table: the built loop has exactly its connections, with the port
sizes it declares, and the linear models wire the same channels."""

from __future__ import annotations

import pytest
from pydrake.systems.framework import Diagram

from hybridtable._components import input_ports
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.wiring import LOOP_WIRING, PORT_SIZES, channel_wiring, edge
from hybridtable.studies.paper import table1_params

NAMES = ("spacecraft", "table", "contact", "force_sensor", "compensator")


@pytest.mark.parametrize("sample_rate_hz", [None, 1000.0])
def test_the_built_loop_is_wired_as_the_table_says(sample_rate_hz):
    params = table1_params("SDMDC", sample_rate_hz=sample_rate_hz)
    loop = build_hybrid_loop(params, log=False, flat=False)
    found = set()
    for (dst, in_index), (src, out_index) in loop.diagram.connection_map().items():
        if src.get_name() in NAMES and dst.get_name() in NAMES:
            out_port = src.get_output_port(out_index)
            in_port = dst.get_input_port(in_index)
            found.add((src.get_name(), out_port.get_name(), dst.get_name(), in_port.get_name()))
            assert out_port.size() == PORT_SIZES[out_port.get_name()]
            assert in_port.size() == PORT_SIZES[in_port.get_name()]
    assert found == set(LOOP_WIRING)


def test_channel_wiring_names_every_scalar_of_the_loop():
    c = channel_wiring()
    assert c["table.commanded_state[1]"] == "spacecraft.state[1]"
    assert c["compensator.table_motion[2]"] == "table.motion[2]"
    assert c["spacecraft.force[0]"] == "compensator.compensated_force[0]"
    assert len(c) == sum(PORT_SIZES[e[3]] for e in LOOP_WIRING)


def test_an_edge_the_loop_does_not_have_is_refused():
    with pytest.raises(KeyError, match="no connection"):
        edge("contact.force", "spacecraft.force")


@pytest.mark.parametrize("sample_rate_hz", [None, 1000.0])
def test_the_flat_loop_connects_every_edge_to_every_primitive_it_feeds(sample_rate_hz):
    params = table1_params("SDMDC", sample_rate_hz=sample_rate_hz)
    loop = build_hybrid_loop(params, log=False)
    assert all(not isinstance(s, Diagram) for s in loop.diagram.GetSystems())
    connections = loop.diagram.connection_map()
    parts = dict(
        zip(
            NAMES,
            (loop.spacecraft, loop.table, loop.contact, loop.sensor, loop.compensator),
            strict=True,
        )
    )
    wired = 0
    for src, out_name, dst, in_name in LOOP_WIRING:
        out_port = parts[src].GetOutputPort(out_name)
        assert out_port.size() == PORT_SIZES[out_name]
        for in_port in input_ports(parts[dst], in_name):
            assert in_port.size() == PORT_SIZES[in_name]
            source = connections[(in_port.get_system(), in_port.get_index())]
            assert source == (out_port.get_system(), out_port.get_index())
            wired += 1
    # Each edge feeds its port; in the continuous loop the measured force also
    # the compiled compensator's hold of the last tick's sample (a sampled rig
    # computer's compensator is one system holding it itself).
    assert wired == len(LOOP_WIRING) + (sample_rate_hz is None)
