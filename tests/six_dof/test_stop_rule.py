"""The 6-DoF loop's stop rule (laws.separation) keeps the 6-DoF semantics:
the contact starts with a contact force, not with noise passing the
compensator's gate in free flight, and a record of a given duration is
returned whole even when the devices never touch."""

from __future__ import annotations

import dataclasses

import pytest

from hybridtable.six_dof.scenario import load_scenario
from hybridtable.six_dof.simulation import simulate6
from tests.examples import EXAMPLES

ON_AXIS = EXAMPLES.parent / "six_dof" / "on_axis.toml"


def _far(**changes):
    p = load_scenario(ON_AXIS, compensator="SDMDC")
    approach = dataclasses.replace(p.approach, initial_gap_m=0.1)
    return dataclasses.replace(p, approach=approach, **changes)


@pytest.mark.parametrize("seed", [0, 1])
def test_noise_through_the_gate_before_contact_does_not_end_the_run(seed):
    # 100 mm of free flight with 1 N of force noise over a 3 N dead band: the
    # gate opens on noise long before the touch.
    run = simulate6(_far(force_noise_n=1.0, force_deadband_n=3.0, seed=seed))
    assert run.metrics is not None
    assert run.metrics.cor_normal == pytest.approx(1.0, abs=0.02)
    assert run.time_s[-1] > 1.0  # the approach alone takes 1 s


def test_a_given_duration_without_contact_is_returned_whole():
    run = simulate6(_far(duration_s=0.2))
    assert run.metrics is None
    assert run.time_s[-1] == pytest.approx(0.199)
