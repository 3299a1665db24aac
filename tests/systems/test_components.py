"""A component is one statement of its primitives: built alone (a Diagram with
named ports) or added flat into a loop (a Block with the same ports), and the
loop runs the same either way, to the last bit."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from hybridtable._components import Block, add_component, eval_output, input_ports
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import LOG_ROWS, run_loop
from hybridtable.studies.paper import table1_params
from hybridtable.systems.spacecraft import Spacecraft, SpacecraftParams


@pytest.mark.parametrize(
    "compensator, rate_hz", [("SDMDC", None), ("none", None), ("SDMDC", 1000.0)]
)
def test_the_flat_loop_runs_as_the_nested_one_to_the_last_bit(compensator, rate_hz):
    params = table1_params(compensator, sample_rate_hz=rate_hz)
    flat = run_loop(build_hybrid_loop(params))
    nested = run_loop(build_hybrid_loop(params, flat=False))
    assert flat.steps == nested.steps
    for name in ("time_s", *(n for n in LOG_ROWS if n != "a_act_m_per_s2")):
        np.testing.assert_array_equal(getattr(flat, name), getattr(nested, name))
    assert flat.metrics.cor == nested.metrics.cor


def test_a_component_alone_and_flat_has_the_same_ports_and_state():
    alone = Spacecraft(SpacecraftParams(mass_kg=2.0), sample_period_s=0.5)
    assert alone.GetInputPort("force").size() == 1
    assert alone.GetOutputPort("state").size() == 2
    builder = DiagramBuilder()
    block = add_component(builder, "spacecraft", alone)
    assert isinstance(block, Block) and block.get_name() == "spacecraft"
    assert [p.size() for p in input_ports(block, "force")] == [1]
    builder.ExportInput(block.GetInputPort("force"), "force")
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    block.set_initial_state(context, 1.0, 3.0)
    diagram.get_input_port(0).FixValue(context, [4.0])
    np.testing.assert_array_equal(eval_output(block, "state", context), [1.0, 3.0])
    # One tick of the rig computer's semi-implicit Euler: v = 3 - 4 * 0.5 / 2 = 2,
    # then p = 1 + 2 * 0.5 = 2.
    diagram.CalcForcedDiscreteVariableUpdate(context, context.get_mutable_discrete_state())
    np.testing.assert_allclose(eval_output(block, "state", context), [2.0, 2.0])
    # Its attributes are the component's; its System methods would be the
    # component's own diagram's, which is not in this one: refused in words.
    assert block.params.mass_kg == 2.0
    with pytest.raises(AttributeError, match="added flat"):
        block.GetMyContextFromRoot(context)
    # Not flat: the component's diagram itself.
    builder = DiagramBuilder()
    whole = add_component(builder, "spacecraft", Spacecraft(SpacecraftParams(2.0)), flat=False)
    assert isinstance(whole, Spacecraft)
