"""The thesis' program format: its ball-bar programs as Fig 4.30(a) writes them (``program_format``).

The engine selects, checks and computes a program on every machine (:mod:`mtmcal_bayes.io.chain_programs`: the
pattern at a set-up and mount, a campaign run, a planned run; the commands of Tables 2.2/2.3 through the
``integrex-i200`` chain, the W ball where :mod:`.translation` places it).  What is the thesis' own is how the
program is written:

* **its blocks**: ``G01 X Y Z B C [F]``, 4 decimals, nothing else (no header, no start pose);
* **its NC frame**: the commands (the B-axis centre in the C-table frame) shifted so that the first block sits at
  ``start`` = (x0, y0, z0), else by the set-up's NC origin ``(X_T, 0, Z_C + R_B + Z_T)`` (of the campaign's set-up
  and mount, whatever tool length ``R_B_mm`` the program is for);
* **its grid**: ``n`` blocks from the arc's first angle by ``step_deg`` (default 2.5°), by default over the arc's
  span — B 0–90° with its end, C one turn without repeating its start;
* **its options**: ``R_B_mm`` (the tool length the blocks are for), ``start``, ``n``; without a campaign, with
  ``R_B_mm`` and ``start``: a program from these alone (bar 100 mm, W ball at R_C = Z_C = 0);
* a feed word only where one is asked.

Thesis Fig 4.30(a) is BX from R_B = 356.3945 mm, x0 = −390, z0 = −112.2605 mm, B steps of 2.5/9°, F2000:
X = x0 + R_B·sin B, Z = z0 − R_B·(1 − cos B).
"""

from __future__ import annotations

import math

import numpy as np

from ...campaign import Ballbar, Campaign, Mount, Setup
from ...errors import ParameterError
from ...io.gcode import block_line
from .htm import Geometry, nc_origin

#: a full turn, degrees: an arc that closes it is programmed without repeating its start
TURN_DEG = 360.0
#: the bar of a program written without a campaign, mm
ALONE_BAR_MM = 100.0


def _full_turn(arc: np.ndarray) -> bool:
    """Whether ``arc`` (k,) degrees is a full turn on an even grid whose last step would return to its start."""
    if len(arc) < 3:
        return False
    d = np.diff(arc)
    return bool(np.allclose(d, d[0]) and abs(arc[-1] + d[0] - arc[0] - TURN_DEG) < 1e-9)


class Fig430Format:
    """The program format of thesis Fig 4.30(a) (the module docstring), in the engine's protocol
    (:class:`mtmcal_bayes.io.chain_programs.ChainFormat`)."""

    name = "thesis Fig 4.30(a)"
    options = ("R_B_mm", "start", "n")
    step_deg = 2.5
    campaign_feed = False

    def alone(self, campaign, options: dict):
        """With ``R_B_mm`` and ``start`` and no campaign: one of the thesis machine with that tool, a 100 mm bar and
        the W ball at R_C = Z_C = 0 (the blocks then need nothing else); else ``campaign``."""
        if "R_B_mm" not in options or "start" not in options:
            return campaign
        R_B = options["R_B_mm"]
        bar = Ballbar(length=ALONE_BAR_MM, accuracy=campaign.ballbar.accuracy,
                      setups={"R_B": Setup("R_B", R_B, 0.0, 0.0)}, mounts={"origin": Mount("origin", 0.0, 0.0)})
        return Campaign(machine=campaign.machine, ballbar=bar, source="<R_B_mm and start>")

    def grid(self, arc: np.ndarray, step_deg: float, options: dict) -> np.ndarray:
        """``n`` angles from the arc's first by ``step_deg``; default ``n`` spans the arc (a full turn without
        repeating its start)."""
        if not (np.isfinite(step_deg) and step_deg > 0):
            raise ParameterError("step_deg", f"must be a positive number, got {step_deg}")
        n = options.get("n")
        if n is None:
            full = _full_turn(arc)
            n = round((TURN_DEG if full else arc[-1] - arc[0]) / step_deg) + (0 if full else 1)
        if n < 1:
            raise ParameterError("n", f"must be at least 1, got {n}")
        return arc[0] + step_deg * np.arange(n)

    def tool_length(self, setup, options: dict) -> float:
        """``R_B_mm`` where given, else the set-up's."""
        R_B = options.get("R_B_mm", setup.R_B)
        if not (np.isfinite(R_B) and R_B > 0):
            raise ParameterError("R_B_mm", f"must be a positive number, got {R_B}")
        return R_B

    def ballbar(self, program, options: dict, *, decimals: int = 4) -> str:
        """The blocks of ``program`` (a :class:`~mtmcal_bayes.io.chain_programs.BallbarProgram`) in its NC frame."""
        start = options.get("start")
        if start is not None and not all(math.isfinite(v) for v in start):
            raise ParameterError("start", "must be finite numbers")
        q = program.commands.q
        xyz = np.c_[q["X"], q["Y"], q["Z"]]
        if start is not None:
            xyz = xyz - xyz[0] + np.asarray(start, dtype=float)
        else:
            s, m = program.setup, program.mount
            xyz = xyz - nc_origin(Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C))
        B, C = np.degrees(q["B"]), np.degrees(q["C"])
        lines = [block_line((x, y, z, b, c), feed=program.feed, decimals=decimals)
                 for (x, y, z), b, c in zip(xyz, B, C)]
        return "\n".join(lines) + "\n"


#: the thesis plug-in's program format
FORMAT = Fig430Format()
