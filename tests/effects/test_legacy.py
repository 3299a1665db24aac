"""An old CoR effect (``CorEffect`` of ``hybridtable.explain``) still registers,
with a deprecation warning, and changes a CoR row's loop as it did."""

from __future__ import annotations

import pytest

from hybridtable.effects import registry
from hybridtable.effects.library import BUILTIN_EFFECTS
from hybridtable.explain import CorEffect, CorParameter, register_cor_effect
from hybridtable.explain.conditions import Conditions
from hybridtable.explain.model import EffectAt, loop_of, table_scale

OLD = CorEffect(
    "old_deadband",
    "the rig computer applies no force while the reading is at or below a deadband",
    (CorParameter("force_deadband_n", "N", 0.0, 0.0, 50.0, 1.0, quantity="deadband"),),
    lambda conditions, params, values: params.with_(
        force_deadband_n=values["force_deadband_n"] + 0.0 * conditions.sensor_delay_s
    ),
)


@pytest.fixture
def builtins_only(monkeypatch):
    monkeypatch.setattr(registry, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})


def test_an_old_cor_effect_registers_with_a_warning_and_explain_tries_it(builtins_only):
    with pytest.warns(DeprecationWarning, match="register_effect"):
        effect = register_cor_effect(OLD)
    assert registry.get_effect("old_deadband") is effect
    assert "old_deadband" in registry.default_effects("explain")
    assert "old_deadband" not in registry.default_effects("diagnose")
    assert effect.stage == "closed_loop" and effect.parameters[0].quantity == "deadband"


def test_an_old_cor_effect_changes_the_loop_as_its_apply_says(builtins_only):
    with pytest.warns(DeprecationWarning):
        effect = register_cor_effect(OLD)
    case = ("SDMDC", Conditions(sample_rate_hz=1000.0))
    at = EffectAt(effect, table_scale([case]))
    params, systems = loop_of(case, (at,), {"force_deadband_n": 12.5})
    assert systems is None  # a change of the loop's parameters: the fast engine runs it
    assert params.force_deadband_n == 12.5
    # the stated loop, at its rig computer's rate, with the dead band changed
    stated = case[1].loop_params("SDMDC")
    assert params.sample_rate_hz == 1000.0
    assert params.with_(force_deadband_n=stated.force_deadband_n) == stated
