"""Benchmark: a campaign's runs per second on one and on two Dask workers.

A Monte Carlo campaign of Table-1-like runs (the paper's four compensators,
sensor delay 1-10 ms, approach 0.05-0.2 m/s, the fast engine) runs on a
LocalCluster of one worker, then of two, in this one process. Each cluster is
warmed up first (imports, a short campaign), and only the campaign's compute
phase is timed (first task to last row, the Parquet writes included). Prints
the ms per run per worker, the runs per second and the ratio two/one workers
(targets: <= 20 ms per run, >= 1.8x), and, for scale, one run of the Drake
diagram and of the fast engine in this process.

With ``--six-dof`` the campaign is the shipped 6-DoF spec
(``examples/sweeps/docking_envelope.toml``: the docking loop on the offset
scenario, three compensators) cut to ``--samples`` draws (target: two workers
>= 1.7x one).

Usage: python benchmarks/bench_sweep.py [--samples N] [--six-dof] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import logging
import tempfile
import time
from pathlib import Path

SPEC = """
name = "bench"
seed = 1
engine = "{engine}"
compensators = ["none", "SDC", "MDC", "SDMDC"]
metrics = ["cor", "peak_force_n"]

[monte_carlo]
samples = {samples}
[monte_carlo.draw]
sensor_delay_s = {{distribution = "uniform", low = 0.001, high = 0.01}}
initial_velocity_m_per_s = {{distribution = "uniform", low = 0.05, high = 0.2}}
"""


ENVELOPE = Path(__file__).resolve().parents[1] / "examples" / "sweeps" / "docking_envelope.toml"


def _campaign(client, samples: int, engine: str, folder: Path) -> tuple[float, int]:
    import tomllib

    from hybridtable.sweeps.engine import run_campaign
    from hybridtable.sweeps.spec import parse_spec

    if engine == "six_dof":
        raw = tomllib.loads(ENVELOPE.read_text())
        raw["monte_carlo"]["samples"] = samples
        spec = parse_spec(raw, str(ENVELOPE), ENVELOPE.parent)
    else:
        spec = parse_spec(tomllib.loads(SPEC.format(samples=samples, engine=engine)))
    out = folder / f"bench-{time.monotonic_ns()}.parquet"
    result = run_campaign(spec, out, client=client, progress=False)
    return result.compute_time_s, result.written


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=500, help="draws (x4 compensators = runs)")
    ap.add_argument("--six-dof", action="store_true", help="the shipped 6-DoF campaign")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args()
    engine = "six_dof" if args.six_dof else "fast"
    target = 1.7 if args.six_dof else 1.8

    from distributed import Client, LocalCluster

    from hybridtable.loop.fast import simulate_fast
    from hybridtable.loop.simulation import simulate
    from hybridtable.studies.paper import table1_params

    p = table1_params("SDMDC")
    simulate_fast(p)
    t = time.perf_counter()
    for _ in range(5):
        simulate_fast(p)
    fast_ms = (time.perf_counter() - t) / 5 * 1e3
    t = time.perf_counter()
    simulate(p)
    diagram_ms = (time.perf_counter() - t) * 1e3
    print(f"one Table 1 run in this process: fast {fast_ms:.1f} ms, diagram {diagram_ms:.0f} ms")

    rates = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2):
            with (
                LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    silence_logs=logging.ERROR,
                    dashboard_address=":0",
                ) as cluster,
                Client(cluster) as client,
            ):
                _campaign(client, (1 if args.six_dof else 10) * n, engine, Path(tmp))  # warm-up
                seconds, runs = _campaign(client, args.samples, engine, Path(tmp))
            rates[n] = runs / seconds
            print(
                f"{n} worker{'s' if n > 1 else ''}: {runs} runs in {seconds:.2f} s, "
                f"{rates[n]:.0f} runs/s, {1e3 * n / rates[n]:.1f} ms per run per worker"
            )
    ratio = rates[2] / rates[1]
    print(
        f"two workers / one worker: {ratio:.2f}x runs per second (target >= {target:g}x); "
        f"{1e3 / rates[1]:.1f} ms per run on one worker"
        + ("" if args.six_dof else " (target <= 20 ms)")
    )
    if args.json:
        Path(args.json).write_text(
            json.dumps(
                {
                    "fast_ms_in_process": fast_ms,
                    "diagram_ms_in_process": diagram_ms,
                    "runs_per_s": {str(k): v for k, v in rates.items()},
                    "ms_per_run_one_worker": 1e3 / rates[1],
                    "speedup_two_workers": ratio,
                },
                indent=2,
            )
        )


if __name__ == "__main__":
    main()
