"""Never hang, never a traceback, never a silent NaN: the newer surfaces on hostile inputs.

Plug-ins, sweep specs and ``--resume``, model files, 6-DoF scenarios, CoR
tables and outputs on a full disk (:mod:`tests.fuzz.surfaces`). One test per
command and surface; the cases of every selected test run together (one per
core, each in a fork under its time bound, the longest first) the first time a
test asks, and each test then fails with the list of its cases that hung,
crashed, refused unclearly, accepted what is certainly invalid, wrote an
unexplained non-finite number or left a bad output. Two campaigns writing one
``--out`` at once are a plain test of their own.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest

from tests.fuzz.runner import Result, _judge, _Raw, refusal_lines, run_cases
from tests.fuzz.surfaces import (
    GROUPS,
    REPO,
    SURFACES,
    SurfaceCase,
    cases_of,
    surface_cases,
    sweep_spec,
)

__all__: list[str] = []

pytestmark = pytest.mark.fuzz

#: Children at a time: the cores, at most 4.
JOBS = max(1, min(4, os.cpu_count() or 1))

_IDS = [f"{command}-{surface}" for command, surface in GROUPS]


def _report(results: list[Result]) -> str:
    bad = [r for r in results if r.outcome != "ok"]
    lines = [f"{len(bad)} of {len(results)} cases failed:"]
    for r in bad:
        lines.append(
            f"  {r.case.name}: {r.outcome}: {r.detail} (expect {r.case.expect}, {r.seconds:.1f} s)"
        )
    return "\n".join(lines)


@pytest.fixture(scope="session")
def surface_results(request) -> dict[tuple[str, str], list[Result]]:
    """The results of every selected group, run in one pool (longest bound first)."""
    selected = []
    for item in request.session.items:
        spec = getattr(item, "callspec", None)
        if item.originalname == "test_surface" and spec is not None:
            selected.append((spec.params["command"], spec.params["surface"]))
    cases = [c for group in dict.fromkeys(selected) for c in cases_of(*group)]
    order = sorted(range(len(cases)), key=lambda i: -(cases[i].timeout_s or 60.0))
    results = run_cases([cases[i] for i in order], jobs=JOBS)
    grouped: dict[tuple[str, str], list[Result]] = defaultdict(list)
    for r in results:
        grouped[(r.case.command, r.case.surface)].append(r)
    return grouped


@pytest.mark.parametrize("command, surface", list(GROUPS), ids=_IDS)
def test_surface(command, surface, surface_results):
    results = surface_results[(command, surface)]
    assert len(results) == len(cases_of(command, surface))
    assert all(r.outcome == "ok" for r in results), _report(results)


def test_the_corpus_covers_every_surface_with_300_cases():
    cases = surface_cases()
    assert len(cases) >= 300
    assert len({c.name for c in cases}) == len(cases)
    count = defaultdict(int)
    for c in cases:
        count[c.surface] += 1
        assert c.expect in ("ok", "refuse", "either", "fail"), c.name
        assert c.baseline is not None, c.name
        assert (c.command, c.surface) in GROUPS, c.name
    assert set(count) == set(SURFACES)
    assert all(n >= 20 for n in count.values()), dict(count)
    by_name = {c.name: c for c in cases}
    # what the docs promise, spelled out
    assert by_name["simulate/plugins/import-sys-exit-0"].expect == "refuse"
    assert by_name["simulate/plugins/sensor-nan"].expect == "fail"
    assert by_name["sweep/sweeps/resume-ok-row-cor-nan"].post_check is not None
    assert by_name["sweep/sweeps/resume-spec-of-other-metrics"].expect == "refuse"
    assert by_name["simulate6/six_dof/approach.misalignment_deg=[nan, 0.0]"].must_mention == (
        "misalignment_deg",
        "s.toml",
    )
    assert by_name["explain/explain/10000-rows"].timeout_s == 120.0
    assert by_name["simulate/outputs/full-disk-plot"].file_size_limit_bytes == 20_000


def _raw(case: SurfaceCase, code: int, stderr: str, post: str | None = None) -> _Raw:
    return _Raw(case, list(case.argv), code, None, 0.1, "", stderr, None, False, post)


def test_the_judge_of_fail_mention_ignored_lines_and_post_checks():
    case = SurfaceCase("x/outputs/a", "outputs", {}, ["simulate6", "s.toml"], "fail")
    failed = "hybridtable simulate6: error: s.toml: the simulation diverged"
    assert _judge(_raw(case, 1, failed + "\n"), set())[0] == "ok"
    assert _judge(_raw(case, 2, failed + "\n"), set())[0] == "ok"
    assert _judge(_raw(case, 0, ""), set())[0] == "wrong_accept"
    assert _judge(_raw(case, 1, failed + "\n", "left behind: p.png"), set())[0] == "bad_output"
    named = SurfaceCase(
        "x/six_dof/b",
        "six_dof",
        {},
        ["simulate6", "s.toml"],
        "refuse",
        must_mention=("misalignment_deg",),
    )
    assert _judge(_raw(named, 2, "error: s.toml: a value is NaN\n"), set())[0] == "unclear_refusal"
    assert _judge(_raw(named, 2, "error: s.toml: misalignment_deg is NaN\n"), set())[0] == "ok"
    info = SurfaceCase(
        "x/sweeps/c",
        "sweeps",
        {},
        ["sweep", "spec.toml"],
        "refuse",
        ignore_lines=(r"dashboard http",),
    )
    two = "sweep x: 8 runs; dashboard http://127.0.0.1:8787/status\nerror: not this spec's\n"
    assert _judge(_raw(info, 2, two), set())[0] == "ok"


def _sweep_env() -> dict[str, str]:
    path = os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])
    return dict(os.environ, PYTHONPATH=path, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")


def test_two_campaigns_on_one_out_at_once(tmp_path: Path):
    """Two ``sweep`` campaigns started together on one ``--out``, without ``--force``:
    at most one may write it; the other refuses in one line (README: an existing
    output is replaced only with --force), and the file is a whole campaign's."""
    import pyarrow.parquet as pq

    (tmp_path / "spec.toml").write_bytes(sweep_spec())
    argv = [
        sys.executable,
        "-m",
        "hybridtable.cli",
        "sweep",
        "spec.toml",
        "--out",
        "same.parquet",
        "--workers",
        "1",
        "--no-progress",
    ]
    procs = [
        subprocess.Popen(
            argv,
            cwd=tmp_path,
            env=_sweep_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        for _ in range(2)
    ]
    start = time.monotonic()
    outputs = []
    try:
        for p in procs:
            out, err = p.communicate(timeout=max(1.0, 180.0 - (time.monotonic() - start)))
            outputs.append((p.returncode, out, err))
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, 9)
                p.wait()
    codes = [code for code, _, _ in outputs]
    info = re.compile(r"Dask worker|dashboard http|^wrote ")
    detail = "\n".join(f"exit {c}: {e.strip()[-400:]}" for c, _, e in outputs)
    assert codes.count(0) <= 1, f"both campaigns wrote same.parquet:\n{detail}"
    for code, _, err in outputs:
        if code != 0:
            lines = [x for x in refusal_lines(err) if not info.search(x)]
            assert code == 2 and len(lines) == 1, f"not a one-line refusal:\n{detail}"
    if 0 in codes:
        rows = pq.read_table(tmp_path / "same.parquet").to_pylist()
        assert [r["run"] for r in rows] == list(range(8))
        assert all(r["status"] == "ok" for r in rows)
