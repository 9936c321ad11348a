"""Drawing a report's figures in forked processes while the report goes on computing.

Each figure is independent once what it shows exists, and drawing is most of a report's CPU time.  A job may
also compute a result instead of a figure (the report's plan, its weighing of the instruments' conflict), which
then runs beside the report's own work instead of after it.  A :class:`Drawing` takes the jobs in batches:
:meth:`Drawing.start` forks up to two processes for a batch and returns at once, so the figures of the main
posterior are drawn while the report compares the instruments; :meth:`Drawing.wait` waits for one batch,
:meth:`Drawing.cancel` ends one whose result is no longer wanted, :meth:`Drawing.finish` waits for every batch.
The jobs reach the workers through the fork (nothing is pickled but each job's small return value); the workers
take the jobs of their batch in turn from a shared counter and write their files into the report's temporary
directory, so a failure still leaves nothing half-written.  The processes are forked with :mod:`multiprocessing`'s
``Process`` and a pipe each — no helper thread runs in the report's process, so a later batch forks a
process without threads.  Where the platform does not fork, a batch is drawn at once, in order.
"""

from __future__ import annotations

import gc
import multiprocessing
import os
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import StepFailure
from ..figure_style import save_png, warm_up

#: processes drawing one batch
WORKERS = 2


def _run(job: tuple[str, Callable], directory: Path):
    """Run one job: ``make()`` returns a Figure (saved as PNG under the job's name), ``(Figure, extra)``,
    ``(None, extra)`` (a result computed beside the figures, no file), or None (the job wrote its own file);
    returns the extra (or None)."""
    name, make = job
    made = make()
    if made is None:
        return None
    fig, extra = made if isinstance(made, tuple) else (made, None)
    if fig is not None:
        save_png(fig, directory / name)
    return extra


def _work(jobs, directory: Path, counter, conn) -> None:
    """A worker: take the batch's next job from ``counter`` until none is left; send ``{name: extra}`` (or the
    exception that stopped it) through ``conn``."""
    gc.disable()  # a short-lived process: no cyclic collection (it would walk every object inherited from the report)
    out = {}
    name = None
    try:
        while True:
            with counter.get_lock():
                i = counter.value
                counter.value += 1
            if i >= len(jobs):
                break
            name = jobs[i][0]
            out[name] = _run(jobs[i], directory)
        conn.send(("ok", out))
    except BaseException as exc:  # noqa: BLE001 - every failure goes back to the report, which raises it
        sent = StepFailure.of(_step(name), exc) if isinstance(exc, Exception) else exc
        try:
            conn.send(("error", sent))
        except Exception as unsent:  # noqa: BLE001 - an exception that cannot be pickled: its text
            conn.send(("error", StepFailure(_step(name), type(sent).__name__, f"{sent} (not sent: {unsent})")))
    finally:
        conn.close()


def _step(name: str | None) -> str:
    """What a drawing process was doing when it stopped: its job's file name, or the job's name."""
    if name is None:
        return "a drawing process"
    return f"drawing {name}" if "." in name else f"the report's {name} (beside the sampling)"


