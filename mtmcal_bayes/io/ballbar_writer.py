"""``[ballbar]`` of a campaign on any machine written: the inverse of the one reader (:mod:`.ballbar_section`).

The engine writes its keys alike for every machine — instrument, bar length and accuracy, feed, convention, the
reason of a reading chosen over another, each run with its repeats or its traces (relative to the saved file), its
reading, its alternative reading, and each planned run; the machine's ``ballbar_keys`` (the reader's, with their
writing beside their reading) write its own keys of the table, of a set-up and of a mount.  A run's own geometry
(``arc_deg`` + ``step_deg``, ``hold_deg``, ``reversed``) is written only where it differs from what its campaign
format fixes: an arc other than its pattern's in a format whose patterns fix the arc (the thesis'), held axes where
it holds any, the bar reversed where it is.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .. import units
from ..campaign import Ballbar, Campaign, PlannedRun, Run


def ballbar_to_dict(c: Campaign, keys, save_dir: Path | None) -> dict | None:
    """The ``[ballbar]`` table of ``c`` (file units), ``keys`` its machine's (``ballbar_keys``); None for a campaign
    without a ball bar (no set-ups, mounts or runs: a probe-only campaign).  Trace files are written relative to
    ``save_dir`` (absolute when ``None``)."""
    bb = c.ballbar
    if not (bb.setups or bb.mounts or bb.runs or bb.planned):
        return None
    b: dict = {"instrument": bb.instrument} if bb.instrument else {}
    b.update({"length_mm": bb.length, "accuracy_um": units.from_internal(bb.accuracy, "um")})
    if bb.feed_mm_per_min is not None:
        b["feed_mm_per_min"] = bb.feed_mm_per_min
    b.update(keys.write(bb))
    b["convention"] = bb.convention  # stated, so that a saved campaign keeps its reading whatever the default
    if bb.alternative_reason and bb.reading_choices():  # the reason of a choice whose runs are still there
        b["alternative_reason"] = bb.alternative_reason
    b["setups"] = {s.id: keys.write_setup(s) for s in bb.setups.values()}
    b["mounts"] = {m.id: keys.write_mount(m) for m in bb.mounts.values()}
    runs = [_measured(c, run, save_dir) for run in bb.runs]
    runs += [_planned(bb, run) for run in bb.planned]  # after the measured runs, in measuring order
    if runs:  # none: a machine with set-ups and mounts only
        b["runs"] = runs
    return b


def _measured(c: Campaign, run: Run, save_dir: Path | None) -> dict:
    d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount, **_geometry(c.ballbar, run)}
    if run.convention:
        d["convention"] = run.convention
    if run.alternative_convention:
        d["alternative_convention"] = run.alternative_convention
    if run.trace_csv:
        d["trace_csv"] = [relative_path(c, f, save_dir) for f in run.trace_csv]
    else:
        d.update({f"{k}_um": [units.from_internal(x, "um") for x in v] for k, v in run.repeats.items()})
    return d


def _planned(bb: Ballbar, run: PlannedRun) -> dict:
    """A planned run: ``planned = true``, ``repeats`` and what else is set."""
    d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount, **_geometry(bb, run)}
    if run.convention:
        d["convention"] = run.convention
    d.update({"planned": True, "repeats": int(run.repeats)})
    if run.length is not None:
        d["length_mm"] = run.length
    if run.minutes is not None:
        d["minutes"] = run.minutes
    if run.order is not None:
        d["order"] = int(run.order)
    if run.why:
        d["why"] = run.why
    return d


def _geometry(bb: Ballbar, run: Run | PlannedRun) -> dict:
    """``arc_deg`` + ``step_deg``, ``hold_deg`` and ``reversed`` of a run where they differ from what its campaign
    format fixes (its pattern's arc where the format gives one, no held axes, the pattern's bar side)."""
    d: dict = {}
    fixed = bb.pattern_arcs.get(run.pattern)
    if run.arc_deg is not None and not (fixed is not None and np.array_equal(run.arc_deg, fixed)):
        arc = np.asarray(run.arc_deg, dtype=float)
        d["arc_deg"] = [float(arc[0]), float(arc[-1])]
        d["step_deg"] = float(arc[1] - arc[0])
    if run.hold_deg:
        d["hold_deg"] = {k: float(v) for k, v in run.hold_deg.items()}
    if run.reversed:
        d["reversed"] = True
    return d


def relative_path(c: Campaign, name: str, save_dir: Path | None) -> str:
    """A file named in ``c`` (relative to its folder), as seen from ``save_dir`` (absolute when ``None``)."""
    path = Path(c.base_dir or ".", name).resolve()
    return str(path) if save_dir is None else os.path.relpath(path, save_dir)


__all__ = ["ballbar_to_dict", "relative_path"]
