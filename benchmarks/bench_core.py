"""Benchmark: the physics core, old commit against this checkout, as ratios in one run.

Times, in alternating child processes of the same machine (one checkout's
package on ``PYTHONPATH`` each), what the physics core decides:

- one Table 1 run through the Drake diagram (continuous loop, RK3), for
  ``none`` and ``SDMDC``, and a 1 kHz sampled rig computer with SDMDC: wall
  time per run (median of the repetitions, each the best of ``--runs`` runs
  after a warm-up), integrator steps, and the time per step;
- the floor of that diagram: SDMDC with a bilateral (linear) contact and the
  ungated (linear) compensator, advanced over the SDMDC run's simulated time
  (no Python callback on the new side: what the simulator itself costs);
- optionally ``diagnose`` (one process, ``workers=1``) on the shipped runs
  (``--diagnose DIR``) and on three sets of three runs from the independent rig
  generator ``tests/generators/effectsim.py`` (nothing hidden, contact
  damping, an extra sensor delay): wall time, model runs (in the ``steps``
  column) and the verdict, which must not change.

The old checkout is a folder (``git worktree add ../old eae8025``) or a
commit, checked out into a temporary worktree. Ratios old/new > 1 mean the
new code is faster. The machine is shared: read the ratios, not the times.

Usage: python benchmarks/bench_core.py [--old COMMIT_OR_DIR] [--reps 5] [--runs 3]
       [--diagnose examples/nominal] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: One child: the best time of ``runs`` runs of each case, after a warm-up.
CHILD = r"""
import json, sys, time
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import table1_params
runs = int(sys.argv[1])
cases = {
    "table1_none_diagram": table1_params("none"),
    "table1_SDMDC_diagram": table1_params("SDMDC"),
    "table1_SDMDC_1khz_diagram": table1_params("SDMDC").with_(sample_rate_hz=1000.0),
}
out = {}
for name, p in cases.items():
    simulate(p)
    best = None
    for _ in range(runs):
        t = time.perf_counter()
        r = simulate(p)
        dt = time.perf_counter() - t
        best = dt if best is None else min(best, dt)
    out[name] = {"wall_s": best, "steps": r.steps, "cor": r.metrics.cor}
# The floor: the same SDMDC diagram with a bilateral (linear) contact and the
# ungated (linear) compensator, no Python callback at all where the checkout
# can build them so, advanced over the SDMDC run's simulated time.
try:
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
    import hybridtable.loop.builder as B
    from hybridtable.compensators.paper import Compensator
    from hybridtable.systems.contact import UnilateralSpringContact
    p = cases["table1_SDMDC_diagram"]
    t_end = float(simulate(p).time_s[-1])
    B.make_compensator = lambda params, h, comp: Compensator(
        params.compensator_params(), h, gated=False)
    best = None
    for _ in range(runs + 1):
        loop = B.build_hybrid_loop(p, contact=UnilateralSpringContact(p.plant.contact, bilateral=True))
        sim = Simulator(loop.diagram)
        loop.set_initial_conditions(sim.get_mutable_context())
        ResetIntegratorFromFlags(sim, "runge_kutta3", loop.computer_period_s)
        integ = sim.get_mutable_integrator()
        integ.set_maximum_step_size(loop.computer_period_s)
        integ.set_target_accuracy(1e-8)
        sim.Initialize()
        t = time.perf_counter()
        sim.AdvanceTo(t_end)
        dt = time.perf_counter() - t
        best = dt if best is None else min(best, dt)
    out["table1_linear_floor"] = {"wall_s": best, "steps": sim.get_num_steps_taken(), "cor": 0.0}
except Exception as err:  # an old checkout without these systems
    print(f"floor not measured: {err}", file=sys.stderr)
