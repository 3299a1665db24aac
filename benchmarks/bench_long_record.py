"""Benchmark: ``compare`` and ``diagnose`` on one long log of many contacts.

Writes one ``hybridtable-run/1`` log (default 1e5 rows at 1 kHz holding 20
contacts 5 s apart, the rig of ``tests/generators/rigsim.NOMINAL`` with SDMDC,
2 N and 2 um of reading noise; gaps 2-5 mm and approach velocities
0.05-0.12 m/s, the operator resetting the spacecraft model before each
contact) with the independent generator ``tests/generators/longlog.py``, then
times ``hybridtable compare LOG`` and ``hybridtable diagnose LOG`` in fresh
processes (``--no-progress --json FILE --force``), each at most ``--timeout``
seconds. Targets: compare a 1e5-row record in at most 10 s, diagnose a 1e5-row
log of 20 contacts in at most 60 s.

A command that fails or runs out of time is reported (exit code, its first
stderr line, the time it took), never a crash of the benchmark. The time is
the median of ``--repeat`` processes (default 1: diagnose takes long), the
memory the largest peak resident set of the command's process or of a worker
it waited for (``wait4``; MB = 2**20 bytes); the times grow on a busy
machine. Where the command's JSON names the contact events it split the log
into, their count and whether their resets are the generator's are shown.

With 5 s between resets the spacecraft model flies 0.2-0.6 m away after each
contact, so the reset's command jump is that large and the table, overshooting
it, strikes the contact before the model reaches it (the first line after the
verdict says in how many contacts); ``--rows 10000`` keeps the 20 contacts
0.5 s apart, where the jump is a few mm and every contact is clean.

Usage: python benchmarks/bench_long_record.py [--rows N] [--contacts K]
       [--timeout S] [--repeat N] [--out-dir DIR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.generators.longlog import simulate_log, truth, write_log  # noqa: E402
from tests.generators.rigsim import NOMINAL  # noqa: E402

__all__ = ["main", "make_log", "time_command"]

#: The targets: rows and contacts they apply to, and the time of each command.
TARGET_ROWS = 100_000
TARGET_CONTACTS = 20
TARGET_TIME_S = {"compare": 10.0, "diagnose": 60.0}

SAMPLE_RATE_HZ = 1000
GAPS_M = (0.002, 0.005)
VELOCITIES_M_PER_S = (0.05, 0.12)


def contact_list(count: int) -> list[tuple[float, float]]:
    """``count`` contacts ``(gap [m], v [m/s])`` spread over the gaps and
    velocities, paired in a scrambled order (no trend along the log)."""
    if count == 1:
        return [(GAPS_M[0], VELOCITIES_M_PER_S[0])]
    gaps_m = np.linspace(*GAPS_M, count)
    velocities_m_per_s = np.linspace(*VELOCITIES_M_PER_S, count)
    stride = next(s for s in (7, 3, 11, 13, 1) if np.gcd(s, count) == 1)
    order = (np.arange(count) * stride) % count
    return [(float(g), float(velocities_m_per_s[j])) for g, j in zip(gaps_m, order, strict=True)]


def make_log(folder: Path, rows: int, contacts: int, seed: int = 0) -> tuple[Path, dict]:
    """Write the log (CSV + JSON) into ``folder``; its CSV path and the truth."""
    info = {**NOMINAL, "compensator": "SDMDC", "run_id": f"long-log-{rows}"}
    info["sample_rate_hz"] = SAMPLE_RATE_HZ
    period_s = rows / (contacts * SAMPLE_RATE_HZ)
    log = simulate_log(info, contact_list(contacts), period_s, seed=seed)
    if log["time_s"].size != rows:
        raise SystemExit(f"--rows {rows} is not a whole number of ticks per contact")
    csv_path = write_log(folder, f"long_log_{rows}", info, log)
    facts = truth(log)
    facts["period_s"] = period_s
    return csv_path, facts


def _hybridtable() -> str:
    """The project's ``hybridtable`` executable."""
    for candidate in (
        ROOT / ".venv" / "bin" / "hybridtable",
        Path(sys.executable).parent / "hybridtable",
    ):
        if candidate.is_file():
            return str(candidate)
    found = shutil.which("hybridtable")
    if found is None:
        raise SystemExit("hybridtable is not installed (make run creates .venv)")
    return found


