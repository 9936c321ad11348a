"""The machine-time model applied to designed runs: measuring order, minutes, the schedule's events."""

from __future__ import annotations

import numpy as np

from ..machine_time import TimeModel, canonical_order
from .machine_kit import kit_of


class Timing:
    """Minutes of runs at ``campaign``'s geometry (bar length, CR geometry, feed) under ``model``.

    ``start`` = (ball bar mounted, current setup id, current mount id); runs are measured in
    :func:`~mtmcal_bayes.machine_time.canonical_order` unless already ordered (:meth:`per_run`, :meth:`events`).
    """

    def __init__(self, campaign, model: TimeModel):
        self.model = model
        self.clock = kit_of(campaign).clock(model, campaign)

    def order(self, runs, start) -> list[int]:
        return canonical_order(runs, start[1], start[2])

    def total(self, runs, start) -> float:
        """Minutes of ``runs`` in their measuring order."""
        return self.clock.total([runs[i] for i in self.order(runs, start)], start)

    def per_run(self, runs, start) -> list[float]:
        """Minutes of each run of the ordered ``runs``: measuring plus the set-up changes before it."""
        return self.clock.schedule(runs, start).run_total_min(len(runs))

    def events(self, runs, start):
        """The schedule's events of the ordered ``runs``."""
        return self.clock.schedule(runs, start).events

    def total_of_counts(self, candidates, counts, start) -> float:
        """:meth:`total` of the runs of ``counts`` (K,) of ``candidates`` (as :func:`.design_runs.designed_runs`
        makes them: a candidate's further runs each on a placement of its own) without making them: the same
        schedule walked over (set-up, placement) keys, its minutes added in the same order (the same float).  The
        search asks this tens of thousands of times; walking stand-in runs through :func:`canonical_order` and
        ``MachineClock._steps`` took half as long again over a whole design, so the walk is written out here
        (``tests/test_machine_time.py`` holds it equal to :meth:`total`)."""
        # the runs grouped by set-up, then placement, each in the order of first appearance (designed order)
        groups: dict = {}
        for k in np.flatnonzero(counts):
            c = candidates[k]
            k = int(k)
            by_mount = groups.setdefault(c.setup.id, {})
            by_mount.setdefault(c.mount.id, []).append(k)
            for i in range(1, int(counts[k])):
                by_mount[("again", k, i)] = [k]
        setups = list(groups)
        if start[1] in groups:
            setups.remove(start[1])
            setups.insert(0, start[1])
        m = self.model
        mounted, setup, mount = start
        t = 0.0
        for s in setups:
            mounts = list(groups[s])
            if s == start[1] and start[2] in groups[s]:
                mounts.remove(start[2])
                mounts.insert(0, start[2])
            for mt in mounts:
                for k in groups[s][mt]:
                    if not mounted:
                        t += m.mount_ballbar_min
                    if s != setup:
                        t += m.tool_change_min
                    if mt != mount:
                        t += m.reclamp_w_ball_min
                    if mounted and s == setup and mt == mount:
                        t += m.pattern_change_min
                    t += self._measure(candidates[k])
                    mounted, setup, mount = True, s, mt
        return t

    def _measure(self, c) -> float:
        """Measuring minutes of one run of candidate ``c`` (every run of it alike), each candidate's once."""
        cache = self.__dict__.setdefault("_measured", {})
        if id(c) not in cache:
            cache[id(c)] = (c, self.clock.run_minutes(_AsRun(c)))  # c kept: its id stays its own
        return cache[id(c)][1]


class _AsRun:
    """A candidate seen as a run of a schedule (pattern, set-up, mount, repeats, candidate)."""

    def __init__(self, c):
        self.candidate, self.pattern, self.setup, self.mount, self.repeats = c, c.pattern, c.setup, c.mount, c.repeats

