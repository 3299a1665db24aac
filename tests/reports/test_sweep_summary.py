"""The verdict of a campaign names the compensator closest to an
energy-neutral bounce, not the one with the lowest CoR."""

from __future__ import annotations

import math

import pyarrow as pa

from hybridtable.reports.sweep_summary import summarize, verdict


def _table(rows):
    return pa.Table.from_pylist(rows)


def _row(run, comp, cor, status="ok"):
    return {"run": run, "compensator": comp, "cor": cor, "status": status, "message": ""}


def test_a_loop_that_takes_energy_out_is_not_closest_to_one():
    rows = [
        _row(0, "dissipating", 0.90),
        _row(1, "dissipating", 0.95),
        _row(2, "neutral", 0.999),
        _row(3, "neutral", 1.002),
        _row(4, "pumping", 1.30),
        _row(5, "pumping", math.nan, "diverged"),
    ]
    s = summarize(_table(rows), 6, ("cor",))
    text = verdict("x", s)
    assert text.startswith("sweep x: 5 of 6 runs finished")
    assert "closest to CoR 1: neutral (0.9990 to 1.0020)" in text
    assert "furthest: pumping (1.3000, 1 diverged)" in text
    assert s["compensators"]["dissipating"]["cor_above_1"] == 0
    assert s["compensators"]["neutral"]["cor_above_1"] == 1
    # the worst runs: the diverged one first, then the highest CoR
    assert [r["run"] for r in s["worst"]][:2] == [5, 4]
