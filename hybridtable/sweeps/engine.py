"""Run a campaign on Dask distributed: a local cluster or an existing one.

The runs are cut into tasks of a few runs each and submitted to a
``distributed.Client``: a ``LocalCluster`` of worker processes (one thread
each; as many as the machine has cores, or ``workers``) or the scheduler at
``scheduler`` (``dask scheduler`` and ``dask worker`` started by the user, on
one machine or many; every worker needs hybridtable installed). Rows come back
in any order; the file is written sorted by run, so it does not depend on the
backend, the number of workers or the order of completion.

Faults:

- a run that diverges or raises is a row with its status (:mod:`.runner`);
- a worker lost mid-campaign costs only its tasks, which the scheduler runs
  again elsewhere; a task that kills every worker it lands on
  (``KilledWorker``) is retried run by run, and a run that still kills its
  worker is recorded as ``error``;
- the file is rewritten (atomically) every few seconds, so a campaign killed
  even with SIGKILL leaves a valid Parquet file of its finished runs, and
  ``resume=True`` runs only the missing ones;
- Ctrl-C stops the campaign, writes the finished runs and returns
  (``interrupted``).
"""

from __future__ import annotations

import logging
import math
import os
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hybridtable._files import keep_output
from hybridtable.errors import CommandError
from hybridtable.sweeps.plan import SweepSpec
from hybridtable.sweeps.runner import blank_row, row_problem, run_many
from hybridtable.sweeps.store import read_results, write_results

__all__ = [
    "CampaignResult",
    "run_campaign",
    "open_client",
    "default_workers",
    "task_size",
    "TASK_S",
]

#: Seconds between two writes of the file (at least; a slow write waits longer).
CHECKPOINT_S = 2.0


@dataclass
class CampaignResult:
    """What :func:`run_campaign` did.

    Attributes
    ----------
    path : Path
        The Parquet file.
    n_runs : int
        Runs in the spec.
    written : int
        Rows in the file now.
    resumed : int
        Rows that were already in the file (``resume``).
    interrupted : bool
        Stopped by Ctrl-C before every run finished.
    workers : int
        Dask workers at the start.
    scheduler : str
        The scheduler's address.
    dashboard : str or None
        The Dask dashboard's address.
    wall_time_s : float
    run_seconds : float
        The runs' own time, summed.
    compute_time_s : float
        From the first task submitted to the last result (no cluster start-up).
    retried : list of int
        Runs retried alone after their task killed its workers.
    rerun : list of (run, why)
        Rows of the file that ``resume`` did not keep, and why
        (:func:`~hybridtable.sweeps.runner.row_problem`): those runs ran again.
    rows : list of dict
        The rows, sorted by run.
    """

    path: Path | None
    n_runs: int
    written: int = 0
    resumed: int = 0
    interrupted: bool = False
    workers: int = 0
    scheduler: str = ""
    dashboard: str | None = None
    wall_time_s: float = 0.0
    run_seconds: float = 0.0
    compute_time_s: float = 0.0
    retried: list[int] = field(default_factory=list)
    rerun: list[tuple[Any, str]] = field(default_factory=list)
    rows: list[dict[str, Any]] = field(default_factory=list, repr=False)

    @property
    def complete(self) -> bool:
        return self.written == self.n_runs


