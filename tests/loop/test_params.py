"""The compensator believes the truth unless told, and keeps believing it
through a change of the physics: the one rule
(:meth:`~hybridtable.loop.params.HybridLoopParams.beliefs`,
:meth:`~hybridtable.loop.params.HybridLoopParams.with_physics`), and the places
that use it (the rig's physics changes, the CoR effects)."""

from __future__ import annotations

import pytest

from hybridtable.effects.registry import get_effect
from hybridtable.effects.spec import ModelSpec
from hybridtable.errors import ParameterError
from hybridtable.explain.conditions import Conditions
from hybridtable.loop.params import BELIEFS, HybridLoopParams
from hybridtable.measurement.rig import RigPhysics

#: A loop whose compensator is told nothing: it believes the truth.
UNTOLD = HybridLoopParams(
    spacecraft_mass_kg=2500.0,
    contact_stiffness_n_per_m=1.0e5,
    contact_damping_n_s_per_m=300.0,
    sensor_delay_s=0.005,
    table_response_hz=25.0,
    compensator="SDMDC",
)

#: What UNTOLD's compensator believes.
TRUTH = {
    "lead_time_s": 0.005,
    "compensator_stiffness_n_per_m": 1.0e5,
    "compensator_damping_n_s_per_m": 300.0,
}

#: A change of each true value a belief stands for.
PHYSICS_CHANGES = {
    "sensor_delay_s": 0.008,
    "contact_stiffness_n_per_m": 2.0e5,
    "contact_damping_n_s_per_m": 900.0,
}


class _OnTheLoop:
    """An effect of the one library applied to a loop's parameters, as a CoR row's loop."""

    def __init__(self, name: str) -> None:
        self.effect = get_effect(name)

    def apply(self, conditions, params, values):
        spec = self.effect.apply(ModelSpec(), values, None)
        out, systems = spec.realize(params)
        assert systems is None
        return out


def _effect(name: str):
    return _OnTheLoop(name)


def test_untold_beliefs_are_the_true_values():
    assert set(BELIEFS) == set(TRUTH)
    assert UNTOLD.beliefs() == TRUTH
    comp = UNTOLD.compensator_params()
    assert (comp.lead_time_s, comp.stiffness_n_per_m, comp.damping_n_s_per_m) == (
        0.005,
        1.0e5,
        300.0,
    )


def test_told_beliefs_are_kept():
    told = UNTOLD.with_(
        lead_time_s=0.003, compensator_stiffness_n_per_m=5.0e4, compensator_damping_n_s_per_m=0.0
    )
    assert told.beliefs() == {
        "lead_time_s": 0.003,
        "compensator_stiffness_n_per_m": 5.0e4,
        "compensator_damping_n_s_per_m": 0.0,
    }
    assert told.with_physics(**PHYSICS_CHANGES).beliefs() == told.beliefs()


def test_untold_beliefs_follow_the_truth_but_not_through_a_physics_change():
    assert UNTOLD.with_(**PHYSICS_CHANGES).beliefs() == {
        "lead_time_s": 0.008,
        "compensator_stiffness_n_per_m": 2.0e5,
        "compensator_damping_n_s_per_m": 900.0,
    }
    changed = UNTOLD.with_physics(**PHYSICS_CHANGES)
    assert changed.beliefs() == TRUTH
    assert (changed.sensor_delay_s, changed.contact_stiffness_n_per_m) == (0.008, 2.0e5)
    assert changed.contact_damping_n_s_per_m == 900.0
    assert UNTOLD.with_beliefs_pinned().beliefs() == TRUTH
    assert UNTOLD.with_beliefs_pinned().compensator_params() == UNTOLD.compensator_params()


def test_a_belief_is_not_physics():
    with pytest.raises(ParameterError, match="compensator_stiffness_n_per_m"):
        UNTOLD.with_physics(compensator_stiffness_n_per_m=1.0e4)


@pytest.mark.parametrize("name", list(PHYSICS_CHANGES))
def test_the_rig_physics_change_keeps_the_beliefs(name):
    """RigPhysics.changes (a model's effects on the rig) through the same rule."""
    value = PHYSICS_CHANGES[name]
    changed = RigPhysics(changes={name: value}).apply(UNTOLD)
    assert getattr(changed, name) == value
    assert changed.beliefs() == TRUTH
    assert changed == UNTOLD.with_physics(**{name: value})
    # The rig computer's own values (an audit's) are set after the physics.
    audited = RigPhysics(changes={name: value}, computer={"lead_time_s": 0.002}).apply(UNTOLD)
    assert audited.beliefs() == {**TRUTH, "lead_time_s": 0.002}


@pytest.mark.parametrize(
    ("effect", "values", "changed"),
    [
        ("extra_delay", {"extra_delay_s": 0.003}, ("sensor_delay_s", 0.008)),
        ("contact_damping", {"damping_n_s_per_m": 600.0}, ("contact_damping_n_s_per_m", 900.0)),
    ],
)
def test_a_cor_effect_on_the_physics_keeps_the_beliefs(effect, values, changed):
    """The CoR effects that change the loop's physics, through the same rule."""
    out = _effect(effect).apply(Conditions(), UNTOLD, values)
    name, value = changed
    assert getattr(out, name) == pytest.approx(value, rel=1e-12)
    assert out.beliefs() == TRUTH


def test_cor_effects_on_the_beliefs_start_from_the_resolved_ones():
    lead = _effect("lead_time_error").apply(Conditions(), UNTOLD, {"lead_error_s": 0.001})
    assert lead.lead_time_s == pytest.approx(0.006, rel=1e-12)
    stiff = _effect("compensator_stiffness_error").apply(
        Conditions(), UNTOLD, {"compensator_stiffness_ratio": 0.5}
    )
    assert stiff.compensator_stiffness_n_per_m == 5.0e4


def test_stated_conditions_with_hidden_damping_compensate_an_undamped_contact():
    """The stated loop of a CoR table is undamped: the hidden damper is not
    compensated, the stated lead and stiffness stay (the CoR effects' numbers)."""
    stated = Conditions().loop_params("SDMDC")
    out = _effect("contact_damping_ratio").apply(
        Conditions(), stated, {"contact_damping_ratio": 0.1}
    )
    assert out.compensator_params().damping_n_s_per_m == 0.0
    assert out.contact_damping_n_s_per_m > 0.0
    assert out.beliefs()["compensator_stiffness_n_per_m"] == stated.contact_stiffness_n_per_m
