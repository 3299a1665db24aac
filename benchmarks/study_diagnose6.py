"""Confusion study of ``hybridtable diagnose`` on 6-DoF runs from an independent generator.

The sets come from ``tests/generators/run6_logs.py`` (``draw_set6``), whose loop
is ``tests/generators/rig6.py``: plain numpy, written from
``docs/run6-format.md`` and ``docs/six_dof.md`` alone, no ``hybridtable``
code. Every set draws its own rig (sample rate 500/1000/2000 Hz, delay, mass,
stiffness, inertia, pads, dissipation, table, compensator none/SDC/MDC/SDMDC,
F/T and encoder noise) and 1-3 runs of it at different approaches (speed,
tilt, lateral miss), and hides:

- ``null``: nothing;
- ``single``: one library effect (round-robin over the eighteen of
  ``docs/run6-format.md``, "The effects, as laws");
- ``pair``: two library effects acting on different parts of the rig
  (contact, sensor dynamics, sensor statics, table, rig computer);
- ``outside``: an effect outside the library (round-robin over
  ``rig6.OUTSIDE_EFFECTS``: backlash in a lateral table axis, a pad standing
  proud, a quadratic gain of the normal force channel, lateral table axes
  slower than the axial one; the ringing sensor mount, outside when the
  generator was written, is now the library's ``mount_resonance``).

Each effect is sized by the generator's own runs: the nominal model's replay
of the set's first run is 3.75-6.5 noise levels off in its worst channel (RMS
over the contact); an outside effect by what is left after projecting the
difference off the library's effects (linearized). ``com_offset`` (the rig
computer's centre of mass) is drawn, 2-10 cm.

Each set is written to a temporary folder and diagnosed in a subprocess,
``python -m hybridtable.cli diagnose DIR --json FILE --no-progress --workers N``
(exit codes other than 0 and 1 are recorded as errors), and scored:

- null: ``right`` when the verdict is "nothing missing", else ``wrong`` (a
  false positive);
- single: ``right`` when the hidden effect is among those diagnose names (its
  ``selected`` and ``found`` lists and the audit's findings), ``wrong`` when it
  names others only, ``missed`` when it names none;
- pair: ``right`` when both are named, ``wrong`` when it names anything else
  or one of the two, ``missed`` when it names none (a hidden effect among the
  diagnosis's look-alikes is noted, not counted);
- single and pair: ``alike`` rather than ``wrong`` when every hidden effect is
  named or a look-alike the verdict names for a named one, and every named
  effect stands for a hidden one (``lookalikes_of`` in the JSON: the 1-D
  study's rule, ``benchmarks/study_diagnose.py``); the single target is
  reported both ways;
- outside: ``flagged`` when the verdict is "not explained", else ``missed``
  ("nothing missing") or ``wrong`` (library effects said to explain it).

Prints a line per set, a table per class (with the misfits: what diagnose
said instead) and the targets: nulls no false positive, singles >= 90 %
right, outside >= 90 % flagged.

Usage: python benchmarks/study_diagnose6.py [--seed N] [--sets-per-class N]
       [--only CLASS,...] [--workers N] [--json OUT] [--keep DIR] [--quick]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.generators import rig6, run6_logs  # noqa: E402

CLASSES = ("null", "single", "pair", "outside")
#: The outcomes per class, in table order.
OUTCOMES = ("right", "alike", "wrong", "missed", "flagged", "error")
#: Every effect name diagnose could say (the library's, the generator's outside ones).
KNOWN_EFFECTS = tuple(rig6.LIBRARY_EFFECTS) + tuple(rig6.OUTSIDE_EFFECTS)
#: Names of the rig computer's audit (docs/run6-format.md, "The audit of the rig
#: computer's spacecraft").
AUDIT_NAMES = ("com_offset", "mass_error", "inertia_error", "spacecraft_model_error")
DEFAULT_SETS, QUICK_SETS = 12, 2


def plan(seed: int, sets_per_class: int, classes) -> list[dict]:
    """The sets to draw: class, index, the set's seed and its effects (``None``: drawn)."""
    library, outside = run6_logs.LIBRARY_EFFECTS, run6_logs.OUTSIDE_EFFECTS
    out = []
    for c, cls in enumerate(CLASSES):
        if cls not in classes:
            continue
        for i in range(sets_per_class):
            effects = None
            if cls == "single":
                effects = [library[(seed + i) % len(library)]]
            elif cls == "outside":
                effects = [outside[(seed + i) % len(outside)]]
            elif cls == "null":
                effects = []
            out.append(
                {"class": cls, "index": i, "seed": seed * 10000 + c * 1000 + i, "effects": effects}
            )
    return out


