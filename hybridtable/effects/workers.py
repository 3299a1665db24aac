"""Fitting jobs of a model selection (``diagnose``'s candidates, ``explain``'s
models) in forked worker processes, with a progress bar or a callback.

Every job gets the call's ``shared`` inputs (an evaluator, a base fit, the
effects of a table): they are held in this module while the pool runs, and
forked workers inherit them, so nothing of them (no Drake object) is pickled;
the plug-in effects registered in this process are inherited the same way.
Each worker's BLAS runs one thread (:func:`one_thread`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["DEFAULT_WORKERS", "one_thread", "pool_map", "worker_count"]


#: Processes a fit uses when the user names none (at most the CPUs).
DEFAULT_WORKERS = 2


def worker_count(workers: int | None) -> int:
    """``workers``, or :data:`DEFAULT_WORKERS` capped at the CPUs when None."""
    import os

    return workers if workers is not None else min(DEFAULT_WORKERS, os.cpu_count() or 1)


#: The ``shared`` inputs of the running :func:`pool_map` calls (innermost last).
_SHARED: list[Any] = []


def one_thread() -> None:
    """Limit this process's BLAS to one thread. The fits multiply matrices of a
    few rows; each worker is already one of the CPUs, and BLAS threads on top of
    them spin against each other (Table 1 on two cores: 73 s with two BLAS
    threads a worker, 12 s with one)."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def _call(item: tuple[Callable[[Any, Any], Any], Any]) -> Any:
    func, job = item
    return func(_SHARED[-1], job)


def pool_map(
    func: Callable[[Any, Any], Any],
    jobs: Sequence[Any],
    workers: int,
    progress: bool = False,
    label: str = "fit",
    on_done: Callable[[Any, Any], None] | None = None,
    shared: Any = None,
) -> list[Any]:
    """``[func(shared, j) for j in jobs]``, in ``workers`` forked processes when
    there are two or more of each (and the platform forks); ``func`` is a
    module-level function; a progress bar on standard error if ``progress``;
    ``on_done(job, result)`` after each job, in order."""
    import multiprocessing as mp

    forked = workers > 1 and len(jobs) > 1 and "fork" in mp.get_all_start_methods()
    pool = limits = None
    _SHARED.append(shared)
    try:
        if forked:
            from concurrent.futures import ProcessPoolExecutor

            pool = ProcessPoolExecutor(
                max_workers=workers, mp_context=mp.get_context("fork"), initializer=one_thread
            )
            results = pool.map(_call, [(func, j) for j in jobs])
        else:  # here, with one BLAS thread while the jobs run
            from threadpoolctl import threadpool_limits

            limits = threadpool_limits(1)
            results = (func(shared, j) for j in jobs)
        if progress:
            from tqdm import tqdm

            results = tqdm(
                results, total=len(jobs), desc=label, unit="fit", file=sys.stderr, leave=False
            )
        out = []
        for job, result in zip(jobs, results, strict=True):
            out.append(result)
            if on_done is not None:
                on_done(job, result)
        return out
    finally:
        _SHARED.pop()
        if pool is not None:
            pool.shutdown()
        if limits is not None:
            limits.restore_original_limits()
