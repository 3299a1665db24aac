"""Benchmark: reading long runs, the pyarrow path against the Python path.

Writes valid ``hybridtable-run/1`` runs of 1e4, 1e5 and 1e6 rows (a periodic,
contact-free signal at 1 kHz: the spacecraft model swinging 5 mm at 0.5 Hz
short of the table, the table following with a lag and 2 um of noise, the
force sensor reading 0.5 N of noise below its deadband; cells written with
``%.9g``), then times :func:`~hybridtable.measurement.run_reader.read_run` on
each in a fresh Python process per measurement, once with the reader as it is
(pyarrow, :mod:`hybridtable.measurement.csv_fast`) and once forced onto its
line-precise Python path, and reports the ratio.

Each process imports the reader, numpy and pyarrow, notes its peak resident
memory (``ru_maxrss``), reads the run and notes the peak again: "total" is the
process's peak, "above imports" the growth during the read, the reader's own
memory, which the targets apply to (1e6 rows in at most 2 s and 300 MB).
MB are 2**20 bytes. The time is the median of ``--repeat`` processes, the
memory their largest.

Usage: python benchmarks/bench_read.py [--out-dir DIR] [--json FILE]
       [--repeat N] [--rows 1e4,1e5,1e6]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

#: Largest row count the targets apply to, and the targets.
TARGET_ROWS = 1_000_000
TARGET_TIME_S = 2.0
TARGET_MEMORY_MB = 300.0

SAMPLE_RATE_HZ = 1000.0
EXAMPLE_JSON = Path(__file__).resolve().parents[1] / "examples" / "nominal" / "run1.json"

#: The measuring process: argv = csv path, "fast" or "python"; prints one JSON line.
_MEASURE = """
import json, resource, sys, time
import numpy, pyarrow, pyarrow.csv
from hybridtable.measurement import run_reader
kib0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
run_reader._FAST_CSV = sys.argv[2] == "fast"
t0 = time.perf_counter()
run = run_reader.read_run(sys.argv[1])
wall_s = time.perf_counter() - t0
kib1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"rows": run.n, "time_s": wall_s, "imports_kib": kib0, "peak_kib": kib1}))
"""


def write_run(folder: Path, rows: int) -> Path:
    """A valid run of ``rows`` ticks in ``folder`` (CSV and JSON); its CSV path."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"bench_{rows:d}"
    rng = np.random.default_rng(rows)
    t_s = np.arange(rows) / SAMPLE_RATE_HZ
    w_rad_per_s = 2 * np.pi * 0.5
    amplitude_m, gap_m, lag_s = 0.005, 0.02, 0.008
    p_des_m = -gap_m + amplitude_m * np.sin(w_rad_per_s * t_s)
    v_des_m_per_s = amplitude_m * w_rad_per_s * np.cos(w_rad_per_s * t_s)
    p_act_m = -gap_m + amplitude_m * np.sin(w_rad_per_s * (t_s - lag_s))
    p_act_m += rng.normal(0.0, 2e-6, rows)
    f_mea_n = rng.normal(0.0, 0.5, rows)
    f_comp_n = np.zeros(rows)
    table = np.column_stack([t_s, p_des_m, p_act_m, f_mea_n, f_comp_n, v_des_m_per_s])
    csv_path = folder / f"{stem}.csv"
    with open(csv_path, "w", encoding="utf-8", newline="\n") as f:
        f.write("time_s,p_des_m,p_act_m,f_mea_n,f_comp_n,v_des_m_per_s\n")
        np.savetxt(f, table, fmt="%.9g", delimiter=",")
    info = json.loads(EXAMPLE_JSON.read_text(encoding="utf-8"))
    info.update(
        run_id=f"bench-{rows:d}",
        sample_rate_hz=SAMPLE_RATE_HZ,
        initial_gap_m=gap_m,
        initial_velocity_m_per_s=float(v_des_m_per_s[0]),
    )
    (folder / f"{stem}.json").write_text(json.dumps(info, indent=2) + "\n", encoding="utf-8")
    return csv_path


