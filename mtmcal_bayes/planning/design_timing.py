"""The machine-time model applied to designed runs: measuring order, minutes, the schedule's events."""

from __future__ import annotations

from ..machine_time import MachineClock, TimeModel, canonical_order


class Timing:
    """Minutes of runs at ``campaign``'s geometry (bar length, CR geometry, feed) under ``model``.

    ``start`` = (ball bar mounted, current setup id, current mount id); runs are measured in
    :func:`~mtmcal_bayes.machine_time.canonical_order` unless already ordered (:meth:`per_run`, :meth:`events`).
    """

    def __init__(self, campaign, model: TimeModel):
        bb = campaign.ballbar
        self.model = model
        self.clock = MachineClock(model, L_B=bb.length, cr_geometry=bb.cr_geometry, feed=bb.feed_mm_per_min)

    def order(self, runs, start) -> list[int]:
        return canonical_order(runs, start[1], start[2])

    def total(self, runs, start) -> float:
        """Minutes of ``runs`` in their measuring order."""
        ordered = [runs[i] for i in self.order(runs, start)]
        return self.clock.schedule(ordered, start).total_min

    def per_run(self, runs, start) -> list[float]:
        """Minutes of each run of the ordered ``runs``: measuring plus the set-up changes before it."""
        return self.clock.schedule(runs, start).run_total_min(len(runs))

    def events(self, runs, start):
        """The schedule's events of the ordered ``runs``."""
        return self.clock.schedule(runs, start).events
