"""The time model on a machine from its description (:mod:`mtmcal_bayes.machine_time`): a run's path over its arc."""

from __future__ import annotations

import numpy as np

from ..machine_time import MachineClock, TimeModel
from ..machines.patterns import pattern_commands
from .chain_candidates import arc_of


class DescribedClock(MachineClock):
    """The time model on a described machine: a run's ``path`` is the length of its linear-axis commands (X, Y, Z)
    over its arc, ``span`` the arc in degrees, and a run holding another rotary axis off 0 adds
    ``index_rotary_min`` (:mod:`mtmcal_bayes.machine_time`).  Runs are designed runs (``.candidate``)."""

    def __init__(self, model: TimeModel, campaign):
        bb = campaign.ballbar
        super().__init__(model, L_B=bb.length, feed=bb.feed_mm_per_min)
        self.desc = campaign.machine.description
        self._cache: dict[int, tuple] = {}  # id -> (candidate, minutes): the candidate kept, its id its own

    def run_minutes(self, run) -> float:
        c = run.candidate
        key = id(c)
        if key not in self._cache:
            arc = arc_of(c, self.desc)
            cmd = pattern_commands(self.desc, c.pattern, length=c.setup.R_B, ball=c.mount.position, bar=c.length,
                                   arc_deg=arc, hold_deg=dict(c.hold_deg) or None)
            xyz = np.stack([cmd.q[a] for a in "XYZ"], axis=-1)
            path = float(np.sum(np.linalg.norm(np.diff(xyz, axis=0), axis=1)))
            span = float(arc[-1] - arc[0])
            m = self.model
            one = max(path / self.feed_mm_per_min, span / m.rotary_deg_per_min)
            index = m.index_rotary_min if any(v != 0 for _, v in c.hold_deg) else 0.0
            self._cache[key] = (c, m.dwell_min + index + c.repeats * m.directions * one)
        return self._cache[key][1]
