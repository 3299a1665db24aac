"""An effect whose system a table's rig computer cannot carry is left out, with why,
not fitted as a loop that fails at every value where it acts."""

from __future__ import annotations

from pathlib import Path

from hybridtable.effects.registry import get_effect
from hybridtable.explain.explain import explain_table
from hybridtable.explain.table import read_cor_table

TABLE1 = Path(__file__).resolve().parents[2] / "examples" / "explain" / "table1_simulation.csv"


def test_a_sensor_filter_on_a_continuous_rig_computer_is_left_out_with_why():
    # Table 1 states no sample rate: a continuous rig computer, and a sensor's
    # low pass is a system of a sampled one.
    expl = explain_table(
        read_cor_table(TABLE1),
        [get_effect("sensor_filter"), get_effect("extra_delay")],
        max_effects=1,
    )
    assert set(expl.cannot_run) == {"sensor_filter"}
    assert "sample rate" in expl.cannot_run["sensor_filter"]
    assert {f.effects for f in expl.fits} == {(), ("extra_delay",)}
    listed = expl.to_dict()["not_fitted"]
    assert {"effects": ["sensor_filter"], "why": expl.cannot_run["sensor_filter"]} in listed