def time_command(argv: list[str], cwd: Path, timeout_s: float) -> dict:
    """Run ``argv`` in a fresh process at most ``timeout_s`` [s]: its exit code
    (None: timed out), wall time [s], peak resident memory [MB] and the first
    lines of its stdout and stderr (of a traceback, its last line)."""
    out_path, err_path = cwd / ".stdout", cwd / ".stderr"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        t0 = time.perf_counter()
        pid = os.posix_spawn(argv[0], argv, dict(os.environ), file_actions=_redirect(out, err))
        rc, usage = None, None
        try:
            while time.perf_counter() - t0 < timeout_s:
                done, status, usage = os.wait4(pid, os.WNOHANG)
                if done:
                    rc = os.waitstatus_to_exitcode(status)
                    break
                time.sleep(0.02)
            else:
                os.kill(pid, 9)
                _, _, usage = os.wait4(pid, 0)
        except BaseException:
            os.kill(pid, 9)
            os.wait4(pid, 0)
            raise
        wall_s = time.perf_counter() - t0
    first = {}
    for key, path in (("stdout", out_path), ("stderr", err_path)):
        lines = [x for x in path.read_text(errors="replace").splitlines() if x.strip()]
        first[key] = lines[0].strip() if lines else ""
        if first[key].startswith("Traceback"):  # the exception's own line says more
            first[key] = lines[-1].strip()
        path.unlink()
    return {
        "exit_code": rc,
        "time_s": wall_s,
        "peak_mb": usage.ru_maxrss / 1024 if usage is not None else None,
        "first_stdout": first["stdout"],
        "first_stderr": first["stderr"],
    }


def _redirect(out, err) -> list:
    return [
        (os.POSIX_SPAWN_DUP2, out.fileno(), 1),
        (os.POSIX_SPAWN_DUP2, err.fileno(), 2),
    ]


def _events(json_path: Path, facts: dict) -> dict:
    """What the command's JSON says of the split: events and whether its
    resets are the generator's."""
    try:
        document = json.loads(json_path.read_text())
    except (OSError, ValueError):
        return {}
    splits = document.get("contact_events") or []
    if not splits:
        return {"events": 1 if document else None, "resets_found": []}
    found = [int(t) for s in splits for t in s.get("reset_ticks", [])]
    return {
        "events": sum(len(s.get("events", [])) for s in splits),
        "resets_found": found,
        "resets_match": found == facts["reset_ticks"][1:],
    }


def _count(rows: int) -> str:
    text = f"{rows:.0e}".replace("e+0", "e").replace("e+", "e")
    return text if float(text) == rows else f"{rows:d}"


