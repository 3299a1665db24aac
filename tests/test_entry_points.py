"""A package of one's own adds a compensator and an effect through REAL entry
points: a module and its ``*.dist-info`` folder on ``sys.path``, found by
:func:`importlib.metadata.entry_points` like any installed package.

The registries' "loaded" flags and contents are replaced with ``monkeypatch``
for the test and restored after it.
"""

from __future__ import annotations

import sys
import textwrap

import pytest

from hybridtable.compensators import registry as compensators
from hybridtable.effects import registry as effects
from hybridtable.effects.library import BUILTIN_EFFECTS
from hybridtable.errors import ParameterError
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params

#: The plug-in: an SDC under another name, and force_bias under another name.
PLUGIN = '''
"""A demo plug-in of hybridtable."""
from dataclasses import replace

from hybridtable.compensators.paper import Compensator
from hybridtable.effects.library.force_bias import EFFECT as _FORCE_BIAS

CALLS = []


def make_demo_sdc(params, derivative_period_s):
    CALLS.append(derivative_period_s)
    kind = params.with_(compensator="SDC").compensator_params()
    return Compensator(kind, derivative_period_s=derivative_period_s)


DEMO_BIAS = replace(_FORCE_BIAS, name="demo_bias", touches=("demo.bias",))
DUPLICATE = _FORCE_BIAS
'''


def _install(tmp_path, monkeypatch, module: str, entry_points: str) -> None:
    """Write ``module`` (the plug-in) and its dist-info on a fresh ``sys.path``
    entry, and reset both registries to their built-ins, not yet loaded."""
    (tmp_path / f"{module}.py").write_text(PLUGIN, encoding="utf-8")
    dist = tmp_path / f"{module}-0.1.dist-info"
    dist.mkdir()
    name = module.replace("_", "-")
    (dist / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n", encoding="utf-8"
    )
    (dist / "entry_points.txt").write_text(textwrap.dedent(entry_points), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, module, raising=False)
    monkeypatch.setattr(compensators, "_REGISTRY", dict(compensators.BUILTIN))
    monkeypatch.setattr(compensators, "_entry_points_loaded", False)
    monkeypatch.setattr(effects, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})
    monkeypatch.setattr(effects, "_entry_points_loaded", False)


@pytest.fixture
def forget_plugins():
    """Drop the plug-in modules the test imported (monkeypatch restores the rest)."""
    yield
    for module in ("ht_demo_plugin", "ht_dup_plugin"):
        sys.modules.pop(module, None)


def test_entry_points_add_a_compensator_and_an_effect(
    tmp_path, monkeypatch, forget_plugins, paper_run
):
    _install(
        tmp_path,
        monkeypatch,
        "ht_demo_plugin",
        """\
        [hybridtable.compensators]
        demo-sdc = ht_demo_plugin:make_demo_sdc

        [hybridtable.effects]
        demo_bias = ht_demo_plugin:DEMO_BIAS
        """,
    )
    assert "ht_demo_plugin" not in sys.modules  # loaded lazily, on first use
    names = compensators.compensator_names()
    builtin = tuple(compensators.BUILTIN)
    assert names[: len(builtin)] == builtin and "demo-sdc" in names[len(builtin) :]
    plugin = sys.modules["ht_demo_plugin"]

    # Table 1 with the plug-in: the same loop, hence the same CoR, as SDC.
    cor = simulate(table1_params("demo-sdc")).metrics.cor
    assert plugin.CALLS  # the plug-in's factory built the compensator
    assert cor == paper_run("SDC").metrics.cor
    assert cor != paper_run("none").metrics.cor

    builtin_effects = tuple(e.name for e in BUILTIN_EFFECTS)
    names = effects.effect_names()
    assert names[: len(builtin_effects)] == builtin_effects
    assert "demo_bias" in names[len(builtin_effects) :]
    assert effects.user_effect("demo_bias") is plugin.DEMO_BIAS
    assert effects.effect_source("demo_bias") == "entry point"
    # Loaded once: a second use neither reloads nor duplicates.
    assert effects.effect_names() == names
    assert compensators.compensator_names().count("demo-sdc") == 1


def test_an_entry_point_with_a_registered_name_is_refused(tmp_path, monkeypatch, forget_plugins):
    _install(
        tmp_path,
        monkeypatch,
        "ht_dup_plugin",
        """\
        [hybridtable.compensators]
        SDC = ht_dup_plugin:make_demo_sdc

        [hybridtable.effects]
        force_bias = ht_dup_plugin:DUPLICATE
        """,
    )
    with pytest.raises(ParameterError, match="force_bias.*ht_dup_plugin:DUPLICATE"):
        effects.get_effect("force_bias")
    with pytest.raises(ParameterError, match="SDC.*ht_dup_plugin:make_demo_sdc"):
        compensators.compensator_names()
