"""The runs of a design as campaign runs: ids, W-ball placements, the campaign they extend.

A design counts runs per candidate; here each becomes one run.  The first run of a candidate is
at the candidate's mount; each further one is on a W-ball placement of its own (a re-clamped ball:
own offsets, the campaign format's rule for a second run of one pattern, setup and mount), named
``<mount>#2``, ``<mount>#3`` at the same geometry.  A touch-probe or R-test run has no set-up or mount of the ball
bar's (None): a further run of such a candidate sets its own terms anew (:meth:`.candidates.WithoutBar.again`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from ..campaign import Campaign, Mount, Setup
from .candidates import Candidate


@dataclass(frozen=True)
class DesignedRun:
    """One run of a design: its candidate, which run of that candidate it is (1, 2, …) and its geometry."""

    candidate: Candidate
    instance: int
    setup: Setup | None
    mount: Mount | None

    @property
    def instrument(self) -> str:
        return self.candidate.instrument

    @property
    def measured(self):
        """The candidate as this run measures it (a further probe or R-test run: its own terms' owners)."""
        return self.candidate.again(self.instance)

    @property
    def pattern(self) -> str:
        return self.candidate.pattern

    @property
    def repeats(self) -> int:
        return self.candidate.repeats

    @property
    def length(self) -> float:
        return self.candidate.length

    @property
    def label(self) -> str:
        if self.setup is None:
            return self.candidate.name + (f" #{self.instance}" if self.instance > 1 else "")
        return f"{self.pattern}@{self.setup.id}/{self.mount.id}"


def designed_runs(candidates: list[Candidate], counts: np.ndarray, taken=()) -> list[DesignedRun]:
    """The runs of ``counts`` (K,) in candidate order (not yet in measuring order); a further run's placement gets
    the first id ``<mount>#2``, ``<mount>#3``, … not in ``taken`` (the mount ids already in use)."""
    used = set(taken)
    out = []
    for k in np.flatnonzero(counts):
        c = candidates[k]
        if c.instrument != "ballbar":
            out += [DesignedRun(c, i, None, None) for i in range(1, int(counts[k]) + 1)]
            continue
        n = 2
        for i in range(1, int(counts[k]) + 1):
            mount = c.mount
            if i > 1:
                while f"{c.mount.id}#{n}" in used:
                    n += 1
                mount = Mount(f"{c.mount.id}#{n}", c.mount.Z_C, c.mount.R_C, position=c.mount.position)
                used.add(mount.id)
            out.append(DesignedRun(c, i, c.setup, mount))
    return out


def geometry_of(campaign: Campaign, runs: list[DesignedRun]) -> tuple[dict[str, Setup], dict[str, Mount]]:
    """The campaign's setups and mounts plus those the runs bring."""
    setups, mounts = dict(campaign.ballbar.setups), dict(campaign.ballbar.mounts)
    for r in runs:
        if r.setup is None:
            continue
        setups.setdefault(r.setup.id, r.setup)
        mounts.setdefault(r.mount.id, r.mount)
    return setups, mounts


def with_runs(campaign: Campaign, runs: list[DesignedRun], as_run) -> Campaign:
    """A copy of ``campaign`` with the ball-bar ``runs`` appended as runs of zero eccentricities (``repeats`` each): the rows
    of the forward models for them, after the measured runs' rows.  ``as_run(candidate) -> Run`` makes a candidate a
    run (:meth:`.design.Planner.as_run`: with its arc and held axes where it has them); the run is placed at its
    designed mount."""
    aug = copy.copy(campaign)
    bb = copy.copy(campaign.ballbar)
    bb.setups, bb.mounts = geometry_of(campaign, runs)
    made = []
    for r in runs:
        if r.instrument != "ballbar":  # not a ball-bar run: its rows are its candidate's (:mod:`.design_check`)
            continue
        run = as_run(r.candidate)
        run.setup, run.mount = r.setup.id, r.mount.id
        made.append(run)
    bb.runs = list(bb.runs) + made
    aug.ballbar = bb
    return aug


__all__ = ["DesignedRun", "designed_runs", "geometry_of", "with_runs"]
