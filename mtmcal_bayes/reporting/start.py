"""A report's first steps, taken before the modules that compute it are imported.

Importing the report's computation (sampling, ArviZ, the posterior's checks, the planner: :mod:`.build`) keeps one
core busy for about a second while the other has nothing to do.  The figures of the campaign's machine
(``machine.png``, ``deviations.png``) need the campaign alone, so :func:`begin` checks the output directory, makes
the temporary directory the report is written into and begins those figures in a process of their own, which draws
them during that second; the report then goes on with the same :class:`~.drawing.Drawing`.  This module and what it
imports (the drawing, the machine's figures: matplotlib, the description) stay clear of the computation's modules.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ..analysis import CampaignAnalysis
from ..errors import MtmcalError
from ..io.textfiles import atomic_directory
from .drawing import Drawing
from .machine_figure import figure_jobs


@dataclass
class Begun:
    """A report begun by :func:`begin`: the temporary directory it is written into, and its drawing, whose first
    batch draws the machine's figures."""

    directory: Path
    drawing: Drawing


def check_output_dir(out_dir: Path) -> None:
    """A :class:`MtmcalError` where the report cannot be written into ``out_dir``: it is a file, or its parent
    directory does not exist."""
    if out_dir.exists() and not out_dir.is_dir():
        raise MtmcalError(f"{out_dir}: cannot write the report: it exists and is not a directory")
    if not out_dir.resolve().parent.is_dir():
        raise MtmcalError(f"{out_dir}: cannot write the report: directory {out_dir.resolve().parent} does not exist")


@contextlib.contextmanager
def begin(campaign, out_dir) -> Iterator[Begun]:
    """Begin the report of ``campaign`` (a campaign or its analysis) into ``out_dir`` (module docstring): on success
    of the ``with`` block the files written into ``Begun.directory`` move into ``out_dir``; on failure nothing is
    left, and the drawing processes still running are ended."""
    out_dir = Path(out_dir)
    check_output_dir(out_dir)
    if isinstance(campaign, CampaignAnalysis):
        campaign = campaign.campaign
    with atomic_directory(out_dir) as tmp:
        drawing = Drawing(tmp)
        try:
            # one process: the other core is the only one free while this one imports
            drawing.start(figure_jobs(campaign), workers=1)
            yield Begun(tmp, drawing)
        finally:
            drawing.stop()
