"""The thesis campaign format in the engine's terms: its W balls as positions, its runs as arcs and bar sides.

A run's W ball is where the thesis places it (Tables 2.2/2.3): at the dummy sphere, at X = 0 for a B pattern and
X = R_C for a C pattern, Y = 0, Z = Z_C (the home pose, the C axis at the origin of the ``integrex-i200``
description); a mount's position is that of its first run.  A run's arc is the thesis' grid (B 0–90° by 1°, C
0–355° by 5°).  Its BT bar is on the trailing side of the W ball and, in the geometry of Fig 2.6
(``cr_geometry = "RC+LB"``), its CR bar outside it: both *reversed* against the engine's patterns
(:mod:`mtmcal_bayes.machines.patterns`).  Through these the engine's chain
(:class:`~mtmcal_bayes.models.chain_models.ChainBallbarModel`) gives the thesis machine's ``chain`` model
(``tests/test_chain.py``; its reading frames too, ``tests/test_conventions_machines.py``), and the engine's
:func:`~mtmcal_bayes.machines.patterns.pattern_commands` the commands of Tables 2.2/2.3 (:func:`commands`: the
programs of Fig 4.30(a), the planner's feasibility and clock).
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ...io.machine_reader import description_of
from ...machines.patterns import PatternCommands, pattern_commands
from ...patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG


def w_ball(mount, pattern: str) -> np.ndarray:
    """The W-ball position (3,) mm at the home pose of a run of ``pattern`` on ``mount`` (``Z_C``, ``R_C`` mm):
    ``(0, 0, Z_C)`` for a B pattern, ``(R_C, 0, Z_C)`` for a C pattern (Tables 2.2/2.3)."""
    return np.array([0.0 if pattern in B_PATTERNS else mount.R_C, 0.0, mount.Z_C])


def arc_deg(pattern: str) -> np.ndarray:
    """The thesis' grid of a pattern's angles (k,), degrees: B 0–90° by 1°, C 0–355° by 5°."""
    return B_ANGLES_DEG if pattern in B_PATTERNS else C_ANGLES_DEG


def bar_reversed(pattern: str, cr_geometry: str) -> bool:
    """Whether a run's bar is on the other side of the W ball than the engine's pattern puts it: BT always, CR in
    the geometry of Fig 2.6 (``"RC+LB"``, the T ball outside)."""
    return pattern == "BT" or (pattern == "CR" and cr_geometry == "RC+LB")


def run_placement(campaign, pattern: str, mount) -> tuple[np.ndarray, np.ndarray, bool]:
    """A run of ``pattern`` on ``mount`` of a thesis-format ``campaign`` in the engine's terms: ``(W-ball position
    (3,) mm, arc (k,) degrees, bar reversed)``."""
    return w_ball(mount, pattern), arc_deg(pattern), bar_reversed(pattern, campaign.ballbar.cr_geometry)


def commands(desc, pattern: str, *, R_B: float, mount, L_B: float, cr_geometry: str = "RC-LB",
             angles_deg=None) -> PatternCommands:
    """The engine's commands of a thesis pattern (those of Tables 2.2/2.3): tool length ``R_B``, W ball on ``mount``,
    bar ``L_B`` (mm), over ``angles_deg`` (default the thesis' grid, :func:`arc_deg`) on the thesis machine's
    description ``desc``."""
    return pattern_commands(desc, pattern, length=R_B, ball=w_ball(mount, pattern), bar=L_B,
                            arc_deg=arc_deg(pattern) if angles_deg is None else angles_deg,
                            reverse=bar_reversed(pattern, cr_geometry))


def translated(campaign):
    """A copy of a thesis-format ``campaign`` whose mounts have ``position`` (3,) mm and whose runs have
    ``arc_deg`` and ``reversed`` (module docstring), its machine with its description; everything else as it is."""
    out = copy.copy(campaign)
    if campaign.machine.description is None:  # a campaign built in Python: the thesis machine's description
        out.machine = dataclasses.replace(campaign.machine, description=description_of(campaign.machine))
    bb = out.ballbar = copy.deepcopy(campaign.ballbar)
    first: dict[str, str] = {}
    for run in [*bb.runs, *bb.planned]:
        first.setdefault(run.mount, run.pattern)
    for mid, mount in bb.mounts.items():
        mount.position = w_ball(mount, first.get(mid, "C"))
    for run in [*bb.runs, *bb.planned]:
        run.arc_deg, run.reversed = arc_deg(run.pattern), bar_reversed(run.pattern, bb.cr_geometry)
    return out
