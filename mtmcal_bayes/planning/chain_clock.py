"""The machine clock of the engine's designed runs (:mod:`mtmcal_bayes.machine_time`): a run is timed over its arc."""

from __future__ import annotations

from ..machine_time import MachineClock, Motion, TimeModel
from .chain_candidates import arc_of


def engine_clock(model: TimeModel, campaign) -> MachineClock:
    """The clock of designed runs (``.candidate``) on ``campaign``'s machine: a run's motion is its candidate's
    pattern over its arc with its held axes, tool length, W-ball position and bar, so ``path`` is the length of its
    linear-axis commands over the arc and ``span`` the arc (:mod:`mtmcal_bayes.machine_time`)."""
    desc = campaign.machine.description

    def motion(run) -> Motion:
        c = run.candidate
        return Motion(c.pattern, float(c.setup.R_B), tuple(float(x) for x in c.mount.position), float(c.length),
                      tuple(float(a) for a in arc_of(c, desc)), tuple(c.hold_deg))

    return MachineClock(model, desc, motion, feed=campaign.ballbar.feed_mm_per_min)
