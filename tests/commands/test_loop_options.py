"""The loop options' defaults and units come from one place: the Table 1 point
(``limits.TABLE1_DEFAULTS``), the loop's own defaults, and ``limits.LIMITS``."""

from __future__ import annotations

import math

from hybridtable.commands._loop_options import EXTRA_OPTIONS, LOOP_OPTIONS
from hybridtable.explain.conditions import PAPER_CONDITIONS
from hybridtable.limits import LIMITS, TABLE1_DEFAULTS
from hybridtable.loop.params import HybridLoopParams
from hybridtable.studies.paper import load_tables, paper_params
from hybridtable.sweeps.inputs import DEFAULTS


def test_every_option_default_is_the_loop_it_makes():
    p = paper_params()
    # Every quantity the loop defaults (all but the plant's two it needs).
    field_defaults = HybridLoopParams(spacecraft_mass_kg=2500.0, contact_stiffness_n_per_m=1e5)
    field_defaults = field_defaults.quantities()
    for name, (default, unit, _) in {**LOOP_OPTIONS, **EXTRA_OPTIONS}.items():
        assert unit == LIMITS[name].unit
        if name in TABLE1_DEFAULTS:
            assert default == TABLE1_DEFAULTS[name]
        if default is None or name == "contact_damping_ratio":
            continue
        # What a run left at its defaults simulates.
        assert math.isclose(getattr(p, name), default, rel_tol=1e-12), name
        if name not in TABLE1_DEFAULTS:
            assert default == field_defaults[name], name


def test_the_table1_point_is_the_papers_and_every_default_of_it():
    stated = load_tables()["table1_simulation"]["parameters"]
    assert {k: float(v) for k, v in stated.items()} == TABLE1_DEFAULTS
    assert DEFAULTS == TABLE1_DEFAULTS
    for name, value in TABLE1_DEFAULTS.items():
        assert PAPER_CONDITIONS[name] == value
