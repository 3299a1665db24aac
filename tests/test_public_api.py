"""The names users import from the top-level package keep working, and each is
the very object of the subpackage that defines it."""

from __future__ import annotations

import importlib

import pytest

import hybridtable

#: What ``from hybridtable import ...`` offered before the packages were split
#: (main 0fc9224): removing one breaks users' scripts.
PUBLIC = {
    "COMPENSATORS": "hybridtable.compensators.paper",
    "Compensator": "hybridtable.compensators.paper",
    "CompensatorParams": "hybridtable.compensators.paper",
    "ContactMetrics": "hybridtable.loop.metrics",
    "ContactParams": "hybridtable.systems.contact",
    "ForceSensorDelay": "hybridtable.systems.sensor",
    "HybridLoop": "hybridtable.loop.builder",
    "HybridLoopParams": "hybridtable.loop.params",
    "ParameterError": "hybridtable.errors",
    "SecondOrderTable": "hybridtable.systems.table",
    "SensorParams": "hybridtable.systems.sensor",
    "SimulationError": "hybridtable.errors",
    "SimulationResult": "hybridtable.loop.simulation",
    "Spacecraft": "hybridtable.systems.spacecraft",
    "SpacecraftParams": "hybridtable.systems.spacecraft",
    "TableParams": "hybridtable.systems.table",
    "UnilateralSpringContact": "hybridtable.systems.contact",
    "add_hybrid_loop": "hybridtable.loop.builder",
    "build_hybrid_loop": "hybridtable.loop.builder",
    "contact_metrics": "hybridtable.loop.metrics",
    "run_loop": "hybridtable.loop.simulation",
    "simulate": "hybridtable.loop.simulation",
}


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_top_level_name_is_the_subpackage_object(name):
    assert name in hybridtable.__all__
    home = importlib.import_module(PUBLIC[name])
    assert getattr(hybridtable, name) is getattr(home, name)


def test_every_package_all_is_importable():
    for package in (
        "hybridtable",
        "hybridtable.systems",
        "hybridtable.compensators",
        "hybridtable.loop",
        "hybridtable.measurement",
        "hybridtable.stewart",
        "hybridtable.analysis",
        "hybridtable.diagnosis",
        "hybridtable.studies",
    ):
        module = importlib.import_module(package)
        missing = [n for n in module.__all__ if not hasattr(module, n)]
        assert missing == [], f"{package}.__all__ names what it does not define: {missing}"


def test_the_table1_point_through_the_facade():
    # The facade and the subpackages run the same loop: Table 1, no compensation.
    from hybridtable.studies.paper import table1_params

    result = hybridtable.simulate(table1_params("none"))
    assert result.metrics.cor == pytest.approx(1.16115, abs=5e-5)
