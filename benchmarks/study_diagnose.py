"""Confusion study of ``diagnose`` on sets from an independent generator.

The sets come from ``tests/generators/rigzoo.py``, written from the physics
and the run format alone (no ``hybridtable`` code): every set draws its own
rig (mass, stiffness, delay, table, rate, deadband, noise white / AR(1) /
AR(2), 2-5 runs at varied approach velocities and compensators) and hides
nothing (null), one library effect sized to a nominal error of 2 or 5
(single), a pair (pair; pair_cancel: one dissipates, one adds energy, the
CoR unchanged), an effect outside the library (outside), a computer effect
(computer: mass, lead time, compensator stiffness), or a library effect at
the detection limit (tiny, counted apart). A different ``--seed`` draws sets
never seen.

Three more classes, drawn only when ``--only`` names them (the default study
is the seven above, unchanged), hold a rig condition (``rigzoo``'s
``CONDITION_CLASSES``) with a null or a single library effect:
``deadband0`` (``force_deadband_n = 0``: the noise passes the gate in free
flight), ``fractional_delay`` (``sensor_delay_s`` not a whole number of
ticks) and ``integrator`` (the rig computer steps the model by explicit
Euler, trapezoid or RK4, which the JSON does not say). They are scored as a
null (nothing hidden) or a single; the integrator's rule, where the
diagnosis reports one, is scored too ("integrator named": the rule or one
equivalent to it for a held force, RK4 = trapezoid).

Each set is written to a folder, read with ``read_runs`` and diagnosed; the
verdict is scored per class:

- null: "right" if nothing is named, else "false positive";
- single / tiny / computer: "right" (the hidden effect, or a look-alike of a
  named one, and nothing else), "right+extra", "wrong", "missed";
- pair / pair_cancel: "both", "one", "wrong" (only other effects), "none";
- outside: "flagged" if the diagnosis says ``explained: false``, else
  "not flagged";
- deadband0 / fractional_delay / integrator: as a null ("right", "false
  positive") when nothing is hidden, else as a single.

Every set also records whether the diagnosis said ``explained: true`` with a
held-out error above 1.3 (noise units). Prints a line per set, a summary per
class, the wall time per set and the acceptance figures (nulls: nothing
named; single >= 95 % named; pairs >= 80 % both; outside >= 90 % flagged; no
``explained: true`` above 1.3).

Usage: python benchmarks/study_diagnose.py [--seed N] [--sets N]
       [--only CLASS,...] [--workers N] [--json FILE] [--markdown FILE]
       [--keep DIR]
       (e.g. --only deadband0,fractional_delay,integrator for the conditions)
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import tempfile
import time
import traceback
from collections import Counter, defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tqdm import tqdm  # noqa: E402

from hybridtable.diagnosis.diagnose import diagnose  # noqa: E402
from hybridtable.measurement.run_reader import read_runs  # noqa: E402
from tests.generators import rigzoo  # noqa: E402

#: Outcomes per class, in table order.
OUTCOMES = {
    "null": ("right", "false positive"),
    "single": ("right", "right+extra", "wrong", "missed"),
    "tiny": ("right", "right+extra", "wrong", "missed"),
    "computer": ("right", "right+extra", "wrong", "missed"),
    "pair": ("both", "one", "wrong", "none"),
    "pair_cancel": ("both", "one", "wrong", "none"),
    "outside": ("flagged", "not flagged"),
}
#: The rig-condition classes: a null or a single library effect.
for _c in rigzoo.CONDITION_CLASSES:
    OUTCOMES[_c] = ("right", "right+extra", "false positive", "wrong", "missed")
#: The audit's JSON key for each computer effect, and the generator's parameter.
COMPUTER_KEYS = {
    "mass_error": ("spacecraft_mass_kg", "m_used_kg"),
    "lead_time_error": ("lead_time_s", "lead_used_s"),
    "compensator_stiffness_error": ("contact_stiffness_n_per_m", "k_used_n_per_m"),
}
EXPLAINED_LIMIT = 1.3
#: A noise estimate this many times the true std is reported (signal absorbed).
NOISE_RATIO_LIMIT = 1.5


# --------------------------------------------------------------------------- #
# Reading the diagnosis (tolerant of today's JSON)
# --------------------------------------------------------------------------- #
def selected_of(j: dict) -> list[str]:
    sel = list(j.get("selected") or [])
    for f in (j.get("audit") or {}).get("findings") or []:
        eff = f.get("effect")
        if eff and eff not in sel:
            sel.append(eff)
    return sel


def lookalikes_of(j: dict, selected: list[str]) -> dict[str, set[str]]:
    la = j.get("lookalikes")
    out: dict[str, set[str]] = defaultdict(set)
    if isinstance(la, dict):
        for k, v in la.items():
            out[k].update(v or [])
    else:
        for c in j.get("ranking") or []:
            if c.get("effect") in selected:
                out[c["effect"]].update(c.get("indistinguishable_from") or [])
    return out


def explained_of(j: dict) -> bool:
    v = j.get("explained")
    if v is None:
        return j.get("verdict") != "unexplained"
    return bool(v)


def heldout_of(j: dict) -> float:
    rem = j.get("remaining") or {}
    v = rem.get("heldout_error")
    if v is None:
        st = j.get("staircase") or []
        v = st[-1].get("heldout_error") if st else None
    return float(v) if v is not None else math.nan


#: Names a diagnosis may give the rig computer's integrator, to rigzoo's.
INTEGRATOR_ALIASES = {
    "semi_implicit_euler": "semi_implicit_euler",
    "semi_implicit": "semi_implicit_euler",
    "symplectic_euler": "semi_implicit_euler",
    "symplectic": "semi_implicit_euler",
    "explicit_euler": "explicit_euler",
    "forward_euler": "explicit_euler",
    "euler": "explicit_euler",
    "trapezoid": "trapezoid",
    "trapezoidal": "trapezoid",
    "rk4": "rk4",
    "runge_kutta": "rk4",
    "exact": "trapezoid",
    "zoh": "trapezoid",
}


def integrator_of(j: dict) -> str | None:
    """The integrator rule the diagnosis names, in rigzoo's names (None if it
    names none; tolerant of where the JSON puts it)."""
    found = None
    for where in (j, j.get("computer") or {}, j.get("audit") or {}):
        if isinstance(where, dict) and where.get("integrator") is not None:
            found = where["integrator"]
            break
    if found is None:
        for f in (j.get("audit") or {}).get("findings") or []:
            if (
                f.get("key") in ("integrator", "integration_rule")
                or f.get("effect") == "integrator"
            ):
                found = f.get("used", f.get("value"))
                break
    if isinstance(found, dict):
        found = found.get("rule") or found.get("name") or found.get("used")
    if not isinstance(found, str):
        return None
    key = found.strip().lower().replace("-", "_").replace(" ", "_")
    return INTEGRATOR_ALIASES.get(key, key)


def integrator_score(spec: rigzoo.SetSpec, j: dict) -> dict:
    """The rig's integrator against the one the diagnosis names (``right``:
    the same rule or one equivalent to it for a held force; None: none named)."""
    true = spec.rig.integrator
    named = integrator_of(j)
    eq = rigzoo.INTEGRATOR_EQUIVALENT
    right = None if named is None else eq.get(named, named) == eq[true]
    return {"true": true, "named": named, "right": right}


def accounts(s: str, t: str, la: dict[str, set[str]]) -> bool:
    """Named effect ``s`` stands for the hidden ``t`` (itself or a look-alike)."""
    return s == t or t in la.get(s, ()) or s in la.get(t, ())


def score(spec: rigzoo.SetSpec, j: dict) -> dict:
    """Outcome of one diagnosis against the set's truth."""
    sel = selected_of(j)
    if spec.rig.integrator != rigzoo.DEFAULT_INTEGRATOR:
        # the rule is the set's condition, scored apart ("integrator named"):
        # the audit's finding of it is no effect named
        sel = [s for s in sel if s != "integrator_error"]
    la = lookalikes_of(j, sel)
    expl = explained_of(j)
    held = heldout_of(j)
    truth = sorted(spec.truth())
    label = spec.label
    extras = [s for s in sel if not any(accounts(s, t, la) for t in truth)]
    hit = [t for t in truth if any(accounts(s, t, la) for s in sel)]
    if label == "null" or (label in rigzoo.CONDITION_CLASSES and not truth):
        outcome = "false positive" if sel else "right"
    elif label == "outside":
        outcome = "not flagged" if expl else "flagged"
    elif label in ("pair", "pair_cancel"):
        if len(hit) == len(truth):
            outcome = "both"
        elif hit:
            outcome = "one"
        else:
            outcome = "wrong" if sel else "none"
    else:
        if hit:
            outcome = "right+extra" if extras else "right"
        else:
            outcome = "wrong" if sel else "missed"
    row = {
        "outcome": outcome,
        "verdict": j.get("verdict"),
        "selected": sel,
        "extras": extras,
        "hit": hit,
        "explained": expl,
        "heldout_error": held,
        "explained_true_above_1.3": bool(expl and math.isfinite(held) and held > EXPLAINED_LIMIT),
        "lookalikes": {k: sorted(v) for k, v in la.items()},
    }
    if label == "computer":
        row["audit"] = audit_accuracy(spec, j)
    if label in rigzoo.CONDITION_CLASSES:
        row["condition"] = spec.condition()
        row["integrator"] = integrator_score(spec, j)
        if spec.hidden and spec.hidden[0].kind == "computer":
            row["audit"] = audit_accuracy(spec, j)
    return row


