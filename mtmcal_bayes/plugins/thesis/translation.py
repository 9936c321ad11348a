"""The thesis campaign format in the engine's terms: its W balls as positions, its runs as arcs and bar sides.

A mount's W ball is where the thesis places it (Tables 2.2/2.3): at the dummy sphere of the mount's first run, at
X = 0 for a B pattern and X = R_C for a C pattern, Y = 0, Z = Z_C (the home pose, the C axis at the origin of the
``integrex-i200`` description).  A run's arc is the thesis' grid (B 0–90° by 1°, C 0–355° by 5°).  Its BT bar is
on the trailing side of the W ball and, in the geometry of Fig 2.6 (``cr_geometry = "RC+LB"``), its CR bar outside
it: both *reversed* against the engine's patterns (:mod:`mtmcal_bayes.machines.patterns`).  Through these the
engine's chain (:class:`~mtmcal_bayes.models.chain_models.ChainBallbarModel`) gives the thesis machine's ``chain``
model (``tests/test_chain.py``; its reading frames too, ``tests/test_conventions_machines.py``).
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ...io.machine_reader import description_of
from ...patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG


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
        x = 0.0 if first.get(mid, "C") in B_PATTERNS else mount.R_C
        mount.position = np.array([x, 0.0, mount.Z_C])
    for run in [*bb.runs, *bb.planned]:
        run.arc_deg = B_ANGLES_DEG if run.pattern in B_PATTERNS else C_ANGLES_DEG
        run.reversed = run.pattern == "BT" or (run.pattern == "CR" and bb.cr_geometry == "RC+LB")
    return out
