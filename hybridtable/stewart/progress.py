"""A progress bar over simulated time for the Stewart back-end's simulations.

A Stewart run is several simulations (the identifications that tune the
table, the chirp, the loop), each a few seconds of wall time. Inside
``with SimulatedTimeProgress():`` every simulation that adds a
:class:`ProgressTicker` to its diagram (:func:`add_progress_ticker`; the
identification's ``drive_table`` and :func:`~hybridtable.stewart.run.simulate_stewart`
do) shows a tqdm bar on stderr over its simulated seconds, removed when it
ends (``leave=False``). Outside such a block, :func:`add_progress_ticker`
adds nothing, so the simulations are unchanged.

The ticker is a per-step publish event: it adds no step and no state, so a
run with the bar gives the same numbers as one without.
"""

from __future__ import annotations

import sys
from contextvars import ContextVar
from typing import TextIO

from pydrake.systems.framework import DiagramBuilder, LeafSystem

__all__ = [
    "SimulatedTimeProgress",
    "ProgressTicker",
    "active_progress",
    "add_progress_ticker",
]

_ACTIVE: ContextVar[SimulatedTimeProgress | None] = ContextVar(
    "hybridtable_stewart_progress", default=None
)


class SimulatedTimeProgress:
    """Show a tqdm bar over simulated time for each simulation run inside the block.

    Parameters
    ----------
    file : text stream, optional
        Where the bars go (default: stderr).
    disable : bool or None
        ``None`` (default): no bar when ``file`` is not a terminal (tqdm's
        rule), so logs and pipes stay clean.
    min_interval_s : float
        Simulated time between two updates of a bar, s.
    """

    def __init__(
        self, file: TextIO | None = None, disable: bool | None = None, min_interval_s: float = 0.01
    ) -> None:
        self._file = file
        self._disable = disable
        self._min_interval_s = min_interval_s
        self._bar = None
        self._last_s = 0.0
        self._token = None
        #: Labels of the simulations shown, in order (for the tests and logs).
        self.stages: list[str] = []

    def __enter__(self) -> SimulatedTimeProgress:
        self._token = _ACTIVE.set(self)
        return self

    def __exit__(self, *exc) -> None:
        self._close()
        _ACTIVE.reset(self._token)

    def start(self, label: str, duration_s: float) -> None:
        """A new simulation of about ``duration_s`` simulated seconds begins."""
        from tqdm import tqdm

        self._close()
        self.stages.append(label)
        self._last_s = 0.0
        self._bar = tqdm(
            total=max(duration_s, 1e-9),
            desc=label,
            unit="s",
            leave=False,
            file=self._file if self._file is not None else sys.stderr,
            disable=self._disable,
            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} s simulated "
            "[{elapsed}<{remaining}]",
        )

    def at(self, time_s: float) -> None:
        """The current simulation has reached ``time_s`` (simulated, s)."""
        bar = self._bar
        if bar is None or time_s - self._last_s < self._min_interval_s:
            return
        if time_s > bar.total:
            bar.total = time_s
        bar.update(time_s - self._last_s)
        self._last_s = time_s

    def _close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def active_progress() -> SimulatedTimeProgress | None:
    """The :class:`SimulatedTimeProgress` of the enclosing block, if any."""
    return _ACTIVE.get()


class ProgressTicker(LeafSystem):
    """Reports the simulated time to a :class:`SimulatedTimeProgress` at every
    simulator step (a per-step publish event: no extra step, no state)."""

    def __init__(self, progress: SimulatedTimeProgress) -> None:
        LeafSystem.__init__(self)
        self._progress = progress
        self.DeclarePerStepPublishEvent(self._tick)

    def _tick(self, context) -> None:
        self._progress.at(context.get_time())


def add_progress_ticker(
    builder: DiagramBuilder, label: str, duration_s: float
) -> ProgressTicker | None:
    """Inside a :class:`SimulatedTimeProgress` block, start a bar ``label``
    over ``duration_s`` simulated seconds and add its ticker to ``builder``;
    outside one, do nothing (returns ``None``)."""
    progress = active_progress()
    if progress is None:
        return None
    progress.start(label, duration_s)
    ticker = builder.AddNamedSystem("progress", ProgressTicker(progress))
    return ticker