def audit_accuracy(spec: rigzoo.SetSpec, j: dict) -> dict:
    """The audit's value against the value the generator's computer used."""
    h = spec.hidden[0]
    key, par = COMPUTER_KEYS[h.name]
    true_used = h.params(spec.scales)[par]
    for f in (j.get("audit") or {}).get("findings") or []:
        if f.get("key") == key:
            used = f.get("used")
            if used is None:
                break
            return {
                "key": key,
                "true_used": true_used,
                "found_used": used,
                "json": f.get("json"),
                "relative_error": (used - true_used) / true_used,
                "reported_relative_error": f.get("relative_error"),
            }
    return {"key": key, "true_used": true_used, "found_used": None, "relative_error": None}


# --------------------------------------------------------------------------- #
# The study
# --------------------------------------------------------------------------- #
def pick(specs: list[rigzoo.SetSpec], only: set[str] | None, n: int | None):
    """Sets of the classes ``only``, interleaved across classes, the first ``n``."""
    by: dict[str, list] = defaultdict(list)
    for s in specs:
        if only is None or s.label in only:
            by[s.label].append(s)
    out = []
    queues = [list(by[c]) for c in rigzoo.CLASSES if by[c]]
    while any(queues):
        for q in queues:
            if q:
                out.append(q.pop(0))
    return out[:n] if n else out


