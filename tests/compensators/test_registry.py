"""The compensator registry: the paper's four then the plug-ins, user factories,
entry points, and every registered compensator under AutoDiff.
"""

from __future__ import annotations

import pytest

from hybridtable import Compensator, HybridLoopParams, ParameterError
from hybridtable.compensators.paper import COMPENSATORS
from hybridtable.compensators.registry import (
    compensator_names,
    make_compensator,
    register_compensator,
)
from hybridtable.compensators.smith import make_smith
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.simulation import run_loop, simulate
from hybridtable.studies.paper import table1_params
from tests.compensators.support import PLUGINS


def test_registry_holds_the_paper_compensators_then_the_plugins():
    names = compensator_names()
    assert names[:4] == COMPENSATORS
    assert set(PLUGINS) <= set(names)
    for name in PLUGINS:
        assert (
            HybridLoopParams(
                spacecraft_mass_kg=1.0, contact_stiffness_n_per_m=1.0, compensator=name
            ).compensator
            == name
        )
    with pytest.raises(ParameterError, match="smith"):  # the message lists the choices
        HybridLoopParams(
            spacecraft_mass_kg=1.0, contact_stiffness_n_per_m=1.0, compensator="nonesuch"
        )
    with pytest.raises(ValueError, match="already registered"):
        register_compensator("smith", make_smith)
    with pytest.raises(ValueError, match="already registered"):
        register_compensator("SDMDC", make_smith, replace=True)


def test_a_registered_factory_builds_the_loop_compensator(paper_run):
    from hybridtable.compensators import registry

    calls = []

    def factory(params, period):
        calls.append(period)
        return Compensator(params.with_(compensator="SDC").compensator_params(), period)

    register_compensator("test-sdc", factory)
    try:
        p = table1_params("test-sdc")
        cor = simulate(p).metrics.cor
        assert calls and calls[0] == build_hybrid_loop(p, log=False).computer_period_s
        assert cor == paper_run("SDC").metrics.cor
    finally:
        del registry._REGISTRY["test-sdc"]


@pytest.mark.parametrize("name", ["none", "SDMDC"])
def test_paper_compensators_unchanged_by_the_registry(name, paper_run):
    p = table1_params(name)
    h = build_hybrid_loop(p, log=False).computer_period_s
    direct = Compensator(p.compensator_params(), derivative_period_s=h)
    cor = paper_run(name).metrics.cor
    assert cor == run_loop(build_hybrid_loop(p, compensator=direct)).metrics.cor


def test_plugins_convert_to_autodiff():
    p = table1_params("sdmdc-online", sample_rate_hz=1e3)
    for name in PLUGINS:
        assert make_compensator(p.with_(compensator=name), 1e-3).ToAutoDiffXd() is not None
    assert make_compensator(p.with_(passivity=True), 1e-3).ToAutoDiffXd() is not None