def _phrase(name: str, result: dict, timeout_s: float) -> str:
    target = f"target {TARGET_TIME_S[name]:g} s"
    if result["exit_code"] is None:
        return f"{name}: no answer within {timeout_s:g} s ({target})"
    if result["exit_code"] != 0:
        why = result["first_stderr"] or "no message"
        return f'{name}: exit {result["exit_code"]} after {result["time_s"]:.1f} s ("{why}")'
    return f"{name}: {result['time_s']:.1f} s ({target})"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=lambda s: int(float(s)), default=TARGET_ROWS)
    ap.add_argument("--contacts", type=int, default=TARGET_CONTACTS)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per command")
    ap.add_argument("--repeat", type=int, default=1, help="processes per command")
    ap.add_argument("--commands", default="compare,diagnose", help="comma separated")
    ap.add_argument("--seed", type=int, default=0, help="seed of the reading noise")
    ap.add_argument("--out-dir", type=Path, help="keep the log and outputs here")
    ap.add_argument("--json", type=Path, help="write the results to this JSON file")
    args = ap.parse_args(argv)
    if args.rows < 3 * args.contacts or args.contacts < 1:
        ap.error("--rows must be at least 3 per contact, --contacts at least 1")
    commands = [c for c in args.commands.split(",") if c]
    if not set(commands) <= set(TARGET_TIME_S):
        ap.error(f"--commands: choose from {', '.join(TARGET_TIME_S)}")
    folder = args.out_dir or Path(tempfile.mkdtemp(prefix="bench_long_record_"))
    folder.mkdir(parents=True, exist_ok=True)
    exe = _hybridtable()
    results = {}
    try:
        print(f"writing {_count(args.rows)} rows, {args.contacts} contacts ...", file=sys.stderr)
        t0 = time.perf_counter()
        csv_path, facts = make_log(folder / "log", args.rows, args.contacts, args.seed)
        write_s = time.perf_counter() - t0
        for name in commands:
            json_path = folder / f"{name}.json"
            runs = []
            for i in range(args.repeat):
                print(f"{name} {i + 1}/{args.repeat} ...", file=sys.stderr)
                cmd = [exe, name, str(csv_path), "--no-progress", "--json", str(json_path)]
                runs.append(time_command([*cmd, "--force"], folder, args.timeout))
                if runs[-1]["exit_code"] != 0:
                    break
            result = dict(runs[-1])
            if all(r["exit_code"] == 0 for r in runs):
                result["time_s"] = statistics.median(r["time_s"] for r in runs)
            peaks = [r["peak_mb"] for r in runs if r["peak_mb"] is not None]
            result["peak_mb"] = max(peaks) if peaks else None
            result["repeats"] = len(runs)
            result.update(_events(json_path, facts) if result["exit_code"] == 0 else {})
            results[name] = result
    finally:
        if args.out_dir is None:
            shutil.rmtree(folder, ignore_errors=True)

    size = f"{_count(args.rows)} rows, {args.contacts} contact{'s' * (args.contacts != 1)}"
    phrases = [_phrase(name, results[name], args.timeout) for name in commands]
    verdict = f"{size}: " + "; ".join(phrases)
    if (args.rows, args.contacts) != (TARGET_ROWS, TARGET_CONTACTS):
        verdict += f" (the targets are set for {_count(TARGET_ROWS)} rows, 20 contacts)"
    print(verdict)
    contacts = facts["contacts"]
    struck = sum(c["p_des_at_touch_m"] < 0.0 for c in contacts)
    jumps_mm = [1e3 * c["reset_jump_m"] for c in contacts[1:]]
    cors = [c["cor"] for c in contacts]
    print(
        f"The log: {size} {facts['period_s']:g} s apart, written in "
        f"{write_s:.1f} s; true CoR {min(cors):.3f}-{max(cors):.3f}; "
        + (
            f"reset jumps {min(jumps_mm):.1f}-{max(jumps_mm):.1f} mm; "
            if jumps_mm
            else "no reset; "
        )
        + (
            f"in {struck} of {len(contacts)} contacts the table struck the contact before "
            "the spacecraft model reached it"
            if struck
            else "the spacecraft model led the table into every contact"
        )
    )
    print()
    head = (
        f"{'command':<9} {'exit':>4} {'time [s]':>9} {'target [s]':>10} {'peak [MB]':>9} "
        f"{'events':>6} {'resets as generated':>19}  first line"
    )
    print(head)
    for name in commands:
        r = results[name]
        code = "-" if r["exit_code"] is None else str(r["exit_code"])
        peak = "-" if r["peak_mb"] is None else f"{r['peak_mb']:.0f}"
        events = r.get("events")
        match = r.get("resets_match")
        line = r["first_stdout"] if r["exit_code"] == 0 else r["first_stderr"]
        if r["exit_code"] is None:
            line = f"killed after {args.timeout:g} s"
        print(
            f"{name:<9} {code:>4} {r['time_s']:>9.1f} {TARGET_TIME_S[name]:>10g} {peak:>9} "
            f"{'-' if events is None else events:>6} "
            f"{'-' if match is None else ('yes' if match else 'no'):>19}  {line}"
        )
    print(
        f"\ntime: median of {args.repeat} fresh process(es); peak: the largest resident "
        "memory of the command or a worker; exit '-': no answer within --timeout."
    )
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        document = {
            "verdict": verdict,
            "rows": args.rows,
            "contacts": args.contacts,
            "truth": facts,
            "results": results,
        }
        args.json.write_text(json.dumps(document, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