def run_one(spec: rigzoo.SetSpec, root: Path, workers: int | None) -> dict:
    t0 = time.perf_counter()
    sized = rigzoo.resolve(spec)
    folder = root / sized.set_id
    if folder.exists():
        shutil.rmtree(folder)
    rigzoo.write_set(folder, sized)
    gen_s = time.perf_counter() - t0
    (root / f"{sized.set_id}.truth.json").write_text(json.dumps(sized.to_json(), indent=2) + "\n")
    t1 = time.perf_counter()
    d = diagnose(read_runs([folder]), workers=workers)
    j = d.to_json()
    wall = time.perf_counter() - t1
    row = {"set": sized.to_json(), "generate_s": gen_s, "diagnose_s": wall}
    row.update(score(sized, j))
    row["noise_ratio"] = noise_ratio(sized, j)
    return row


def noise_ratio(spec: rigzoo.SetSpec, j: dict) -> dict:
    """The diagnosis' noise estimate over the true noise std, per channel
    (mean over runs): far above 1, the noise model has absorbed signal."""
    true = {"f_mea_n": spec.noise.sigma_f, "p_act_m": spec.noise.sigma_p}
    out = {}
    for ch, sig in true.items():
        vals = [
            r["noise"][ch]["rms"]
            for r in j.get("runs") or []
            if ch in (r.get("noise") or {}) and r["noise"][ch].get("rms") is not None
        ]
        if vals:
            out[ch] = sum(vals) / len(vals) / sig
    return out


def line(row: dict) -> str:
    s = row["set"]
    truth = "+".join(s["truth"]) or (
        "(outside: " + s["hidden"][0]["name"] + ")" if s["hidden"] else "-"
    )
    named = " + ".join(row.get("selected") or []) or "-"
    extra = ""
    if row.get("explained_true_above_1.3"):
        extra += f"  [explained:true at {row['heldout_error']:.2f}]"
    big = {c: v for c, v in (row.get("noise_ratio") or {}).items() if v > NOISE_RATIO_LIMIT}
    if big:
        extra += (
            "  [noise estimate "
            + ", ".join(f"{c} {v:.1f}x" for c, v in big.items())
            + " the truth]"
        )
    aud = row.get("audit")
    if aud and aud.get("relative_error") is not None:
        extra += f"  [audit rel. err {aud['relative_error']:+.2e}]"
    integ = row.get("integrator")
    if integ and s["label"] == "integrator":
        extra += f"  [integrator {integ['true']}, named {integ['named'] or '-'}]"
    err = s["info"].get("error")
    err_s = f"{err:.2f}" if isinstance(err, float) else "-"
    return (
        f"{s['set_id'][:48]:48s} {s['label']:11s} err {err_s:>5s}  truth {truth:36s} "
        f"named {named:36s} -> {row['outcome']}"
        f"  (gen {row['generate_s']:.1f} s, diag {row['diagnose_s']:.1f} s){extra}"
    )