def _names_in(item) -> set[str]:
    """Effect names an entry of the JSON carries (a name, or a dict naming one)."""
    if isinstance(item, str):
        return {item} if item in KNOWN_EFFECTS or item in AUDIT_NAMES else set()
    if isinstance(item, dict):
        for key in ("effect", "name"):
            if isinstance(item.get(key), str):
                return {item[key]}
        text = json.dumps(item)
        return {n for n in KNOWN_EFFECTS + AUDIT_NAMES if f'"{n}"' in text}
    return set()


def named_effects(doc: dict) -> set[str]:
    """The effects a diagnosis names: ``selected``, ``found`` and the audit's findings."""
    names: set[str] = set()
    for key in ("selected", "found"):
        for item in doc.get(key) or []:
            names |= _names_in(item)
    audit = doc.get("audit") or {}
    for item in audit.get("findings") or []:
        names |= _names_in(item)
    return names


def score(cls: str, effects: list[str], doc: dict | None) -> tuple[str, str]:
    """The outcome of a set and, when it is not right, what diagnose said."""
    if doc is None:
        return "error", "no diagnosis"
    verdict = str(doc.get("verdict", ""))
    named = named_effects(doc)
    said = f"{verdict}: {' + '.join(sorted(named)) or 'no effect'}"
    if cls == "null":
        return ("right", "") if verdict.startswith("nothing") else ("wrong", said)
    if cls == "outside":
        if verdict == "not explained":
            return "flagged", ""
        return ("missed" if verdict.startswith("nothing") else "wrong"), said
    if set(effects) <= named:
        return "right", ""
    alike = set()
    for item in doc.get("lookalikes") or []:
        alike |= _names_in(item)
    if set(effects) & alike:
        said += f" (look-alikes: {' + '.join(sorted(alike))})"
    of = doc.get("lookalikes_of") or {}

    def accounts(s: str, t: str) -> bool:  # the 1-D study's rule
        return s == t or t in of.get(s, ())

    hidden = set(effects)
    if all(any(accounts(s, t) for s in named) for t in hidden) and all(
        any(accounts(s, t) for t in hidden) for s in named - set(AUDIT_NAMES)
    ):
        return "alike", said
    if not named:
        return "missed", said
    return "wrong", said


