"""The set-up of a local cluster's worker processes (a Dask preload).

Ctrl-C in a terminal reaches every process of the foreground group: the
campaign's own process stops the campaign, writes the finished runs and closes
the cluster, so its workers ignore the signal instead of each printing a
traceback.
"""

from __future__ import annotations

import signal

__all__ = ["dask_setup"]


def dask_setup(worker) -> None:
    """Called by Dask in each worker process when it starts."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
