"""Fitting jobs of a model selection (``diagnose``'s candidates, ``explain``'s
models) in forked worker processes, with a progress bar or a callback.

The jobs read their shared inputs (an evaluator, a base fit, the plug-in
effects registered in this process) from module state set before the call:
forked workers inherit it, so no Drake object is pickled.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["pool_map"]


def pool_map(
    func: Callable[[Any], Any],
    jobs: Sequence[Any],
    workers: int,
    progress: bool = False,
    label: str = "fit",
    on_done: Callable[[Any, Any], None] | None = None,
) -> list[Any]:
    """``[func(j) for j in jobs]``, in ``workers`` forked processes when there
    are two or more of each (and the platform forks); a progress bar on
    standard error if ``progress``; ``on_done(job, result)`` after each job,
    in order."""
    import multiprocessing as mp

    if workers <= 1 or len(jobs) <= 1 or "fork" not in mp.get_all_start_methods():
        results = (func(j) for j in jobs)
    else:
        from concurrent.futures import ProcessPoolExecutor

        pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("fork"))
        results = pool.map(func, jobs)
    if progress:
        from tqdm import tqdm

        results = tqdm(
            results, total=len(jobs), desc=label, unit="fit", file=sys.stderr, leave=False
        )
    out = []
    try:
        for job, result in zip(jobs, results, strict=True):
            out.append(result)
            if on_done is not None:
                on_done(job, result)
    finally:
        if workers > 1 and len(jobs) > 1 and "pool" in locals():
            pool.shutdown()
    return out
