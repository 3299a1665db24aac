"""The loops added to a user's own DiagramBuilder, as the README shows."""

from __future__ import annotations

import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

import hybridtable
from hybridtable.studies.paper import table1_params


def _own(compensator: str):
    builder = DiagramBuilder()
    loop = hybridtable.add_hybrid_loop(builder, table1_params(compensator))
    builder.AddSystem(ConstantVectorSource([0.0]))  # something of the user's beside it
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    return loop, simulator, context


def test_the_readme_flow_gives_simulates_cor_exactly(paper_run):
    """Own builder, own Simulator (its default integrator), collect_result: the
    CoR of simulate() (RK3 at 1e-8, stopped at separation) to 1e-9 (measured
    1.2e-12)."""
    loop, simulator, context = _own("SDMDC")
    simulator.AdvanceTo(1.0)
    mine = hybridtable.collect_result(loop, context)
    assert mine.metrics.cor == pytest.approx(paper_run("SDMDC").metrics.cor, abs=1e-9)
    assert mine.f_act_n[-1] == 0.0 and len(mine.time_s) == len(mine.f_mea_n)


def test_a_record_cut_mid_contact_is_refused_not_read():
    loop, simulator, context = _own("none")
    simulator.AdvanceTo(0.3)
    with pytest.raises(hybridtable.SimulationError, match="while a force still acts"):
        hybridtable.collect_result(loop, context)


def test_run_loop_on_a_loop_in_ones_own_builder_says_what_to_do():
    builder = DiagramBuilder()
    loop = hybridtable.add_hybrid_loop(builder, table1_params("none"))
    builder.Build()
    with pytest.raises(ValueError, match=r"set loop\.diagram = builder\.Build\(\)"):
        hybridtable.run_loop(loop)


def test_the_docking_loop_in_ones_own_builder():
    """The 6-DoF loop's initial conditions need only the root context."""
    from hybridtable.six_dof.builder import add_docking_loop
    from hybridtable.six_dof.simulation import simulate6
    from tests.six_dof.conftest import docking_params

    params = docking_params(duration_s=0.05)
    builder = DiagramBuilder()
    loop = add_docking_loop(builder, params)
    simulator = Simulator(builder.Build())
    loop.set_initial_conditions(simulator.get_mutable_context())
    simulator.AdvanceTo(0.05)
    with pytest.raises(ValueError, match="loop.diagram is None"):
        simulate6(params, loop=loop)
