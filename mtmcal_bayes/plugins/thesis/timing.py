"""The machine clock of the thesis' patterns (:mod:`mtmcal_bayes.machine_time`): each timed over its whole range.

A thesis run's motion is its pattern as Tables 2.2/2.3 place it (the W ball, the bar side: :mod:`.translation`) at
the campaign's bar length, over the pattern's whole range sampled densely (:data:`TIMED_POINTS` angles over 0–90°
for a B pattern, over a closed turn 0–360° for a C pattern): the path the feed word of its measuring program
(Fig 4.30(a)) is programmed along, not the 5° polygon of its readings: the B-axis centre's path in the C-table
frame, an arc of radius R_B (R_B + L_B for BR, ``hypot(R_B, L_B)`` for BT) for the B patterns, a circle of radius
R_C (R_C ∓ L_B for CR, ``hypot(R_C, L_B)`` for CT) for the C patterns.  The bar is the campaign's, also for a
candidate with another bar length (as the thesis clock has always timed it).
"""

from __future__ import annotations

import functools

import numpy as np

from ...io.machine_reader import THESIS_TYPE, builtin_description, description_of
from ...machine_time import MachineClock, Motion, TimeModel
from ...patterns import B_PATTERNS
from .translation import bar_reversed, w_ball

#: angles of the grid a thesis pattern is timed over (720 chords: the arc's length to a relative 1e-6)
TIMED_POINTS = 721


@functools.cache
def timed_arc(pattern: str) -> tuple[float, ...]:
    """The angles a thesis pattern is timed over, degrees: its whole range (90° for B, a closed turn for C)."""
    span = 90.0 if pattern in B_PATTERNS else 360.0
    return tuple(float(a) for a in np.linspace(0.0, span, TIMED_POINTS))


def motion(run, *, L_B: float, cr_geometry: str = "RC-LB") -> Motion:
    """The motion of a thesis ``run`` (``pattern``, ``setup`` and ``mount`` objects) with a bar of ``L_B`` mm."""
    return Motion(run.pattern, float(run.setup.R_B), tuple(float(x) for x in w_ball(run.mount, run.pattern)),
                  float(L_B), timed_arc(run.pattern), reverse=bar_reversed(run.pattern, cr_geometry))


def thesis_clock(model: TimeModel, *, L_B: float, cr_geometry: str = "RC-LB", feed: float | None = None,
                 desc=None) -> MachineClock:
    """The clock of thesis runs with a bar of ``L_B`` mm in the CR geometry ``cr_geometry`` at the campaign's
    ``feed`` (mm/min), on the thesis machine's description (``desc``, default the built-in ``integrex-i200``)."""
    return MachineClock(model, builtin_description(THESIS_TYPE) if desc is None else desc,
                        functools.partial(motion, L_B=L_B, cr_geometry=cr_geometry), feed=feed)


def campaign_clock(model: TimeModel, campaign) -> MachineClock:
    """:func:`thesis_clock` of a thesis-format ``campaign`` (its bar, CR geometry, feed and description)."""
    bb = campaign.ballbar
    return thesis_clock(model, L_B=bb.length, cr_geometry=bb.cr_geometry, feed=bb.feed_mm_per_min,
                        desc=description_of(campaign.machine))