def summarise(rows: list[dict]) -> dict:
    by: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        by[r["set"]["label"]].append(r)
    classes = {}
    for c in rigzoo.CLASSES:
        rs = by.get(c, [])
        if not rs:
            continue
        cnt = Counter(r["outcome"] for r in rs)
        classes[c] = {
            "n": len(rs),
            "counts": {o: cnt.get(o, 0) for o in (*OUTCOMES[c], "error")},
            "rates": {o: cnt.get(o, 0) / len(rs) for o in (*OUTCOMES[c], "error")},
            "explained_true_above_1.3": sum(bool(r.get("explained_true_above_1.3")) for r in rs),
            "noise_overestimated": sum(
                any(v > NOISE_RATIO_LIMIT for v in (r.get("noise_ratio") or {}).values())
                for r in rs
            ),
        }
        if c == "outside":
            classes[c]["not_flagged_named"] = dict(
                Counter(
                    " + ".join(r.get("selected") or []) or "none"
                    for r in rs
                    if r["outcome"] == "not flagged"
                )
            )
        if c == "integrator":
            classes[c]["integrator_named"] = sum(
                bool((r.get("integrator") or {}).get("right")) for r in rs
            )
        if c in rigzoo.CONDITION_CLASSES:
            classes[c]["integrator_named_wrongly"] = sum(
                (r.get("integrator") or {}).get("right") is False for r in rs
            )
        if c == "computer":
            errs = [
                abs(r["audit"]["relative_error"])
                for r in rs
                if r.get("audit") and r["audit"].get("relative_error") is not None
            ]
            classes[c]["audit_abs_relative_error_max"] = max(errs) if errs else None
    by_effect: dict[str, dict[str, dict[str, int]]] = {}
    for r in rows:
        lab = r["set"]["label"]
        if (
            lab in ("single", "tiny", "outside", "computer", *rigzoo.CONDITION_CLASSES)
            and r["set"]["hidden"]
        ):
            name = r["set"]["hidden"][0]["name"]
            cell = by_effect.setdefault(lab, {}).setdefault(name, {})
            cell[r["outcome"]] = cell.get(r["outcome"], 0) + 1
    done = [r for r in rows if r["outcome"] != "error"]
    walls = [r["diagnose_s"] for r in done]
    gens = [r["generate_s"] for r in rows if "generate_s" in r]

    def rate(c, good):
        k = classes.get(c)
        if not k:
            return None
        return sum(k["counts"].get(o, 0) for o in good) / k["n"]

    pairs = [r for r in rows if r["set"]["label"] in ("pair", "pair_cancel")]
    acceptance = {
        "nulls_named": (classes.get("null") or {}).get("counts", {}).get("false positive"),
        "single_named_rate": rate("single", ("right", "right+extra")),
        "pairs_both_rate": (
            sum(r["outcome"] == "both" for r in pairs) / len(pairs) if pairs else None
        ),
        "outside_flagged_rate": rate("outside", ("flagged",)),
        "explained_true_above_1.3": sum(bool(r.get("explained_true_above_1.3")) for r in rows),
    }
    targets = {
        "nulls_named": lambda v: v == 0,
        "single_named_rate": lambda v: v >= 0.95,
        "pairs_both_rate": lambda v: v >= 0.80,
        "outside_flagged_rate": lambda v: v >= 0.90,
        "explained_true_above_1.3": lambda v: v == 0,
    }
    passed = {k: (None if v is None else bool(targets[k](v))) for k, v in acceptance.items()}
    return {
        "classes": classes,
        "by_effect": by_effect,
        "wall_time_s": {
            "diagnose_mean": sum(walls) / len(walls) if walls else None,
            "diagnose_max": max(walls) if walls else None,
            "generate_mean": sum(gens) / len(gens) if gens else None,
            "generate_max": max(gens) if gens else None,
        },
        "acceptance": acceptance,
        "passed": passed,
        "errors": sum(r["outcome"] == "error" for r in rows),
    }


