"""The words of ``hybridtable compensators``: the verdict names the compensator
closest to the ideal loop beside SDMDC and no compensation, the checks are
plain sentences, and every compensator keeps one colour."""

from __future__ import annotations

import math

from hybridtable.reports.compensators import (
    compensator_colours,
    format_checks,
    format_summary,
    sweep_verdict,
)
from hybridtable.studies.compensator_sweep import SweepResult, SweepSettings


def _run(comp, cor, ratio=1.0, guard=False, scenario="mismatch", point=0, ref=1.0):
    return {
        "point": point,
        "scenario": scenario,
        "compensator": comp,
        "prior_ratio": ratio,
        "passivity": guard,
        "error": None,
        "cor": cor,
        "cor_reference": ref,
        "cor_error": cor - ref,
        "peak_force_error": 0.0,
        "energy_drift": cor**2 - ref**2,
        "energy_created": max(0.0, cor**2 - 1.0),
    }


def _sweep(runs, points=1) -> SweepResult:
    comps = tuple(dict.fromkeys(r["compensator"] for r in runs))
    settings = SweepSettings(compensators=comps, prior_ratios=(0.5, 1.0), scenarios=("mismatch",))
    return SweepResult(settings, [{}] * points, runs, [])


def test_the_verdict_names_the_closest_beside_sdmdc_and_no_compensation():
    runs = [
        _run("none", 1.16115),
        _run("none", 1.0, guard=True),
        _run("SDMDC", 1.0515, ratio=0.5),
        _run("SDMDC", 1.00003),
        _run("polynomial", 0.99477),
    ]
    line = sweep_verdict(_sweep(runs))
    # none +passivity is exact here (an undamped contact guarded to CoR 1).
    assert line == (
        "Closest to the ideal loop at the Table 1 point under a believed stiffness 0.5-1x the "
        "true one: none +passivity (worst |CoR error| 0.000); SDMDC leaves 0.052, no "
        "compensation 0.161 (kinetic energy +35%)"
    )
    assert format_summary(_sweep(runs)).splitlines()[0] == line
    assert sweep_verdict(_sweep(runs[2:], points=11)).startswith(
        "Closest to the ideal loop over the 11 grid points under a believed stiffness 0.5-1x "
        "the true one: polynomial (worst |CoR error| 0.005)"
    )


def test_a_failed_run_never_wins():
    failed = dict(_run("sdmdc-online", math.nan), error="diverged")
    line = sweep_verdict(_sweep([failed, _run("SDMDC", 1.01)]))
    assert line.startswith("Closest to the ideal loop at the Table 1 point under")
    assert ": SDMDC (worst" in line


def test_the_checks_are_sentences_that_say_when_they_do_not_hold():
    good = [
        _run("sdmdc-online", 1.00001, ratio=0.5),
        _run("sdmdc-online", 1.00002),
        _run("SDMDC", 1.0515, ratio=0.5),
        _run("SDMDC", 0.9955, guard=True),
    ]
    assert format_checks(_sweep(good)) == [
        "sdmdc-online keeps |CoR error| <= 0.0000 for every believed stiffness (2 runs; it "
        "should stay within 0.01)",
        "the passivity guard holds CoR <= 0.996 in the guarded run",
        "fixed-k SDMDC with the stiffness believed 50 % low misses the ideal CoR by up to "
        "+0.0515 (at point 1 of the grid)",
    ]
    bad = [_run("sdmdc-online", 1.03, ratio=0.5), _run("SDC", 1.02, guard=True)]
    lines = format_checks(_sweep(bad))
    assert lines[0] == (
        "sdmdc-online misses the ideal CoR by up to 0.0300 at some believed stiffness (1 run), "
        "more than 0.01"
    )
    assert lines[1] == (
        "the passivity guard does not hold CoR <= 1.005 in every guarded run: CoR 1.0200 "
        "(SDC, mismatch scenario, point 1 of the grid)"
    )
    for line in lines:
        assert "PASS" not in line and "FAIL" not in line and "acceptance" not in line


def test_every_compensator_keeps_one_colour():
    from hybridtable.compensators.registry import compensator_names

    names = compensator_names()
    colours = compensator_colours()
    assert list(colours) == list(names)
    assert len(set(colours.values())) == len(names)
    assert (0.5, 0.5, 0.5) not in [tuple(round(x, 1) for x in c[:3]) for c in colours.values()]
    many = compensator_colours([f"c{i}" for i in range(20)])
    assert len(set(many.values())) == 20
