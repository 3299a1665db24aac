"""The set-up of a local cluster's worker processes (a Dask preload).

Ctrl-C in a terminal reaches every process of the foreground group: the
campaign's own process stops the campaign, writes the finished runs and closes
the cluster, so its workers ignore the signal instead of each printing a
traceback.

Closing the cluster closes its scheduler, and a worker whose heartbeat is in
flight at that moment logs the broken connection with a full traceback
(``distributed.worker``, level ERROR). The scheduler of a local cluster lives
in the campaign's own process and goes away only when the campaign closes it,
so that record says nothing to the user: the workers drop it.
"""

from __future__ import annotations

import logging
import signal

__all__ = ["dask_setup"]

#: The message ``distributed.worker`` logs when a heartbeat finds no scheduler.
HEARTBEAT_LOST = "Failed to communicate with scheduler during heartbeat"


class _SchedulerClosed(logging.Filter):
    """Drops the worker's record of a heartbeat that found the scheduler gone."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith(HEARTBEAT_LOST)


def dask_setup(worker) -> None:
    """Called by Dask in each worker process when it starts."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    log = logging.getLogger("distributed.worker")
    if not any(isinstance(f, _SchedulerClosed) for f in log.filters):
        log.addFilter(_SchedulerClosed())
