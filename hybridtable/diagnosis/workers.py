"""Fitting jobs of a diagnosis in worker processes, with a progress bar.

The jobs of :func:`pool_map` read their shared inputs (the evaluator, the base
fit) from module state set before the call: forked workers inherit it, so no
Drake object is pickled.
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
) -> list[Any]:
    """``[func(j) for j in jobs]``, in ``workers`` forked processes when there
    are two or more of each; a progress bar on standard error if ``progress``."""
    if workers <= 1 or len(jobs) <= 1:
        iterator = jobs
        if progress:
            from tqdm import tqdm

            iterator = tqdm(jobs, desc=label, unit="fit", file=sys.stderr, leave=False)
        return [func(j) for j in iterator]
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("fork")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        results = pool.map(func, jobs)
        if progress:
            from tqdm import tqdm

            results = tqdm(
                results, total=len(jobs), desc=label, unit="fit", file=sys.stderr, leave=False
            )
        return list(results)