def fmt_rate(v):
    return "-" if v is None else f"{100 * v:.0f} %"


def markdown(summary: dict, rows: list[dict], args) -> str:
    out = [
        "# Confusion study of `diagnose` (independent generator `rigzoo`)",
        "",
        f"Seed {args.seed}, {len(rows)} sets, workers {args.workers or 'default'}.",
        "",
        "## Per class",
        "",
        "| class | sets | outcomes | explained:true above 1.3 | noise estimate > 1.5x truth |",
        "| --- | ---: | --- | ---: | ---: |",
    ]
    for c, k in summary["classes"].items():
        oc = ", ".join(
            f"{o} {n} ({100 * k['rates'][o]:.0f} %)"
            for o, n in k["counts"].items()
            if n or o != "error"
        )
        out.append(
            f"| {c} | {k['n']} | {oc} | {k['explained_true_above_1.3']} | "
            f"{k.get('noise_overestimated', 0)} |"
        )
    out += ["", "## Per hidden effect", "", "| class | effect | outcomes |", "| --- | --- | --- |"]
    for lab, cells in summary.get("by_effect", {}).items():
        for name, cnt in sorted(cells.items()):
            oc = ", ".join(f"{o} {n}" for o, n in sorted(cnt.items()))
            out.append(f"| {lab} | {name} | {oc} |")
    out += [
        "",
        "## Acceptance",
        "",
        "| figure | value | target | met |",
        "| --- | ---: | --- | --- |",
    ]
    acc, ok = summary["acceptance"], summary["passed"]
    labels = {
        "nulls_named": ("nulls with an effect named", "0"),
        "single_named_rate": ("single: hidden effect named", ">= 95 %"),
        "pairs_both_rate": ("pairs: both named", ">= 80 %"),
        "outside_flagged_rate": ("outside: flagged (explained false)", ">= 90 %"),
        "explained_true_above_1.3": ("explained:true with held-out error > 1.3", "0"),
    }
    for key, (lab, tgt) in labels.items():
        v = acc[key]
        vs = "-" if v is None else (fmt_rate(v) if "rate" in key else str(v))
        met = {True: "yes", False: "**no**", None: "-"}[ok[key]]
        out.append(f"| {lab} | {vs} | {tgt} | {met} |")
    w = summary["wall_time_s"]
    if w["diagnose_mean"] is not None:
        out += [
            "",
            f"Wall time per set: diagnose mean {w['diagnose_mean']:.1f} s, max "
            f"{w['diagnose_max']:.1f} s; generation mean {w['generate_mean']:.1f} s, "
            f"max {w['generate_max']:.1f} s.",
        ]
    out += [
        "",
        "## Sets",
        "",
        "| set | class | nominal error | truth | named | explained | held-out | outcome |",
        "| --- | --- | ---: | --- | --- | --- | ---: | --- |",
    ]
    for r in rows:
        s = r["set"]
        truth = " + ".join(s["truth"]) or (f"({s['hidden'][0]['name']})" if s["hidden"] else "-")
        err = s["info"].get("error")
        err_s = f"{err:.2f}" if isinstance(err, float) else "-"
        held = r.get("heldout_error")
        held_s = f"{held:.2f}" if isinstance(held, float) and math.isfinite(held) else "-"
        named = " + ".join(r.get("selected") or []) or "-"
        out.append(
            f"| {s['set_id']} | {s['label']} | {err_s} | {truth} | {named} | "
            f"{r.get('explained', '-')} | {held_s} | {r['outcome']} |"
        )
    return "\n".join(out) + "\n"