def diagnose(folder: Path, out_json: Path, workers: int, timeout_s: float) -> dict:
    """Run ``hybridtable diagnose`` on a folder in a subprocess; its JSON, exit code, time."""
    cmd = [sys.executable, "-m", "hybridtable.cli", "diagnose", str(folder)]
    cmd += ["--json", str(out_json), "--no-progress", "--workers", str(workers), "--force"]
    start = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, cwd=ROOT)
        code, stdout, stderr = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        code, stdout, stderr = "timeout", "", f"diagnose did not finish in {timeout_s} s"
    wall = time.perf_counter() - start
    doc = None
    if code in (0, 1) and out_json.exists():
        try:
            doc = json.loads(out_json.read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            stderr += f"\nunreadable JSON: {exc}"
    return {
        "doc": doc,
        "exit_code": code,
        "wall_s": wall,
        "sentence": (stdout.splitlines() or [""])[0],
        "stderr": stderr[-2000:] if doc is None else "",
    }


def run_set(item: dict, workers: int, timeout_s: float, keep: Path | None) -> dict:
    """Draw, write, diagnose and score one set."""
    start = time.perf_counter()
    s6 = run6_logs.draw_set6(item["seed"], item["class"], item["effects"])
    gen_s = time.perf_counter() - start
    tag = f"{item['class']}-{item['index']:02d}-{'+'.join(s6.effects) or 'nothing'}"
    with tempfile.TemporaryDirectory(prefix="study6-") as tmp:
        folder = Path(tmp) / tag
        run6_logs.write_set6(folder, s6)
        result = diagnose(folder, Path(tmp) / "diagnosis.json", workers, timeout_s)
        if keep is not None:
            dest = keep / tag
            shutil.rmtree(dest, ignore_errors=True)
            shutil.copytree(folder, dest)
            (dest / "truth.json").write_text(json.dumps(s6.truth, indent=2) + "\n")
            if result["doc"] is not None:  # beside the runs: a reader takes it for a run
                diagnosis = keep / f"{tag}.diagnosis.json"
                diagnosis.write_text(json.dumps(result["doc"], indent=2) + "\n")
    outcome, said = score(item["class"], s6.effects, result["doc"])
    if result["doc"] is None:
        said = f"exit {result['exit_code']}: {result['stderr'].strip().splitlines()[-1:] or ''}"
    doc = result["doc"] or {}
    return {
        "class": item["class"],
        "index": item["index"],
        "seed": item["seed"],
        "tag": tag,
        "effects": s6.effects,
        "hidden": s6.truth["hidden"],
        "sizing": {
            e: {k: r[k] for k in ("ratio", "nominal_ratio", "worst", "record_ratio", "target")}
            for e, r in s6.truth["sizing"].items()
        },
        "runs": len(s6.runs),
        "compensator": s6.truth["rig"]["compensator"]["name"],
        "sample_rate_hz": s6.truth["rig"]["rig"]["sample_rate_hz"],
        "outcome": outcome,
        "said": said,
        "verdict": doc.get("verdict"),
        "named": sorted(named_effects(doc)),
        "sentence": doc.get("sentence", result["sentence"]),
        "nominal_errors": doc.get("nominal_errors"),
        "final_errors": doc.get("final_errors"),
        "separating_runs": doc.get("separating_runs"),
        "exit_code": result["exit_code"],
        "stderr": result["stderr"],
        "generate_s": gen_s,
        "diagnose_s": result["wall_s"],
    }


def summarize(results: list[dict]) -> tuple[str, dict]:
    """The table per class, the misfits and the targets (text, and as JSON)."""
    by_class: dict[str, list[dict]] = defaultdict(list)
    for r in results:
        by_class[r["class"]].append(r)
    lines = [
        f"{'class':8} {'sets':>4} " + " ".join(f"{o:>7}" for o in OUTCOMES) + "  misfits",
    ]
    table = {}
    for cls in CLASSES:
        rows = by_class.get(cls)
        if not rows:
            continue
        counts = Counter(r["outcome"] for r in rows)
        misfits = Counter(
            f"{'+'.join(r['effects']) or 'nothing'} -> {r['said']}"
            for r in rows
            if r["outcome"] not in ("right", "flagged")
        )
        table[cls] = {"sets": len(rows), **{o: counts.get(o, 0) for o in OUTCOMES}}
        table[cls]["misfits"] = dict(misfits)
        lines.append(
            f"{cls:8} {len(rows):>4} "
            + " ".join(f"{counts.get(o, 0):>7}" for o in OUTCOMES)
            + ("  " + "; ".join(f"{m} (x{n})" if n > 1 else m for m, n in misfits.items()))
        )
    targets = {}

    def share(cls, outcome):
        rows = by_class.get(cls)
        return None if not rows else sum(r["outcome"] == outcome for r in rows) / len(rows)

    if "null" in by_class:
        fp = sum(r["outcome"] != "right" for r in by_class["null"])
        targets["null false positives"] = {"value": fp, "target": "0", "met": fp == 0}
    for cls, outcome, goal in (("single", "right", 0.9), ("outside", "flagged", 0.9)):
        value = share(cls, outcome)
        if cls == "single" and value is not None:
            lenient = value + share(cls, "alike")
            targets["single right or a look-alike it names (the 1-D study's rule)"] = {
                "value": lenient,
                "target": f">= {goal:.0%}",
                "met": lenient >= goal,
            }
        if value is not None:
            targets[f"{cls} {outcome}"] = {
                "value": value,
                "target": f">= {goal:.0%}",
                "met": value >= goal,
            }
    if "pair" in by_class:
        targets["pair right (no target)"] = {"value": share("pair", "right"), "target": "-"}
    lines.append("")
    lines.append("targets:")
    for name, t in targets.items():
        value = t["value"] if isinstance(t["value"], int) else f"{t['value']:.0%}"
        met = {True: "met", False: "NOT met"}.get(t.get("met"), "")
        lines.append(f"  {name}: {value} (target {t['target']}) {met}")
    per_effect: dict[str, Counter] = defaultdict(Counter)
    for r in results:
        if r["class"] in ("single", "outside"):
            per_effect[r["effects"][0]][r["outcome"]] += 1
    if per_effect:
        lines.append("")
        lines.append("per effect (single, outside):")
        for name, counts in per_effect.items():
            lines.append(f"  {name:22} " + ", ".join(f"{o} {n}" for o, n in counts.items()))
    return "\n".join(lines), {"table": table, "targets": targets}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=0, help="draws sets never seen (default 0)")
    parser.add_argument(
        "--sets-per-class",
        type=int,
        default=None,
        help=f"sets per class (default {DEFAULT_SETS}; {QUICK_SETS} with --quick)",
    )
    parser.add_argument(
        "--only", default=",".join(CLASSES), help=f"classes, comma separated ({','.join(CLASSES)})"
    )
    parser.add_argument("--workers", type=int, default=2, help="diagnose's --workers (default 2)")
    parser.add_argument("--json", type=Path, default=None, help="write every set's result here")
    parser.add_argument(
        "--keep",
        type=Path,
        default=None,
        help="keep each set's runs and truth.json in DIR/TAG, its diagnosis in DIR/TAG.diagnosis.json",
    )
    parser.add_argument(
        "--quick", action="store_true", help=f"{QUICK_SETS} sets per class (about 3 minutes)"
    )
    parser.add_argument(
        "--timeout-s", type=float, default=900.0, help="per diagnose call (default 900)"
    )
    args = parser.parse_args(argv)
    classes = [c.strip() for c in args.only.split(",") if c.strip()]
    unknown = set(classes) - set(CLASSES)
    if unknown:
        parser.error(f"--only: unknown classes {sorted(unknown)} (one of {CLASSES})")
    n = args.sets_per_class or (QUICK_SETS if args.quick else DEFAULT_SETS)
    if n < 1:
        parser.error("--sets-per-class must be at least 1")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
    todo = plan(args.seed, n, classes)
    print(f"{len(todo)} sets ({n} per class: {', '.join(classes)}), seed {args.seed}", flush=True)
    results = []
    start = time.perf_counter()
    for item in todo:
        try:
            r = run_set(item, args.workers, args.timeout_s, args.keep)
        except Exception as exc:  # a generator failure is recorded, not fatal
            r = {
                "class": item["class"],
                "index": item["index"],
                "seed": item["seed"],
                "tag": f"{item['class']}-{item['index']:02d}",
                "effects": item["effects"] or [],
                "outcome": "error",
                "said": f"generator: {type(exc).__name__}: {exc}",
                "generate_s": 0.0,
                "diagnose_s": 0.0,
            }
        results.append(r)
        sizing = ", ".join(
            f"{e} {s['ratio']:.1f}x ({s['worst']})" for e, s in (r.get("sizing") or {}).items()
        )
        print(
            f"{r['tag']:42} {r['outcome']:8} gen {r['generate_s']:5.1f}s diag "
            f"{r['diagnose_s']:5.1f}s  {sizing}  {r['said']}",
            flush=True,
        )
    wall = time.perf_counter() - start
    text, summary = summarize(results)
    print()
    print(text)
    print(f"\n{len(results)} sets in {wall:.0f} s ({wall / max(len(results), 1):.1f} s a set)")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        document = {
            "seed": args.seed,
            "sets_per_class": n,
            "classes": classes,
            "workers": args.workers,
            "wall_s": wall,
            **summary,
            "sets": results,
        }
        args.json.write_text(json.dumps(document, indent=2, default=str) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
