"""One progress protocol for long work: sampling, reports, simulation-based calibration.

A progress callback is any callable taking one :class:`ProgressEvent`; the
library calls it as work advances and never prints.  The command line passes
:class:`StderrProgress`; a notebook may pass ``print`` or its own widget.

Events with a count (``done``/``total``: sampler steps, replicates) arrive
often; events without one mark a stage (``"drawing corner.png"``).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

#: least time between two printed lines of the same counted task, s
MIN_INTERVAL_S = 10.0


@dataclass(frozen=True)
class ProgressEvent:
    """One step of a long task.

    ``task`` names the work (``"sampling [linear]"``, ``"sbc [linear, emcee]"``, ``"report"``);
    ``message`` says where it stands in one line (the time taken included); ``done``/``total``
    count its units (steps, replicates) when it has them; ``elapsed`` is seconds since the task started.
    """

    task: str
    message: str
    done: int | None = None
    total: int | None = None
    elapsed: float = 0.0

    def __str__(self) -> str:
        return f"{self.task}: {self.message}"


#: what every ``progress=`` parameter of the package accepts
Progress = Callable[[ProgressEvent], None]


def emit(progress: Progress | None, event: ProgressEvent) -> None:
    """Call ``progress`` with ``event`` unless it is None."""
    if progress is not None:
        progress(event)


class StderrProgress:
    """Print events on stderr, a counted task at most every :data:`MIN_INTERVAL_S` s (its first and last always)."""

    def __init__(self, stream=None, min_interval: float = MIN_INTERVAL_S):
        self.stream = stream
        self.min_interval = min_interval
        self._last: dict[str, float] = {}

    def __call__(self, event: ProgressEvent) -> None:
        now = time.perf_counter()
        if event.done is not None:
            last = self._last.get(event.task)
            final = event.total is not None and event.done >= event.total
            if last is not None and not final and now - last < self.min_interval:
                return
            self._last[event.task] = now
        print(event, file=self.stream or sys.stderr, flush=True)
