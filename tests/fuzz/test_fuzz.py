"""Never hang, never a traceback, never a silent NaN: every command on hostile inputs.

The fixed corpus (:func:`tests.fuzz.corpus.corpus`) runs in one test per
command and class of defect; each test runs all its cases (one per core, each
in a fork under its time bound) and fails with the list of the cases that
hung, crashed, refused unclearly, accepted what is certainly invalid or wrote
an unexplained non-finite or absurd number. Hypothesis draws more runs and
flag values on top (derandomized: the same draws on every machine).
"""

from __future__ import annotations

import json
import os
from collections import defaultdict

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings

from tests.fuzz.corpus import Case, corpus, flag_strategy, runs_strategy
from tests.fuzz.runner import Result, json_findings, refusal_lines, run_cases

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

__all__: list[str] = []

#: Children at a time: the cores, at most 4.
JOBS = max(1, min(4, os.cpu_count() or 1))

#: Classes of defects tested together (one test each per command).
GROUPS = {
    "cells": ("cells",),
    "time": ("time", "long"),
    "encoding-structure": ("encoding", "structure"),
    "json": ("json",),
    "extreme": ("extreme",),
    "contradictory": ("contradictory",),
    "files-outputs": ("files", "outputs"),
    "flags": ("flags",),
    "lists": ("lists",),
    "nominal-stdout": ("nominal", "stdout"),
}
_GROUP_OF = {klass: group for group, classes in GROUPS.items() for klass in classes}


def _grouped() -> dict[tuple[str, str], list[Case]]:
    groups: dict[tuple[str, str], list[Case]] = defaultdict(list)
    for case in corpus():
        groups[(case.command, _GROUP_OF[case.klass])].append(case)
    return dict(sorted(groups.items()))


_GROUPS = _grouped()


def _report(results: list[Result]) -> str:
    bad = [r for r in results if r.outcome != "ok"]
    lines = [f"{len(bad)} of {len(results)} cases failed:"]
    for r in bad:
        lines.append(f"  {r.case.name}: {r.outcome}: {r.detail} (expect {r.case.expect})")
    return "\n".join(lines)


def test_the_corpus_covers_every_class_and_the_issues_counts():
    cases = corpus()
    count = defaultdict(int)
    for c in cases:
        count[c.command] += 1
    flags = sum(1 for c in cases if c.klass in ("flags", "lists"))
    assert count["compare"] >= 300 and count["diagnose"] >= 30 and flags >= 300
    klasses = {c.klass for c in cases if c.command == "compare"}
    assert {"cells", "time", "encoding", "structure", "json", "extreme"} <= klasses
    assert {"contradictory", "files", "outputs", "long"} <= klasses
    commands = {c.command for c in cases if c.klass == "flags"}
    assert commands == {
        "simulate",
        "reproduce",
        "margins",
        "compare",
        "diagnose",
        "compensators",
        "diagram",
    }
    # a certainly invalid input expects a refusal, a valid one a clean result
    by_name = {c.name: c for c in cases}
    assert by_name["compare/cells/f_mea_n-peak-nan"].expect == "refuse"
    assert by_name["compare/contradictory/dead-sensor-zeros"].expect == "refuse"
    assert by_name["compare/files/base-run"].expect == "ok"
    assert by_name["compare/extreme/table_damping_ratio=1e-300"].expect == "either"


def test_the_judge_ignores_progress_bars_and_counts_lines():
    bar = "\r  0%|          | 0/3 [00:00<?, ?it/s]\r 67%|######6   | 2/3 [00:01<00:00, 1.9it/s]"
    stderr = bar + "\r" + " " * 60 + "\rhybridtable compare: error: run.csv: no such file\n"
    assert refusal_lines(stderr) == ["hybridtable compare: error: run.csv: no such file"]
    assert len(refusal_lines("a\nb\n")) == 2


def test_the_judge_counts_unexplained_nonfinite_absurd_and_impossible_numbers():
    data = json.loads(
        '{"runs": [{"cor": 150.0, "rms": NaN}], "margin": Infinity, "k": 1e300,'
        ' "fit": {"z": null, "note": "no held-out run"}, "echo": 2e15, "cor_error": -3.0}',
        parse_constant=lambda text: text,  # the runner's own parse marks these as literals
    )
    findings = json_findings(data, inputs=[2e15])
    joined = "\n".join(findings)
    assert ".runs[0].cor = 150" in joined  # a CoR of 150 is no contact's
    assert ".k = 1e+300" in joined  # beyond 1e12
    assert ".fit.z" not in joined  # explained by the note beside it
    assert ".echo" not in joined  # the case's own input, repeated
    assert ".cor_error" not in joined  # an error of a CoR may be negative
    assert ".margin" in joined or any("margin" in f for f in findings)
    assert json_findings({"a": [None, 1.0]}, allowed={".a[*]"}) == []


def _table(case, name="run.csv"):
    lines = case.files[name].decode().splitlines()
    head = lines[0].split(",")
    rows = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    return {h: rows[:, i] for i, h in enumerate(head)}


def test_the_contradictory_runs_contradict_themselves():
    cases = {c.name: c for c in corpus() if c.klass == "contradictory"}
    dead = _table(cases["compare/contradictory/dead-sensor-zeros"])
    assert dead["p_act_m"].max() > 1e-3 and np.abs(dead["f_mea_n"]).max() == 0.0
    flipped = _table(cases["compare/contradictory/position-sign-flipped"])
    pressed = flipped["f_mea_n"] > 100.0  # a force of contact while the devices are apart
    assert pressed.sum() > 100 and flipped["p_act_m"][pressed].max() < 0.0
    pulling = _table(cases["compare/contradictory/force-sign-flipped"])
    assert pulling["p_act_m"].max() > 1e-3 and pulling["f_mea_n"].min() < -100.0
    starts = _table(cases["compare/contradictory/starts-in-contact"])
    assert starts["p_act_m"][0] > 0.0 and starts["f_mea_n"][0] > 100.0
    ends = _table(cases["compare/contradictory/ends-at-the-force-peak"])
    assert ends["f_mea_n"][-1] > 100.0
    apart = _table(cases["compare/contradictory/no-contact"])
    assert apart["p_act_m"].max() < 0.0 and np.abs(apart["f_mea_n"]).max() < 10.0
    base = _table(next(c for c in corpus() if c.name == "compare/files/base-run"))
    assert base["p_act_m"][0] < 0.0 < base["p_act_m"].max()  # approach, contact, separation
    assert base["f_mea_n"][-1] < 10.0


@pytest.mark.parametrize("command, group", list(_GROUPS), ids=[f"{c}-{g}" for c, g in _GROUPS])
def test_hostile_corpus(command, group):
    results = run_cases(_GROUPS[(command, group)], jobs=JOBS)
    assert all(r.outcome == "ok" for r in results), _report(results)


_HYPOTHESIS = settings(
    max_examples=40,
    deadline=None,
    database=None,
    derandomize=True,
    phases=(Phase.explicit, Phase.generate),  # no shrinking: a failing case is shown as drawn
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@_HYPOTHESIS
@given(case=runs_strategy("compare"))
def test_compare_on_drawn_runs(case):
    result = run_cases([case], jobs=1)[0]
    assert result.outcome == "ok", _report([result])


@settings(_HYPOTHESIS, max_examples=60)
@given(case=flag_strategy())
def test_drawn_flag_values(case):
    result = run_cases([case], jobs=1)[0]
    assert result.outcome == "ok", _report([result])
