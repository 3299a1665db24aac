"""The fast engine's held ticks: the compiled loop is the Python loop, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import hybridtable.loop.ticks as ticks
from hybridtable.errors import DivergenceError
from hybridtable.laws.compiled import compiled_available
from hybridtable.loop import fast
from hybridtable.loop.fast import simulate_fast
from hybridtable.studies.paper import paper_params, table1_params

pytestmark = pytest.mark.skipif(not compiled_available(), reason="numba is not installed")

#: Held loops (the force law cannot switch inside a tick): the paper's four
#: compensators, a dead band, a clamp, a slow table, a long run that outgrows
#: the first records, a delay of many ticks; and loops whose law switches inside
#: a tick (no delay, the table-position gate, a clamp on the MDC term), where the
#: compiled loop hands each switch to Python.
CASES = {
    "none": table1_params("none"),
    "SDC": table1_params("SDC"),
    "MDC": table1_params("MDC"),
    "SDMDC": table1_params("SDMDC"),
    "deadband": table1_params("SDMDC").with_(force_deadband_n=5.0),
    "clamp-sdc": table1_params("SDC").with_(clamp_nonnegative=True),
    "slow-table": table1_params("SDMDC").with_(table_response_hz=12.0, table_damping_ratio=0.5),
    "long": table1_params("SDC").with_(
        contact_stiffness_n_per_m=4.0e4, initial_velocity_m_per_s=0.02
    ),
    "long-delay": table1_params("MDC").with_(sensor_delay_s=0.04),
    "undelayed": table1_params("SDMDC").with_(sensor_delay_s=0.0),
    "undelayed-deadband": table1_params("MDC").with_(sensor_delay_s=0.0, force_deadband_n=3.0),
    "table-gate": table1_params("SDMDC").with_(contact_gate="table_position"),
    "clamp-mdc": table1_params("SDMDC").with_(clamp_nonnegative=True),
    "clamp-gate-slow-table": table1_params("MDC").with_(
        clamp_nonnegative=True, contact_gate="table_position", table_response_hz=15.0
    ),
}


def _run(params, compiled: bool, monkeypatch):
    monkeypatch.setattr(ticks, "COMPILE_AFTER_RUNS", 0 if compiled else 10**12)
    return simulate_fast(params)


@pytest.mark.parametrize("name", list(CASES))
def test_compiled_ticks_equal_the_python_ticks_bit_for_bit(name, monkeypatch):
    python = _run(CASES[name], False, monkeypatch)
    compiled = _run(CASES[name], True, monkeypatch)
    assert python.to_dict() == compiled.to_dict()
    assert python.cor == compiled.cor  # no tolerance: the same operations in the same order


def test_a_run_that_outgrows_its_records_keeps_them(monkeypatch):
    """Records grown many times (from room for 256 ticks) are the records of a
    run with room enough, compiled or not."""
    params = CASES["long"]
    h, n = fast._computer_period(params)

    def records(compiled: bool) -> list[np.ndarray]:
        monkeypatch.setattr(ticks, "COMPILE_AFTER_RUNS", 0 if compiled else 10**12)
        rule = fast.separation_rule(params, h, kind=fast._StopRule, period_s=h)
        return [np.asarray(x) for x in fast._run_continuous(params, h, n, rule)]

    roomy = records(True)
    monkeypatch.setattr(fast, "RECORD_ROOM", 256)
    grown = [records(False), records(True)]
    assert len(roomy[0]) > 8 * 256  # grown by half again at least six times
    for run in grown:
        for a, b in zip(run, roomy, strict=True):
            np.testing.assert_array_equal(a, b)


def test_a_diverging_loop_stops_alike_in_both(monkeypatch):
    # No compensation, a delay of 0.5 s on a 50 Hz contact (tests/loop/test_fast.py).
    params = paper_params(sensor_delay_s=0.5, contact_frequency_hz=50.0, time_step_s=2e-4)
    errors = []
    for compiled in (False, True):
        with pytest.raises(DivergenceError) as err:
            _run(params, compiled, monkeypatch)
        errors.append(str(err.value))
    assert errors[0] == errors[1]


def test_a_process_compiles_only_after_its_first_runs(monkeypatch):
    monkeypatch.setattr(ticks, "_runs", 0)
    monkeypatch.setattr(ticks, "_COMPILED", {})
    monkeypatch.setattr(ticks, "COMPILE_AFTER_RUNS", 2)
    assert [ticks.tick_loop("measured_force", True)[1] for _ in range(4)] == [
        False,
        False,
        True,
        True,
    ]


def test_a_loop_compiled_before_a_fork_is_used_from_the_first_run(monkeypatch):
    monkeypatch.setattr(ticks, "_runs", 0)
    monkeypatch.setattr(ticks, "_COMPILED", {})
    assert ticks.compile_loops([("measured_force", False), ("measured_force", False)]) == 1
    assert ticks.tick_loop("measured_force", False)[1] is True  # the first run: compiled
    assert ticks.tick_loop("table_position", False)[1] is False  # another law: Python first