def measure(csv_path: Path, path: str) -> dict:
    """One read of ``csv_path`` in a fresh process (``path``: "fast" or "python")."""
    out = subprocess.run(
        [sys.executable, "-c", _MEASURE, str(csv_path), path],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _summary(samples: list[dict]) -> dict:
    imports_mb = max(s["imports_kib"] for s in samples) / 1024
    return {
        "time_s": statistics.median(s["time_s"] for s in samples),
        "peak_mb": max(s["peak_kib"] for s in samples) / 1024,
        "above_imports_mb": max((s["peak_kib"] - s["imports_kib"]) for s in samples) / 1024,
        "imports_mb": imports_mb,
    }


def _count(rows: int) -> str:
    """``rows`` as a power of ten where it is one ("1e6"), else in digits."""
    text = f"{rows:.0e}".replace("e+0", "e").replace("e+", "e")
    return text if float(text) == rows else f"{rows:d}"


def _rows_list(text: str) -> list[int]:
    return [int(float(x)) for x in text.split(",") if x.strip()]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out-dir", type=Path, help="keep the runs here (default: a temp folder)")
    ap.add_argument("--json", type=Path, help="write the results to this JSON file")
    ap.add_argument("--repeat", type=int, default=3, help="processes per measurement")
    ap.add_argument("--rows", type=_rows_list, default=[10_000, 100_000, 1_000_000])
    args = ap.parse_args()
    folder = args.out_dir or Path(tempfile.mkdtemp(prefix="bench_read_"))
    results = []
    try:
        for rows in args.rows:
            print(f"writing {_count(rows)} rows ...", file=sys.stderr)
            csv_path = write_run(folder, rows)
            entry = {"rows": rows, "file_mb": csv_path.stat().st_size / 2**20}
            for path in ("fast", "python"):
                print(f"reading {_count(rows)} rows, {path} path ...", file=sys.stderr)
                samples = [measure(csv_path, path) for _ in range(args.repeat)]
                assert all(s["rows"] == rows for s in samples)
                entry[path] = _summary(samples)
            entry["speed_up"] = entry["python"]["time_s"] / entry["fast"]["time_s"]
            entry["memory_ratio"] = (
                entry["python"]["above_imports_mb"] / entry["fast"]["above_imports_mb"]
            )
            results.append(entry)
    finally:
        if args.out_dir is None:
            shutil.rmtree(folder, ignore_errors=True)

    big = max(results, key=lambda e: e["rows"])
    fast = big["fast"]
    verdict = (
        f"Reads {_count(big['rows'])} rows in {fast['time_s']:.2f} s using "
        f"{fast['above_imports_mb']:.0f} MB above imports "
        f"(targets {TARGET_TIME_S:g} s, {TARGET_MEMORY_MB:g} MB)"
    )
    missed = []
    if big["rows"] >= TARGET_ROWS and fast["time_s"] > TARGET_TIME_S:
        missed.append("time")
    if big["rows"] >= TARGET_ROWS and fast["above_imports_mb"] > TARGET_MEMORY_MB:
        missed.append("memory")
    print(verdict + (f"; misses the {' and '.join(missed)} target" if missed else ""))
    print(
        "The targets apply to the reader's own memory (above imports); "
        f"imports take {fast['imports_mb']:.0f} MB."
    )
    print()
    head = (
        f"{'rows':>9} {'file [MB]':>9} {'pyarrow [s]':>11} {'Python [s]':>10} "
        f"{'speed-up [1]':>12} {'pyarrow [MB]':>12} {'Python [MB]':>11} {'ratio [1]':>9} "
        f"{'pyarrow total [MB]':>18} {'Python total [MB]':>17}"
    )
    print(head)
    for e in results:
        f, p = e["fast"], e["python"]
        print(
            f"{e['rows']:>9d} {e['file_mb']:>9.1f} {f['time_s']:>11.3f} {p['time_s']:>10.3f} "
            f"{e['speed_up']:>12.1f} {f['above_imports_mb']:>12.0f} {p['above_imports_mb']:>11.0f} "
            f"{e['memory_ratio']:>9.1f} {f['peak_mb']:>18.0f} {p['peak_mb']:>17.0f}"
        )
    print(
        "\n[MB] columns without 'total': peak memory above imports; time: median of "
        f"{args.repeat} fresh processes."
    )
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"verdict": verdict, "results": results}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
