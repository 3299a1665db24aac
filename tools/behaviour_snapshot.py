"""Save the JSON and Markdown outputs of every command, and diff two saved sets.

A restructuring must not change a single number. Save a snapshot before it,
another after, and diff them::

    python tools/behaviour_snapshot.py save out/before --runs examples/nominal
    ...  # move code
    python tools/behaviour_snapshot.py save out/after --runs examples/nominal
    python tools/behaviour_snapshot.py diff out/before out/after

The commands run as a user runs them (``python -m hybridtable.cli``):
``reproduce``, ``simulate`` with every registered compensator (continuous, a
1 kHz rig computer, the passivity guard, the Stewart back-end), ``margins``
(continuous and sampled, with validation runs), ``compensators --quick``, and
``compare`` / ``diagnose`` on the recorded runs. Clock readings are the only fields
left out of the diff (keys containing ``wall`` or ``real_time``; in text, only the
reading itself is masked); every other number must be
equal to the last bit (``diff --rtol 1e-9`` allows JSON numbers that moved by
re-ordered floating operations). ``diff`` exits 1 on any difference.
``simulate6`` on the three 6-DoF examples, ``sweep`` of the Table 2 spec,
``explain`` on Tables 3 and 4 and ``effects`` are covered too.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

COMPENSATORS = (
    "none",
    "SDC",
    "MDC",
    "SDMDC",
    "sdmdc-online",
    "polynomial",
    "smith",
    "smith-online",
)


def _cases(runs: str | None) -> list[tuple[str, list[str]]]:
    cases: list[tuple[str, list[str]]] = [("reproduce", ["reproduce", "--no-progress"])]
    for c in COMPENSATORS:
        cases.append((f"simulate-{c}", ["simulate", "--compensator", c]))
        cases.append(
            (f"simulate-{c}-1khz", ["simulate", "--compensator", c, "--sample-rate-hz", "1000"])
        )
    cases += [
        ("simulate-SDMDC-passivity", ["simulate", "--compensator", "SDMDC", "--passivity"]),
        ("simulate-MDC-damped-clamped", ["simulate", "--compensator", "MDC",
                                         "--contact-damping-n-s-per-m", "500",
                                         "--clamp-nonnegative"]),
        ("simulate-SDMDC-stewart", ["simulate", "--compensator", "SDMDC", "--table", "stewart"]),
        ("margins", ["margins", "--sensor-delay-s", "0:0.02:6", "--table-response-hz", "5:100:5",
                     "--validate", "2", "--no-progress"]),
        ("margins-1khz", ["margins", "--sample-rate-hz", "1000", "--sensor-delay-s", "0.005,0.01",
                          "--table-response-hz", "10,25", "--no-progress"]),
        ("compensators-quick", ["compensators", "--quick", "--jobs", "1", "--no-progress",
                                "--prior-ratios", "0.5,1"]),
    ]  # fmt: skip
    for name in ("on_axis", "offset", "stewart"):
        for c in ("none", "SDMDC"):
            cases.append(
                (
                    f"simulate6-{name}-{c}",
                    [
                        "simulate6",
                        f"examples/six_dof/{name}.toml",
                        "--compensator",
                        c,
                        "--no-progress",
                    ],
                )
            )
    cases += [
        ("sweep-table2", ["sweep", "examples/sweeps/table2.toml", "--no-progress",
                          "--workers", "1",
                          "--out", "{out}/sweep-table2.parquet"]),
        ("explain-table3", ["explain", "examples/explain/table3_experiment.csv",
                            "--no-progress"]),
        ("explain-table4-one", ["explain", "examples/explain/table4_experiment_sdmdc.csv",
                                "--max-effects", "1", "--no-progress"]),
        ("effects", ["effects"]),
    ]  # fmt: skip
    if runs:
        cases += [
            ("compare", ["compare", runs, "--no-progress", "--report", "{out}/compare-report"]),
            ("compare-add", ["compare", runs, "--no-progress", "--add", "contact_damping"]),
            ("diagnose", ["diagnose", runs, "--no-progress", "--report", "{out}/diagnose-report"]),
        ]
    return cases


#: The cases ``save --quick`` leaves out (the slowest: minutes on two cores).
SLOW = ("compensators-quick", "explain-", "simulate6-", "sweep-")


def save(out: Path, runs: str | None, quick: bool = False) -> int:
    out.mkdir(parents=True, exist_ok=True)
    failed = 0
    for name, argv in _cases(runs):
        if quick and name.startswith(SLOW):
            continue
        argv = [a.replace("{out}", str(out)) for a in argv]
        cmd = [
            sys.executable,
            "-m",
            "hybridtable.cli",
            *argv,
            "--json",
            str(out / f"{name}.json"),
            "--force",
        ]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        (out / f"{name}.stdout").write_text(proc.stdout)
        status = "ok" if proc.returncode == 0 else f"exit {proc.returncode}"
        failed += proc.returncode != 0
        print(f"{name:32s} {status}", flush=True)
        if proc.returncode:
            print(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "", flush=True)
    return 1 if failed else 0


#: Keys whose values are clock readings (run times, creation stamps) or the
#: machine's (a scheduler's address), not behaviour: left out of the diff.
_CLOCKS = ("wall", "real_time", "created", "compute_time", "scheduler", "seconds")


def _strip(obj, root: str = ""):
    if isinstance(obj, str) and root:
        return obj.replace(root, "<out>")
    if isinstance(obj, dict):
        return {k: _strip(v, root) for k, v in obj.items() if not any(w in k for w in _CLOCKS)}
    if isinstance(obj, list):
        return [_strip(v, root) for v in obj]
    return obj


def _close(a, b, rtol: float) -> bool:
    """Equal, or two numbers within ``rtol`` of each other (relative to the larger, or
    absolute below 1)."""
    if a == b:
        return True
    if rtol <= 0.0 or isinstance(a, bool) or isinstance(b, bool):
        return False
    if not (isinstance(a, int | float) and isinstance(b, int | float)):
        return False
    return abs(a - b) <= rtol * max(1.0, abs(a), abs(b))


def _differences(a, b, path: str = "", rtol: float = 0.0) -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}.{k}: only in one" for k in sorted(set(a) ^ set(b))]
        for k in sorted(set(a) & set(b)):
            out += _differences(a[k], b[k], f"{path}.{k}", rtol)
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} != {len(b)}"]
        out = []
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            out += _differences(x, y, f"{path}[{i}]", rtol)
        return out
    return [] if _close(a, b, rtol) else [f"{path}: {a!r} != {b!r}"]


#: Clock readings in console and Markdown text: ``(0.12 s)``, ``(26 s)``,
#: ``wall time 5.8 s``, ``...: 0.1 s`` at a line's end, ``(657 model runs, 16.1 s)``.
#: Only the reading is masked; the rest of the line is compared.
_TIMING = re.compile(
    r"\(\d+(\.\d+)? s\)|wall time \d+(\.\d+)? s|: \d+(\.\d+)? s$|, \d+(\.\d+)? s\)"
    r"|simulated in \d+(\.\d+)? s \(\d+(\.\d+)? x real time\)"
    r"|runs in \d+(\.\d+)? s \(\d+(\.\d+)? runs/s"
)


def _text_lines(path: Path, root: Path) -> list[str]:
    text = path.read_text().replace(str(root), "<out>")
    return [_TIMING.sub("<clock>", ln) for ln in text.splitlines()]


def diff(a: Path, b: Path, rtol: float = 0.0) -> int:
    names = sorted(
        str(p.relative_to(a)) for p in a.rglob("*") if p.suffix in (".json", ".md", ".stdout")
    )
    bad = 0
    for name in names:
        pa, pb = a / name, b / name
        if not pb.exists():
            print(f"{name}: missing in {b}")
            bad += 1
            continue
        if pa.suffix == ".json":
            found = _differences(
                _strip(json.loads(pa.read_text()), str(a)),
                _strip(json.loads(pb.read_text()), str(b)),
                "",
                rtol,
            )
        else:
            la, lb = _text_lines(pa, a), _text_lines(pb, b)
            found = [f"line: {x!r} != {y!r}" for x, y in zip(la, lb, strict=False) if x != y]
            if len(la) != len(lb):
                found.append(f"{len(la)} lines != {len(lb)} lines")
        if found:
            bad += 1
            print(f"{name}: {len(found)} differences, e.g. " + "; ".join(found[:3]))
    print(f"{len(names)} outputs compared, {bad} differ")
    return 1 if bad else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="verb", required=True)
    p = sub.add_parser("save", help="run every command and save its outputs in DIR")
    p.add_argument("dir", type=Path)
    p.add_argument("--runs", help="folder of recorded runs for compare and diagnose")
    p.add_argument(
        "--quick",
        action="store_true",
        help="leave out the slowest cases (compensators, explain, simulate6, sweep)",
    )
    d = sub.add_parser("diff", help="compare two saved sets; exit 1 on any difference")
    d.add_argument("a", type=Path)
    d.add_argument("b", type=Path)
    d.add_argument(
        "--rtol",
        type=float,
        default=0.0,
        help="JSON numbers within this relative tolerance count as equal (default 0: bit for bit)",
    )
    args = parser.parse_args()
    if args.verb == "save":
        return save(args.dir, args.runs, args.quick)
    return diff(args.a, args.b, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
