"""The plausible ranges: one table for parameters, JSON keys, channels and flags."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from hybridtable.errors import ParameterError
from hybridtable.limits import LIMITS, check_plausible, limit_words
from hybridtable.loop.params import FIELDS, HybridLoopParams
from hybridtable.measurement.run_format import RUN_COLUMNS, RUN_KEYS

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_number_a_user_gives_has_a_range():
    numbers = [k for k, kind in RUN_KEYS.items() if kind == "number"]
    assert set(numbers) <= set(LIMITS)
    words = {
        "compensator",
        "contact_gate",
        "table_initial_state",
        "clamp_nonnegative",
        "passivity",
        "computer_integrator",
    }
    given_state = {"table_initial_position_m", "table_initial_velocity_m_per_s"}
    assert set(FIELDS) - words - given_state <= set(LIMITS)
    assert set(RUN_COLUMNS) - {"time_s"} <= set(LIMITS)
    for name, limit in LIMITS.items():
        assert limit.low < limit.high, name
        assert name.endswith(("_kg", "_n_per_m", "_n_s_per_m", "_hz", "_s", "_m", "_n", "_ratio"))


@pytest.mark.parametrize("name", sorted(LIMITS))
def test_ends_are_accepted_and_beyond_is_refused_in_one_line(name):
    limit = LIMITS[name]
    assert check_plausible(name, limit.low) == limit.low
    assert check_plausible(name, limit.high) == limit.high
    beyond = [limit.high * 10 if limit.high > 0 else 1.0, math.nan, "abc", True]
    beyond.append(limit.low - 1.0 if limit.low <= 0 else limit.low / 10)
    for value in beyond:
        with pytest.raises(ParameterError) as exc:
            check_plausible(name, value, where="run1.json")
        text = str(exc.value)
        assert text.startswith(f"run1.json: {name}") and "\n" not in text
    assert limit.contains(math.inf) == limit.ideal_inf


def test_parameters_refuse_absurd_values_naming_the_field():
    base = dict(spacecraft_mass_kg=675.0, contact_stiffness_n_per_m=6e4)
    with pytest.raises(ParameterError, match=r"^table_response_hz = 1e\+06 Hz is outside"):
        HybridLoopParams(**base, table_response_hz=1e6)
    HybridLoopParams(**base, table_response_hz=math.inf)  # the ideal table
    for name in sorted(set(FIELDS) & set(LIMITS)):  # every loop quantity, in whichever config
        with pytest.raises(ParameterError, match=f"^{name} "):
            HybridLoopParams(**{**base, name: LIMITS[name].high * 10})
    with pytest.raises(ParameterError, match="makes spacecraft_mass_kg = 2.53e"):
        HybridLoopParams.from_contact_frequency(1e-3, 1e10)


def test_the_run_format_documents_every_keys_range():
    text = (DOCS / "run-format.md").read_text()
    for key, kind in RUN_KEYS.items():
        if kind != "number":
            continue
        row = re.search(rf"^\| `{key}` \|.*$", text, re.M)
        assert row, key
        assert limit_words(key) in row.group(0), (key, row.group(0))