def default_workers() -> int:
    """Worker processes of a local cluster: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


#: Seconds of runs one task aims at: the scheduler's few milliseconds per task
#: stay small beside it, the progress bar moves, a lost worker costs little.
TASK_S = 0.5


def task_size(n_todo: int, workers: int, seconds_per_run: float | None = None) -> int:
    """Runs per task: about :data:`TASK_S` of work (one run while the time of a
    run is not known yet), and at least four tasks per worker for the runs
    left, so that no worker waits long on the last one; at most 256."""
    if seconds_per_run is None:
        return 1
    by_time = int(TASK_S / max(seconds_per_run, 1e-6))
    by_balance = math.ceil(n_todo / (4 * max(workers, 1)))
    return max(1, min(256, by_time, by_balance))


def _quiet_dask() -> None:
    for name in ("distributed", "bokeh", "tornado"):
        logging.getLogger(name).setLevel(logging.ERROR)


def _refused(scheduler: str) -> None:
    """Fail at once when nothing listens at a TCP ``scheduler``.

    Dask's client retries a refused connection until its timeout (20 s); a
    closed port (a typo, a scheduler not started) is known after one try. A
    port that does not answer at all (a firewall) is still left to the client.
    """
    import socket

    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        protocol, location = parse_address(scheduler)
        host, port = parse_host_port(location)
    except (TypeError, ValueError):
        return  # not host:port; the client says what is wrong with it
    if protocol != "tcp":
        return
    try:
        socket.create_connection((host, port), timeout=5.0).close()
    except ConnectionRefusedError:
        raise CommandError(
            f"--scheduler {scheduler}: no Dask scheduler answers there (connection refused)"
        ) from None
    except OSError:
        return  # unreachable or slow: the client's own timeout decides


def open_client(scheduler: str | None, workers: int | None):
    """A Dask client and its local cluster (None with ``scheduler``).

    Parameters
    ----------
    scheduler : str or None
        Address of a running scheduler; None: start a ``LocalCluster`` of
        ``workers`` processes (default: the cores), one thread each, whose
        workers ignore Ctrl-C (:mod:`.worker_setup`).
    workers : int or None
        With ``scheduler``: wait until this many workers have joined.

    Raises
    ------
    CommandError
        No scheduler answers at ``scheduler``, or too few workers join in 60 s.
    """
    from distributed import Client, LocalCluster

    _quiet_dask()
    if scheduler:
        _refused(scheduler)
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as err:
            raise CommandError(
                f"--scheduler {scheduler}: no Dask scheduler answers there ({err})"
            ) from None
        if workers is not None:
            # Wait for the workers the user says are there (a cluster starting up).
            try:
                client.wait_for_workers(workers, timeout=60)
            except TimeoutError:
                client.close()
                raise CommandError(
                    f"--scheduler {scheduler}: fewer than {workers} workers after 60 s"
                ) from None
        return client, None
    import warnings

    with warnings.catch_warnings():
        # Port 8787 taken (another cluster): Dask picks another; we print it.
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        cluster = LocalCluster(
            n_workers=workers or default_workers(),
            threads_per_worker=1,
            processes=True,
            silence_logs=logging.ERROR,
            preload=["hybridtable.sweeps.worker_setup"],
        )
    return Client(cluster), cluster


def run_campaign(
    spec: SweepSpec,
    out: str | Path | None,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    progress: bool = True,
    on_start=None,
    client=None,
    in_process: bool = False,
) -> CampaignResult:
    """Run every run of ``spec`` not yet in ``out`` and write ``out``.

    Parameters
    ----------
    spec : SweepSpec
    out : path or None
        The Parquet file (replaced unless ``resume``); None: the rows are only
        returned (a study that post-processes them).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); default: a
        local cluster.
    workers : int, optional
        Local cluster: its worker processes (default: the cores). Existing
        scheduler: wait until this many workers have joined.
    resume : bool
        Keep the runs ``out`` already holds (it must be this spec's) and run
        the others.
    progress : bool
        A progress bar on stderr (runs done, runs per second, ETA).
    on_start : callable, optional
        Called with the :class:`CampaignResult` once the cluster is up (the
        command prints the dashboard's address there).
    client : distributed.Client, optional
        Run on this client (left open) instead of starting one from
        ``scheduler`` and ``workers``.
    in_process : bool
        Run here, one run after the other, without Dask: for campaigns that
        take less time than a cluster takes to start (the margins of a grid of
        linear models). The rows are the same.

    Raises
    ------
    ParameterError
        ``resume`` on a file of another spec.
    CommandError
        No scheduler at ``scheduler``, or the workers cannot run a task.
    """
    t0 = time.perf_counter()
    path = None if out is None else Path(out)
    result = CampaignResult(path, spec.n_runs)
    claimed = path is not None and not (resume and path.exists())
    if claimed:
        # Claim the file first, in one step: of two campaigns started at once
        # on one new --out, the second stops here instead of replacing the
        # first's rows later (WriteError). From here on the file is ours.
        write_results(path, spec, [])
        keep_output(path)  # its rows stay if the command fails later (--resume goes on)
    try:
        return _campaign(
            spec,
            path,
            resume,
            result,
            t0,
            in_process,
            client,
            scheduler,
            workers,
            on_start,
            progress,
        )
    except Exception:
        if claimed and result.written == 0:  # nothing run: leave no file behind
            path.unlink(missing_ok=True)
        raise


def _campaign(
    spec, path, resume, result, t0, in_process, client, scheduler, workers, on_start, progress
) -> CampaignResult:
    """:func:`run_campaign` once its file is claimed."""
    rows: dict[int, dict[str, Any]] = {}
    if resume and path is not None and path.exists():
        for row in read_results(path, spec).to_pylist():
            problem = row_problem(spec, row)
            if problem is None and row["run"] not in rows:
                rows[row["run"]] = row
            else:  # run again: what the file says of it cannot be trusted
                result.rerun.append((row.get("run"), problem or "the run is in the file twice"))
        result.resumed = len(rows)
    todo = [i for i in range(spec.n_runs) if i not in rows]
    if not todo:
        result.written = _write(path, spec, rows)[1]
        result.rows = [rows[i] for i in sorted(rows)]
        result.wall_time_s = time.perf_counter() - t0
        return result

    if in_process:
        _run(None, spec, path, todo, rows, result, progress)
        result.rows = [rows[i] for i in sorted(rows)]
        result.wall_time_s = time.perf_counter() - t0
        result.run_seconds = float(sum(r["seconds"] for r in rows.values()))
        return result
    own = client is None
    cluster = None
    if own:
        client, cluster = open_client(scheduler, workers)
    try:
        info = client.scheduler_info()
        result.workers = len(info.get("workers", {}))
        result.scheduler = str(info.get("address", scheduler or ""))
        result.dashboard = client.dashboard_link
        if on_start is not None:
            on_start(result)
        _run(client, spec, path, todo, rows, result, progress)
    finally:
        if own:
            client.close()
        if cluster is not None:
            cluster.close()
    result.rows = [rows[i] for i in sorted(rows)]
    result.wall_time_s = time.perf_counter() - t0
    result.run_seconds = float(sum(r["seconds"] for r in rows.values()))
    return result


def _run(client, spec, path, todo, rows, result, progress) -> None:
    """Run ``todo`` on ``client`` (None: here), collecting into ``rows`` and
    writing ``path`` every few seconds and at the end, even on Ctrl-C."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    bar = tqdm(
        total=spec.n_runs,
        initial=len(rows),
        desc=f"sweep {spec.name}",
        unit="run",
        disable=not progress,
        file=sys.stderr,
        leave=False,
    )
    last_write, write_cost = time.monotonic(), 0.0
    futures: dict[Any, list[int]] = {}
    try:
        for chunk, found in _results(client, spec, list(todo), futures, result):
            for row in found:
                rows[row["run"]] = row
            bar.update(len(chunk))
            now = time.monotonic()
            if now - last_write >= max(CHECKPOINT_S, 5.0 * write_cost):
                write_cost = _write(path, spec, rows)[0]
                last_write = time.monotonic()
    except KeyboardInterrupt:
        result.interrupted = True
        for f in futures:
            f.cancel()
    except BaseException:  # the workers cannot run the campaign: free the cluster
        for f in futures:
            f.cancel()
        raise
    finally:
        bar.close()
        result.compute_time_s = time.perf_counter() - t0
        result.written = len(rows)
        _write(path, spec, rows)


def _results(client, spec, todo, futures, result):
    """``(chunk, rows)`` as the tasks finish (here, in order, without a client).

    Tasks are cut as the campaign goes: one run each until the runs' time is
    known, then :func:`task_size` of the median run time so far, two tasks
    queued per worker. Rows do not depend on the cut."""
    from collections import deque

    pending = deque(todo)
    workers = max(result.workers, 1)
    seconds: list[float] = []

    def take() -> list[int]:
        # the median: a worker's first run also pays its imports
        typical = statistics.median(seconds) if seconds else None
        n = task_size(len(pending), workers, typical)
        return [pending.popleft() for _ in range(min(n, len(pending)))]

    if client is None:
        while pending:
            chunk = take()
            rows = run_many(spec, chunk)
            seconds.extend(r["seconds"] for r in rows)
            yield chunk, rows
        return
    from distributed import as_completed

    done = as_completed()
    while pending and len(futures) < 2 * workers:
        chunk = take()
        future = client.submit(run_many, spec, chunk, pure=False)
        futures[future] = chunk
        done.add(future)
    for future in done:
        chunk = futures.pop(future)
        rows = _rows_of(client, spec, future, chunk, result)
        seconds.extend(r["seconds"] for r in rows if math.isfinite(r["seconds"]))
        while pending and len(futures) < 2 * workers:
            nxt = take()
            f = client.submit(run_many, spec, nxt, pure=False)
            futures[f] = nxt
            done.add(f)
        yield chunk, rows


def _write(path, spec, rows) -> tuple[float, int]:
    """Write the rows (none without a path); return the seconds it took and
    the rows written."""
    t = time.monotonic()
    if path is not None:
        write_results(path, spec, rows.values(), replace=True)  # claimed: ours to rewrite
    return time.monotonic() - t, len(rows)


def _rows_of(client, spec, future, chunk, result) -> list[dict[str, Any]]:
    """The rows of a finished task; a task whose workers died is retried run
    by run."""
    from distributed import KilledWorker

    try:
        return future.result()
    except KilledWorker:
        pass
    except Exception as err:  # the workers cannot run our code at all
        raise CommandError(
            f"a Dask worker could not run the campaign ({type(err).__name__}: "
            f"{' '.join(str(err).split())[:300]}); is hybridtable installed on every worker?"
        ) from None
    out = []
    for index in chunk:
        result.retried.append(index)
        try:
            out += client.submit(run_many, spec, [index], pure=False).result()
        except KilledWorker:
            row = _lost_row(spec, index)
            out.append(row)
    return out


def _lost_row(spec: SweepSpec, index: int) -> dict[str, Any]:
    row = blank_row(spec, spec.run_inputs(index))
    row.update(
        status="error",
        message="the run killed every Dask worker it was given (a crash inside the simulation)",
        engine="",
        seconds=math.nan,
    )
    return row