print(json.dumps(out))
"""

DIAGNOSE = r"""
import json, sys, tempfile, time
from pathlib import Path
from hybridtable.diagnosis.diagnose import diagnose
from hybridtable.measurement.run_reader import read_runs
from tests.generators.effectsim import make_runs
sets = {"diagnose_examples": read_runs([sys.argv[1]])}
tmp = Path(tempfile.mkdtemp())
for effect in ("none", "contact_damping", "extra_delay"):
    sets[f"diagnose_rigsim_{effect}"] = make_runs(
        tmp / effect, effect, velocities=(0.05, 0.08, 0.12), seed=1, duration_s=0.965
    )
out = {}
for name, runs in sets.items():
    t = time.perf_counter()
    d = diagnose(runs, workers=1)
    out[name] = {"wall_s": time.perf_counter() - t, "steps": d.simulations,
                 "cor": d.staircase[-1]["error"], "verdict": d.verdict}
print(json.dumps(out))
"""


def _child(checkout: Path, code: str, *args: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(checkout), OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=str(checkout),
        check=False,
    )
    if proc.returncode:
        raise SystemExit(f"{checkout}: {proc.stderr.strip().splitlines()[-1]}")
    for line in proc.stderr.splitlines():
        if line.startswith("floor not measured"):
            print(f"{checkout}: {line}", file=sys.stderr)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _checkout(old: str, tmp: Path) -> Path:
    if Path(old).is_dir():
        return Path(old).resolve()
    path = tmp / "old"
    subprocess.run(
        ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(path), old],
        check=True,
        capture_output=True,
    )
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="eae8025", help="commit or folder (default: eae8025)")
    ap.add_argument("--reps", type=int, default=5, help="alternating child pairs (default: 5)")
    ap.add_argument("--runs", type=int, default=3, help="runs per case per child (default: 3)")
    ap.add_argument("--diagnose", metavar="DIR", help="also time diagnose on these runs")
    ap.add_argument("--json", metavar="FILE", help="write the figures as JSON")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        old = _checkout(args.old, Path(tmp))
        try:
            sides: dict[str, list[dict]] = {"old": [], "new": []}
            for _ in range(args.reps):
                sides["old"].append(_child(old, CHILD, str(args.runs)))
                sides["new"].append(_child(ROOT, CHILD, str(args.runs)))
                if args.diagnose:
                    d = str(Path(args.diagnose).resolve())
                    sides["old"][-1].update(_child(old, DIAGNOSE, d))
                    sides["new"][-1].update(_child(ROOT, DIAGNOSE, d))
        finally:
            if not Path(args.old).is_dir():
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old)],
                    check=False,
                    capture_output=True,
                )
    rows = []
    names = [k for k in sides["new"][0] if isinstance(sides["new"][0][k], dict)]
    missing = [k for k in names if any(k not in s for s in sides["old"])]
    for k in missing:  # a case the old checkout cannot build: said, not timed
        print(f"{k}: not measured on {args.old} (the child said why on its stderr)")
    names = [k for k in names if k not in missing]
    print(f"old: {args.old}   new: {ROOT}   ({args.reps} alternating pairs)")
    print(
        f"{'case':<28} {'old ms':>8} {'new ms':>8} {'old/new':>8} {'steps':>12} {'us/step new':>12}"
    )
    for name in names:
        o = statistics.median(s[name]["wall_s"] for s in sides["old"])
        n = statistics.median(s[name]["wall_s"] for s in sides["new"])
        so, sn = sides["old"][0][name]["steps"], sides["new"][0][name]["steps"]
        rows.append(
            {
                "case": name,
                "old_s": o,
                "new_s": n,
                "ratio": o / n,
                "steps_old": so,
                "steps_new": sn,
                "cor_old": sides["old"][0][name]["cor"],
                "cor_new": sides["new"][0][name]["cor"],
            }
        )
        print(
            f"{name:<28} {1e3 * o:8.1f} {1e3 * n:8.1f} {o / n:8.2f} {f'{so}/{sn}':>12} "
            f"{1e6 * n / sn:12.1f}"
        )
    for name in names:
        if name.startswith("diagnose"):
            verdicts = {sides[k][0][name]["verdict"] for k in sides}
            print(f"  {name}: verdict {' / '.join(sorted(verdicts))}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
