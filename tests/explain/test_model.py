"""explain's CoR of a row is the physics core's: a sampled rig computer whose
delay falls between two ticks gives the CoR of the Drake diagram of that loop,
whether the table states the delay or an effect moves it there."""

from __future__ import annotations

import math

import pytest

from hybridtable import simulate
from hybridtable.effects.registry import get_effect
from hybridtable.explain.conditions import Conditions
from hybridtable.explain.model import CorModel, EffectAt, table_scale
from hybridtable.studies.paper import table1_params

#: The rig computer's rate, Hz, and its lead, s (a whole number of ticks).
RATE_HZ = 1000.0
LEAD_S = 0.003


def _diagram_ln_cor(compensator: str, delay_s: float) -> float:
    p = table1_params(
        compensator, sample_rate_hz=RATE_HZ, sensor_delay_s=delay_s, lead_time_s=LEAD_S
    )
    return math.log(simulate(p).metrics.cor)


@pytest.mark.parametrize("compensator", ["none", "SDMDC"])
def test_a_stated_delay_between_ticks_is_the_diagrams_loop(compensator):
    case = (
        compensator,
        Conditions(sensor_delay_s=0.0034, lead_time_s=LEAD_S, sample_rate_hz=RATE_HZ),
    )
    [predicted] = CorModel([]).predict_values([case], {})
    assert predicted == pytest.approx(_diagram_ln_cor(compensator, 0.0034), abs=1e-8)


def test_an_extra_delay_to_between_ticks_is_the_diagrams_loop_of_that_delay():
    # 3 ms stated, 0.4 ms more: the sensor reads 3.4 ms late, the lead stays 3 ms.
    # (Interpolating ln CoR between 3 and 4 ms instead gives 0.00404 against the
    # loop's 0.00361 for SDMDC: 12 % off.)
    case = ("SDMDC", Conditions(sensor_delay_s=0.003, lead_time_s=LEAD_S, sample_rate_hz=RATE_HZ))
    at = EffectAt(get_effect("extra_delay"), table_scale([case]))
    [predicted] = CorModel([at]).predict_values([case], {"extra_delay_s": 0.0004})
    assert predicted == pytest.approx(_diagram_ln_cor("SDMDC", 0.0034), abs=1e-8)
    [stated] = CorModel([]).predict_values([case], {})
    assert predicted > stated  # a longer delay pumps more energy in