def print_summary(summary: dict) -> None:
    print("\nclass        sets  outcomes")
    for c, k in summary["classes"].items():
        oc = "  ".join(
            f"{o} {n} ({100 * k['rates'][o]:.0f}%)"
            for o, n in k["counts"].items()
            if n or o != "error"
        )
        extra = ""
        if k["explained_true_above_1.3"]:
            extra += f"  explained:true>1.3: {k['explained_true_above_1.3']}"
        if k.get("noise_overestimated"):
            extra += f"  noise estimate >{NOISE_RATIO_LIMIT}x truth: {k['noise_overestimated']}"
        if k.get("not_flagged_named"):
            extra += f"  not flagged named: {k['not_flagged_named']}"
        if k.get("audit_abs_relative_error_max") is not None:
            extra += f"  audit |rel. err| max {k['audit_abs_relative_error_max']:.2e}"
        if "integrator_named" in k:
            extra += f"  integrator named: {k['integrator_named']}/{k['n']}"
        if k.get("integrator_named_wrongly"):
            extra += f"  integrator named wrongly: {k['integrator_named_wrongly']}"
        print(f"{c:12s} {k['n']:4d}  {oc}{extra}")
    for lab, cells in summary.get("by_effect", {}).items():
        bad = {n: c for n, c in cells.items() if set(c) - {"right", "flagged"}}
        if bad:
            print(f"  {lab} not right: " + "; ".join(f"{n} {c}" for n, c in sorted(bad.items())))
    w = summary["wall_time_s"]
    if w["diagnose_mean"] is not None:
        print(
            f"\nwall time per set: diagnose mean {w['diagnose_mean']:.1f} s, max "
            f"{w['diagnose_max']:.1f} s; generation mean {w['generate_mean']:.1f} s, max "
            f"{w['generate_max']:.1f} s"
        )
    acc, ok = summary["acceptance"], summary["passed"]
    print("\nacceptance:")
    for key, tgt in (
        ("nulls_named", "== 0"),
        ("single_named_rate", ">= 95 %"),
        ("pairs_both_rate", ">= 80 %"),
        ("outside_flagged_rate", ">= 90 %"),
        ("explained_true_above_1.3", "== 0"),
    ):
        v = acc[key]
        vs = "-" if v is None else (fmt_rate(v) if "rate" in key else str(v))
        met = {True: "met", False: "NOT MET", None: "-"}[ok[key]]
        print(f"  {key:26s} {vs:>6s}  (target {tgt})  {met}")
    if summary["errors"]:
        print(f"\n{summary['errors']} set(s) raised an error (see the JSON)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0, help="study seed (default 0)")
    ap.add_argument("--sets", type=int, default=None, help="at most N sets, mixed across classes")
    ap.add_argument(
        "--only",
        default=None,
        help="classes, comma separated (default: "
        + ",".join(rigzoo.BASE_CLASSES)
        + "; also "
        + ",".join(rigzoo.CONDITION_CLASSES)
        + ")",
    )
    ap.add_argument("--workers", type=int, default=None, help="diagnose's processes")
    ap.add_argument("--json", metavar="FILE", help="write every set's row and the summary")
    ap.add_argument("--markdown", metavar="FILE", help="write the summary as Markdown")
    ap.add_argument("--keep", metavar="DIR", help="write the sets (and their truth) here")
    args = ap.parse_args(argv)
    # The rig-condition classes only when asked for: the default study is the
    # original classes' (the same sets and output as before they existed).
    only = set(rigzoo.BASE_CLASSES)
    if args.only:
        only = {c.strip() for c in args.only.split(",") if c.strip()}
        bad = only - set(rigzoo.CLASSES)
        if bad:
            ap.error(f"unknown class(es) {sorted(bad)}; known: {', '.join(rigzoo.CLASSES)}")
    specs = pick(rigzoo.draw_study(args.seed), only, args.sets)
    tmp = None
    if args.keep:
        root = Path(args.keep)
        root.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="study_diagnose_")
        root = Path(tmp.name)
    rows = []
    t_all = time.perf_counter()
    try:
        bar = tqdm(specs, unit="set", file=sys.stderr)
        for spec in bar:
            bar.set_description(spec.set_id[:30])
            try:
                row = run_one(spec, root, args.workers)
            except Exception as e:  # a set that fails is reported, not fatal
                row = {
                    "set": spec.to_json(),
                    "outcome": "error",
                    "error": f"{type(e).__name__}: {e}",
                    "traceback": traceback.format_exc(),
                    "generate_s": math.nan,
                    "diagnose_s": math.nan,
                }
                tqdm.write(f"{spec.set_id:48s} {spec.label:11s} ERROR {row['error'][:200]}")
                rows.append(row)
                continue
            rows.append(row)
            tqdm.write(line(row))
            if not args.keep:
                shutil.rmtree(root / spec.set_id, ignore_errors=True)
    finally:
        if tmp is not None:
            tmp.cleanup()
    summary = summarise(rows)
    summary["total_wall_s"] = time.perf_counter() - t_all
    print_summary(summary)
    if args.json:
        Path(args.json).write_text(
            json.dumps({"seed": args.seed, "summary": summary, "sets": rows}, indent=2, default=str)
            + "\n"
        )
    if args.markdown:
        Path(args.markdown).write_text(markdown(summary, rows, args))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
