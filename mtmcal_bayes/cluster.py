"""Where batch work runs: a Dask cluster (``dask.distributed``), local by default or one already running.

Fleets of machines and long validations (``validate sbc``) are many independent tasks.  They go to a
:class:`distributed.Client`: by default a :class:`distributed.LocalCluster` of ``workers`` single-threaded
worker processes (one per core), or, with ``scheduler="tcp://host:8786"``, a cluster started elsewhere
(``dask scheduler`` and ``dask worker`` on one or many computers, each with this package installed).
Results never depend on where a task ran: every task is seeded from its own content.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator

from .errors import ParameterError

#: how long connecting to a scheduler may take before it counts as unreachable, s
CONNECT_TIMEOUT_S = 10
#: Dask settings of the local cluster's workers.  Dask starts them with ``MALLOC_TRIM_THRESHOLD_=65536``
#: (memory back to the system sooner), which makes glibc return and refetch memory so often that a replicate
#: of ``validate sbc`` (many small numpy arrays) takes twice as long; any fixed value also turns off glibc's
#: adaptive thresholds, so it is left unset (a value in the user's environment still wins).  The statistical
#: profiler (for a dashboard there is none of) samples the task's stack every 10 ms: 5-15 % of a replicate.
#: The workers ignore SIGINT: Ctrl-C reaches the whole process group, and the caller, not each worker (with a
#: traceback), decides what an interruption does; the workers end when the caller closes the cluster.
#: local workers are forked where the platform can (as the process pool before them did): a spawned worker imports
#: the caller's script again, so a script without an ``if __name__ == "__main__":`` guard would fail
LOCAL_WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
                       "distributed.worker.profile.enabled": False,
                       "distributed.worker.multiprocessing-method": "fork" if hasattr(os, "fork") else "spawn",
                       "distributed.worker.preload": ["import signal; signal.signal(signal.SIGINT, signal.SIG_IGN)"]}


def default_workers() -> int:
    """One worker process per core."""
    return os.cpu_count() or 1


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[object]:
    """A ``distributed.Client``: to ``scheduler`` (an address such as ``tcp://127.0.0.1:8786``, or the path of a
    scheduler file) when given, else to a new local cluster of ``workers`` processes (default: the core count),
    one thread each (the numerical work holds the GIL), closed on exit."""
    import dask
    from distributed import Client, LocalCluster

    if workers is not None and workers < 1:
        raise ParameterError("workers", f"{workers}: at least one worker is needed")
    if scheduler is not None:
        if scheduler.endswith(".json") and not os.path.isfile(scheduler):
            raise ParameterError("scheduler", f"{scheduler}: no such scheduler file")
        try:
            kw = {"scheduler_file": scheduler} if os.path.isfile(scheduler) else {"address": scheduler}
            client = Client(timeout=f"{CONNECT_TIMEOUT_S}s", **kw)
        except (OSError, TimeoutError, ValueError) as exc:
            raise ParameterError("scheduler", f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
        except Exception as exc:  # something answered, not a Dask scheduler (its reply read as a frame: MemoryError)
            raise ParameterError("scheduler", f"{scheduler!r} did not answer as a Dask scheduler "
                                 f"({type(exc).__name__})") from None
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or default_workers()
    # no dashboard; the scheduler's small HTTP server on a free local port, not 8787 (no warning when that is busy)
    with dask.config.set(LOCAL_WORKER_CONFIG), LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}, silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        yield client


class Interrupt:
    """Whether Ctrl-C (SIGINT) arrived while :func:`remembered_interrupt` was active."""

    def __init__(self) -> None:
        self.arrived = False

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C arrived (call it between results, and before writing them)."""
        if self.arrived:
            raise KeyboardInterrupt


@contextlib.contextmanager
def remembered_interrupt() -> Iterator[Interrupt]:
    """Ctrl-C while a cluster's results are collected: raised as ``KeyboardInterrupt`` where it arrives, as usual,
    and also remembered, so that :meth:`Interrupt.check` raises it again.

    Distributed runs callbacks in the caller's thread (its garbage-collector diagnostics) where an exception is
    reported as "ignored" and dropped: a Ctrl-C arriving there was lost, and the run went on to write its results
    as if never interrupted.  An interrupt dropped that way is not printed either (the run says "interrupted" once,
    when ``check`` raises it).  Outside the main thread, or where SIGINT is ignored, nothing changes."""
    interrupt = Interrupt()
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous in (signal.SIG_IGN, None):
        yield interrupt
        return

    def on_sigint(signum, frame):
        interrupt.arrived = True
        raise KeyboardInterrupt

    hook = sys.unraisablehook

    def unraisable(info):
        if not isinstance(info.exc_value, KeyboardInterrupt):
            hook(info)

    signal.signal(signal.SIGINT, on_sigint)
    sys.unraisablehook = unraisable
    try:
        yield interrupt
    finally:
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = hook
