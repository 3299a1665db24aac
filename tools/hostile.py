"""Run the hostile corpus of ``tests/fuzz`` against the command line and count.

Every case of :func:`tests.fuzz.corpus.corpus` (and, with ``--hypothesis N``,
N drawn runs and N drawn flag values) runs in a fork of this process under its
time bound; the table counts the outcomes per command, then lists every case
that is not ``ok`` with its first stderr line or the JSON path of the
offending number, and the most frequent kinds of failure::

    python tools/hostile.py                      # the whole corpus, 2 at a time
    python tools/hostile.py --only compare --klass json --jobs 4
    python tools/hostile.py --hypothesis 200 --json out/hostile.json

Exit code 0 when every case is ``ok``, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.fuzz.corpus import Case, corpus, flag_strategy, runs_strategy  # noqa: E402
from tests.fuzz.runner import OUTCOMES, Result, run_cases  # noqa: E402

__all__ = ["main", "drawn_cases", "summary_table", "failure_kinds"]


def drawn_cases(n: int, seed: int) -> list[Case]:
    """``n`` runs for compare and ``n`` flag values drawn by hypothesis (reproducible by ``seed``)."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import seed as seed_of

    cases: list[Case] = []
    for strategy in (runs_strategy("compare"), flag_strategy(heavy=True)):

        @seed_of(seed)
        @settings(
            max_examples=n,
            deadline=None,
            database=None,
            suppress_health_check=list(HealthCheck),
        )
        @given(case=strategy)
        def draw(case: Case) -> None:
            cases.append(case)

        draw()
    unique: dict[str, Case] = {}
    for case in cases:  # hypothesis may draw a case twice
        unique.setdefault(case.name, case)
    return list(unique.values())


def summary_table(results: list[Result]) -> str:
    """Counts per command (rows) and outcome (columns), with totals."""
    outcomes = [o for o in OUTCOMES if any(r.outcome == o for r in results)] or ["ok"]
    commands = sorted({r.case.command for r in results})
    count = Counter((r.case.command, r.outcome) for r in results)
    widths = [max(len(o) + 2, 7) for o in outcomes]
    head = f"{'command':14s}" + "".join(f"{o:>{w}s}" for o, w in zip(outcomes, widths, strict=True))
    head += f"{'total':>7s}"
    lines = [head, "-" * len(head)]
    for c in [*commands, "all"]:
        row = [
            sum(count[(k, o)] for k in commands) if c == "all" else count[(c, o)] for o in outcomes
        ]
        cells = "".join(f"{n:>{w}d}" for n, w in zip(row, widths, strict=True))
        lines.append(f"{c:14s}{cells}{sum(row):>7d}")
    return "\n".join(lines)


def _kind(detail: str) -> str:
    text = re.sub(r"/tmp/\S+", "PATH", detail)
    text = re.sub(r"line \d+", "line #", text)
    text = re.sub(r"\[\d+\]", "[*]", text)
    text = re.sub(r"-?\d+(\.\d+)?(e[+-]?\d+)?", "#", text)
    text = re.sub(r"\(\+# more\)", "", text)
    return text.strip()[:110]


def failure_kinds(results: list[Result], top: int = 15) -> list[tuple[int, str]]:
    """The most frequent (outcome, command, detail with numbers masked) of the failures."""
    kinds = Counter(
        f"{r.outcome:16s} {r.case.command:12s} {_kind(r.detail)}"
        for r in results
        if r.outcome != "ok"
    )
    return [(n, k) for k, n in kinds.most_common(top)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="CMD",
        help="only these commands (repeatable, or comma separated)",
    )
    parser.add_argument(
        "--klass",
        action="append",
        default=[],
        metavar="K",
        help="only these classes of defect (repeatable, or comma separated)",
    )
    parser.add_argument("--name", metavar="TEXT", help="only cases whose name holds TEXT")
    parser.add_argument(
        "--jobs", type=int, default=os.cpu_count() or 1, help="cases at a time (default: the CPUs)"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="time bound of every case [s] (default 60, diagnose 120)",
    )
    parser.add_argument(
        "--hypothesis",
        type=int,
        default=0,
        metavar="N",
        help="also N drawn runs and N drawn flag values",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the draws (default 0)")
    parser.add_argument(
        "--strict",
        action="store_true",
        help="count every null and infinity of the JSON, also those the valid "
        "reference of a case has (the command's design)",
    )
    parser.add_argument("--list", action="store_true", help="list the cases, run nothing")
    parser.add_argument("--json", metavar="FILE", help="write every result as JSON")
    parser.add_argument("--keep", metavar="DIR", help="leave the cases' folders in DIR")
    args = parser.parse_args(argv)

    only = {x for a in args.only for x in a.split(",") if x}
    klass = {x for a in args.klass for x in a.split(",") if x}
    cases = corpus() + (drawn_cases(args.hypothesis, args.seed) if args.hypothesis else [])
    cases = [
        c
        for c in cases
        if (not only or c.command in only)
        and (not klass or c.klass in klass)
        and (not args.name or args.name in c.name)
    ]
    if args.list:
        for c in cases:
            print(f"{c.expect:7s} {c.name}")
        print(f"{len(cases)} cases")
        return 0
    if not cases:
        print("no case matches", file=sys.stderr)
        return 2

    start = time.monotonic()
    done = 0

    def progress(result: Result) -> None:
        nonlocal done
        done += 1
        if sys.stderr.isatty():
            print(f"\r{done}/{len(cases)} {result.case.name[:60]:60s}", end="", file=sys.stderr)

    keep = Path(args.keep) if args.keep else None
    if keep:
        keep.mkdir(parents=True, exist_ok=True)
    results = run_cases(cases, args.jobs, args.timeout, progress, keep, args.strict)
    if sys.stderr.isatty():
        print("\r" + " " * 80 + "\r", end="", file=sys.stderr)
    bad = [r for r in results if r.outcome != "ok"]
    print(
        f"{len(results) - len(bad)} of {len(results)} hostile cases handled cleanly; "
        f"{len(bad)} not ({time.monotonic() - start:.0f} s, {args.jobs} at a time)\n"
    )
    print(summary_table(results))
    if bad:
        print("\nmost frequent failures:")
        for n, kind in failure_kinds(results):
            print(f"{n:5d}  {kind}")
        print("\ncases that failed (outcome, expected, seconds, first stderr line or JSON path):")
        for r in sorted(bad, key=lambda r: (OUTCOMES.index(r.outcome), r.case.name)):
            print(f"  {r.outcome:16s} {r.case.expect:6s} {r.seconds:5.1f}s  {r.case.name}")
            print(f"      {r.detail[:200]}")
    if args.json:
        rows = [
            {
                "name": r.case.name,
                "command": r.case.command,
                "klass": r.case.klass,
                "expect": r.case.expect,
                "outcome": r.outcome,
                "detail": r.detail,
                "exit_code": r.exit_code,
                "signal": r.signal,
                "seconds": round(r.seconds, 3),
                "argv": r.argv,
            }
            for r in results
        ]
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    return 0 if not bad else 1


if __name__ == "__main__":
    sys.exit(main())