class Drawing:
    """The figures of one report, drawn in batches into ``directory`` (module docstring)."""

    def __init__(self, directory: Path, workers: int = WORKERS):
        self.directory = Path(directory)
        self.workers = min(workers, os.cpu_count() or 1)
        self.fork = self.workers > 1 and "fork" in multiprocessing.get_all_start_methods()
        self.names: list[str] = []
        self._running: list[tuple[object, object, int]] = []  # (process, receiving end, batch)
        self._batches = 0
        self._jobs_of: dict[int, list[str]] = {}
        self._extras: dict[str, object] = {}
        self._errors: list[BaseException] = []
        self._counters: list = []
        self._warm = False
        self._frozen = False

    def start(self, jobs: list[tuple[str, Callable]], workers: int | None = None) -> int:
        """Begin drawing ``jobs`` (``(file name, make)``) in up to ``workers`` processes (default the drawing's) and
        return the batch's number (for :meth:`wait` and :meth:`cancel`); without fork, draw them now."""
        jobs = list(jobs)
        batch = self._batches
        self._batches += 1
        self.names += [name for name, _ in jobs]
        self._jobs_of[batch] = [name for name, _ in jobs]
        if not jobs:
            return batch
        if not self.fork:  # drawn here, failing as a drawing process would (the same error, the same step named)
            for name, make in jobs:
                try:
                    self._extras[name] = _run((name, make), self.directory)
                except Exception as exc:  # noqa: BLE001 - what a drawing process would have sent back
                    raise StepFailure.of(_step(name), exc) from exc
            return batch
        ctx = multiprocessing.get_context("fork")
        if not self._warm:  # once, here: every process forked from now on inherits it
            warm_up()
            self._warm = True
        for stream in (sys.stdout, sys.stderr):  # what is buffered now would otherwise be written by each child too
            stream.flush()
        # every object the report holds now out of the cyclic collector's sight until the drawing stops: the
        # report's own collections then skip them (0.4 s of a 7 s report), and the children, which collect
        # nothing, copy fewer pages; :meth:`stop` gives them back to the collector
        gc.freeze()
        self._frozen = True
        counter = ctx.Value("i", 0)
        # kept until the drawing ends: a counter freed while its batch still runs could be handed to the next batch
        # (the shared memory is reused), and two batches would then take jobs from one counter
        self._counters.append(counter)
        for _ in range(min(self.workers if workers is None else workers, len(jobs))):
            receive, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_work, args=(jobs, self.directory, counter, send), daemon=True)
            proc.start()
            send.close()
            self._running.append((proc, receive, batch))
        return batch

    def _take(self, batch: int | None) -> list[tuple[object, object, int]]:
        """The running processes of ``batch`` (None: of every batch), no longer the drawing's to track."""
        taken, kept = [], []
        for run in self._running:
            (taken if batch is None or run[2] == batch else kept).append(run)
        self._running = kept
        return taken

    @staticmethod
    def _end(proc, receive) -> None:
        """Stop one drawing process without its answer."""
        proc.terminate()
        proc.join()
        receive.close()

    def _collect(self, proc, receive, batch: int, block: bool) -> bool:
        """Take the answer of one drawing process (waiting for it when ``block``); False when it has none yet."""
        if not block and not receive.poll():
            return False
        try:
            status, value = receive.recv()
        except EOFError:
            proc.join()
            status, value = "error", StepFailure(f"a drawing process ({', '.join(self._jobs_of.get(batch, ()))})",
                                                 "EOFError", f"ended without an answer (exit status {proc.exitcode})")
        proc.join()
        receive.close()
        if status == "ok":
            self._extras.update(value)
        else:
            self._errors.append(value)
        return True

    def check(self) -> None:
        """Raise the exception of a job that has already failed (without waiting for the others): the report
        stops there instead of computing on for a page it cannot write."""
        self._running = [(p, r, b) for p, r, b in self._running if not self._collect(p, r, b, block=False)]
        if self._errors:
            raise self._errors[0]

    def wait(self, batch: int) -> dict[str, object]:
        """Wait for one batch (the others go on); returns the extras of every job ended so far, by file name.  A
        job's exception is raised here."""
        for proc, receive, b in self._take(batch):
            self._collect(proc, receive, b, block=True)
        if self._errors:
            raise self._errors[0]
        return dict(self._extras)

    def cancel(self, batch: int | None) -> None:
        """End a batch whose results are no longer wanted (work begun before it was known to be needed); its jobs
        are no longer the drawing's and it leaves no extras.  None: nothing to end."""
        if batch is None:
            return
        for proc, receive, _ in self._take(batch):
            self._end(proc, receive)
        for name in self._jobs_of.pop(batch, ()):
            self._extras.pop(name, None)
            self.names.remove(name)

    def finish(self) -> dict[str, object]:
        """Wait for every batch; returns each job's extra by file name.  A job's exception is raised here."""
        for proc, receive, b in self._take(None):
            self._collect(proc, receive, b, block=True)
        self._counters = []
        if self._errors:
            raise self._errors[0]
        return dict(self._extras)

    def stop(self) -> None:
        """End the drawing processes still running (the report failed elsewhere), and give the objects frozen at the
        forks back to the cyclic collector.  Always called, last."""
        for proc, receive, _ in self._take(None):
            self._end(proc, receive)
        self._counters = []
        if self._frozen:
            gc.unfreeze()
            self._frozen = False


def draw_figures(jobs: list[tuple[str, Callable]], directory: Path) -> dict[str, object]:
    """Draw every ``(file name, make)`` job into ``directory`` and wait; returns each job's extra by file name."""
    drawing = Drawing(directory)
    try:
        drawing.start(jobs)
        return drawing.finish()
    finally:
        drawing.stop()
