"""The local cluster's workers: quiet on Ctrl-C and when their scheduler closes."""

from __future__ import annotations

import inspect
import logging
import signal

import distributed.worker

from hybridtable.sweeps import worker_setup


def test_the_heartbeat_record_dropped_is_the_one_distributed_writes():
    # If Dask rewords it, the filter would silently stop working: fail here instead.
    assert worker_setup.HEARTBEAT_LOST in inspect.getsource(distributed.worker.Worker.heartbeat)


def test_a_worker_drops_the_lost_heartbeat_and_keeps_every_other_record():
    log = logging.getLogger("distributed.worker")
    before_filters, before_sigint = list(log.filters), signal.getsignal(signal.SIGINT)
    try:
        worker_setup.dask_setup(None)
        worker_setup.dask_setup(None)  # a second preload adds no second filter
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        added = [f for f in log.filters if f not in before_filters]
        assert len(added) == 1

        def record(msg: str) -> logging.LogRecord:
            return log.makeRecord(log.name, logging.ERROR, __file__, 1, msg, (), None)

        lost = record("Failed to communicate with scheduler during heartbeat.")
        assert not log.filter(lost)
        assert log.filter(record("Compute Failed"))
        assert log.filter(record("Unexpected exception during heartbeat. Closing worker."))
    finally:
        log.filters[:] = before_filters
        signal.signal(signal.SIGINT, before_sigint)
