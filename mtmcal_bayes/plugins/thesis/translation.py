"""The thesis campaign format in the engine's terms: its runs' arcs and the bar sides of its patterns.

A mount's W ball is where the thesis' keys place it (:meth:`~mtmcal_bayes.campaign.Mount.centre`: at radius R_C
along X from the C axis at height Z_C; a B pattern's mount has R_C = 0, Table 2.2).  A run's arc is the thesis' grid
(B 0–90° by 1°, C 0–355° by 5°).  Its BT bar is on the trailing side of the W ball and, in the geometry of Fig 2.6
(``cr_geometry = "RC+LB"``), its CR bar outside it: both *reversed* against the engine's patterns
(:mod:`mtmcal_bayes.machines.patterns`), which the campaign states as its ``reversed_patterns``.  Through these the
engine's chain (:class:`~mtmcal_bayes.models.chain_models.ChainBallbarModel`) is the thesis machine's ``chain``
model (``tests/test_chain.py``) and its reading frames are the thesis' (``tests/test_conventions_machines.py``).
"""

from __future__ import annotations

import copy
import dataclasses
import functools

from ...io.machine_reader import description_of
from ...pattern_frames import chain_frame
from ...patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG, PATTERNS


def reversed_patterns(cr_geometry: str) -> frozenset[str]:
    """The thesis patterns whose bar is on the other side of the W ball from the engine's: BT, and CR in the
    geometry of Fig 2.6 (``"RC+LB"``)."""
    return frozenset({"BT", "CR"} if cr_geometry == "RC+LB" else {"BT"})


def complete(ballbar, desc) -> None:
    """Give a thesis-format ``ballbar`` (in place) the engine's terms: its patterns' arcs and bar sides and its runs'
    reading frames through the chain of ``desc``."""
    ballbar.pattern_arcs = {p: B_ANGLES_DEG if p in B_PATTERNS else C_ANGLES_DEG for p in PATTERNS}
    ballbar.reversed_patterns = reversed_patterns(ballbar.cr_geometry)
    ballbar.pattern_frames = functools.partial(chain_frame, desc)


def translated(campaign):
    """A copy of a thesis-format ``campaign`` in the engine's terms (:func:`complete`), its machine with its
    description (a campaign built in Python has none: the thesis machine's)."""
    out = copy.copy(campaign)
    if campaign.machine.description is None:
        out.machine = dataclasses.replace(campaign.machine, description=description_of(campaign.machine))
    out.ballbar = copy.deepcopy(campaign.ballbar)
    complete(out.ballbar, out.machine.description)
    return out
