"""The thesis campaign format in the engine's terms: its W balls as positions, its runs as arcs and bar sides.

A run's W ball is where the thesis places it (Tables 2.2/2.3): at the dummy sphere, at X = 0 for a B pattern and
X = R_C for a C pattern, Y = 0, Z = Z_C (the home pose, the C axis at the origin of the ``integrex-i200``
description; a mount of a campaign's B runs has R_C = 0, so :meth:`~mtmcal_bayes.campaign.Mount.centre` is its W
ball).  A run's arc is the thesis' grid (B 0–90° by 1°, C 0–355° by 5°).  Its BT bar is on the trailing side of the
W ball and, in the geometry of Fig 2.6 (``cr_geometry = "RC+LB"``), its CR bar outside it: both *reversed* against
the engine's patterns (:mod:`mtmcal_bayes.machines.patterns`), which a campaign read in this format states as its
``pattern_arcs`` and ``reversed_patterns`` (:func:`complete`), with its runs' commands as the Tables print them
(``run_commands``, :func:`table_commands`: the bits of the published numbers; the engine's equal them to
rounding).  Through these the engine's ball-bar model (:class:`~mtmcal_bayes.models.ballbar.BallbarModel`) with
the chain is the thesis machine's ``chain`` model (``tests/test_chain.py``), its reading frames are those of Tables 2.2/2.3 (``tests/test_conventions_machines.py``),
and the engine's :func:`~mtmcal_bayes.machines.patterns.pattern_commands` gives the commands of Tables 2.2/2.3 at
these W balls (:func:`run_placement`: the programs of ``ncgen``, the planner's feasibility and clock).
"""

from __future__ import annotations

import copy
import dataclasses
import functools

import numpy as np

from ...io.machine_reader import description_of
from ...machines.patterns import PatternCommands
from ...pattern_frames import chain_frame
from ...patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG, PATTERNS
from .pattern_tables import pattern_commands as tables


def w_ball(mount, pattern: str) -> np.ndarray:
    """The W-ball position (3,) mm at the home pose of a run of ``pattern`` on ``mount`` (``Z_C``, ``R_C`` mm):
    ``(0, 0, Z_C)`` for a B pattern, ``(R_C, 0, Z_C)`` for a C pattern (Tables 2.2/2.3)."""
    return np.array([0.0 if pattern in B_PATTERNS else mount.R_C, 0.0, mount.Z_C])


def arc_deg(pattern: str) -> np.ndarray:
    """The thesis' grid of a pattern's angles (k,), degrees: B 0–90° by 1°, C 0–355° by 5°."""
    return B_ANGLES_DEG if pattern in B_PATTERNS else C_ANGLES_DEG


def reversed_patterns(cr_geometry: str) -> frozenset[str]:
    """The thesis patterns whose bar is on the other side of the W ball from the engine's: BT, and CR in the
    geometry of Fig 2.6 (``"RC+LB"``, the T ball outside)."""
    return frozenset({"BT", "CR"} if cr_geometry == "RC+LB" else {"BT"})


def bar_reversed(pattern: str, cr_geometry: str) -> bool:
    """Whether a run of ``pattern`` has its bar on the other side of the W ball than the engine's pattern puts it."""
    return pattern in reversed_patterns(cr_geometry)


def run_placement(campaign, pattern: str, mount) -> tuple[np.ndarray, np.ndarray, bool]:
    """A run of ``pattern`` on ``mount`` of a thesis-format ``campaign`` in the engine's terms: ``(W-ball position
    (3,) mm, arc (k,) degrees, bar reversed)``; a mount that gives its position (the generic format) is there, the
    bar on the side the campaign states."""
    if mount.position is not None:
        return mount.centre(), arc_deg(pattern), pattern in campaign.ballbar.reversed_patterns
    return w_ball(mount, pattern), arc_deg(pattern), bar_reversed(pattern, campaign.ballbar.cr_geometry)


def table_commands(run, ballbar) -> PatternCommands | None:
    """The commands of a thesis-format ``run`` of ``ballbar`` as Tables 2.2/2.3 print them
    (:func:`.pattern_tables.pattern_commands`), with the polar angle its measured traces are read by
    (:func:`~mtmcal_bayes.patterns.polar_angle`); None for a run the Tables do not give (a held axis, a bar side of
    its own).  The engine's patterns give the same commands to rounding (``tests/test_chain.py``); these are the
    bits the thesis' numbers were computed with (a tie between candidate runs in ``plan`` goes by them)."""
    reversed_ = ballbar.bar_reversed(run)
    if run.hold_deg or (reversed_ != (run.pattern == "BT") and run.pattern != "CR"):
        return None
    s, m = ballbar.setups[run.setup], ballbar.mounts[run.mount]
    arc = np.asarray(ballbar.arc_of(run), dtype=float)
    cmd = tables(run.pattern, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=ballbar.length, angles_deg=arc,
                 cr_geometry="RC+LB" if reversed_ else "RC-LB")
    return PatternCommands({"C": cmd.C, "B": cmd.B, "X": cmd.X, "Y": cmd.Y, "Z": cmd.Z}, cmd.psi, arc)


def complete(ballbar, desc) -> None:
    """Give a thesis-format ``ballbar`` (in place) the engine's terms: its patterns' arcs and bar sides, its runs'
    commands (Tables 2.2/2.3) and their reading frames through the chain of ``desc``."""
    ballbar.pattern_arcs = {p: arc_deg(p) for p in PATTERNS}
    ballbar.reversed_patterns = reversed_patterns(ballbar.cr_geometry)
    ballbar.run_commands = table_commands
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
