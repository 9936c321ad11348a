"""Drawing a report's figures: in two forked processes where the platform forks, else one after another.

Each figure is independent once the posterior exists, and drawing is most of a
report's time; two processes halve it on a two-core machine.  The jobs reach the
workers through the fork (nothing is pickled but an index); each worker writes its
PNG into the report's temporary directory, so a failure still leaves nothing
half-written.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from ..figure_style import save_png

#: the jobs of the drawing in progress, inherited by the forked workers
_JOBS: list[tuple[str, Callable]] = []


def _draw(index: int, directory: Path):
    """Draw job ``index`` and save it; returns what the job returned beside its figure (or None)."""
    name, make = _JOBS[index]
    made = make()
    fig, extra = made if isinstance(made, tuple) else (made, None)
    save_png(fig, directory / name)
    return extra


def draw_figures(jobs: list[tuple[str, Callable]], directory: Path) -> dict[str, object]:
    """Draw every ``(file name, make)`` job into ``directory``; ``make()`` returns a Figure or ``(Figure, extra)``.

    Returns each job's extra by file name.
    """
    global _JOBS
    _JOBS = list(jobs)
    try:
        workers = min(2, os.cpu_count() or 1, len(jobs))
        if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
            with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
                extras = [f.result() for f in [pool.submit(_draw, i, directory) for i in range(len(jobs))]]
        else:
            extras = [_draw(i, directory) for i in range(len(jobs))]
    finally:
        _JOBS = []
    return {name: extra for (name, _), extra in zip(jobs, extras)}
