"""Benchmark: wall time of ``hybridtable explain`` on the shipped CoR tables, as a user runs it.

Each table is explained by a fresh ``python -m hybridtable.cli explain TABLE``
process with the default workers (the fast engine compiles its held ticks in
each process, so a warm process would flatter it). With ``--old DIR`` (a
checkout of an older commit, e.g. ``git worktree add /tmp/old eae8025``) the
same commands run on that code too, alternately, in the same run, and the
ratio old / new is printed. Target (issue 34): each shipped table at most
30 s on the 2-core machine.

Usage: python benchmarks/bench_explain.py [--old DIR] [--repeat N] [--tables NAME ...]
       [--workers N] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLES = ROOT / "examples" / "explain"
TARGET_S = 30.0


def _time(code: Path, table: Path, workers: int | None) -> float:
    argv = [sys.executable, "-m", "hybridtable.cli", "explain", str(table), "--no-progress"]
    if workers is not None:
        argv += ["--workers", str(workers)]
    env = {**os.environ, "PYTHONPATH": str(code), "MPLBACKEND": "Agg"}
    start = time.perf_counter()
    subprocess.run(argv, env=env, cwd=code, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", type=Path, help="a checkout of the commit to compare with")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each command (median)")
    ap.add_argument("--workers", type=int, help="explain's --workers (default: its own)")
    ap.add_argument("--tables", nargs="*", default=sorted(p.stem for p in TABLES.glob("*.csv")))
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args()
    out = {}
    for name in args.tables:
        table = TABLES / f"{name}.csv"
        new, old = [], []
        for _ in range(args.repeat):
            new.append(_time(ROOT, table, args.workers))
            if args.old is not None:
                old.append(_time(args.old, table, args.workers))
        row = {"new_s": statistics.median(new), "within_target": max(new) <= TARGET_S}
        line = f"{name}: {row['new_s']:.1f} s"
        if old:
            row["old_s"] = statistics.median(old)
            row["old_over_new"] = row["old_s"] / row["new_s"]
            line += f", old {row['old_s']:.1f} s, {row['old_over_new']:.1f}x faster"
        line += f" (target {TARGET_S:g} s: {'met' if row['within_target'] else 'NOT met'})"
        print(line, flush=True)
        out[name] = row
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
