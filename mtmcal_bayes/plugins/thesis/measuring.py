"""Measuring NC programs of the ball-bar patterns for a campaign's tool setup and mount (``ncgen``).

:func:`~.program_format.pattern_program` writes the blocks from plain
numbers; this module takes them from a campaign: R_B of the setup (default the
primary one, that of BX), Z_C and R_C of the mount the campaign uses for the
pattern's axis, the bar length and the CR geometry, and the NC origin
``(X_T, 0, Z_C + R_B + Z_T)`` unless the first block is placed explicitly.
"""

from __future__ import annotations

import math

from ...errors import ParameterError
from ...io.machine_reader import description_of
from .htm import nc_origin
from ...patterns import PATTERNS
from .compensation.compensate import geometry_for
from .program_format import pattern_program


def measuring_program(pattern: str, campaign=None, *, R_B_mm: float | None = None, start: tuple | None = None,
                      step_deg: float = 2.5, feed: float | None = None, n: int | None = None,
                      setup: str | None = None, mount: str | None = None) -> str:
    """The program text of ``pattern`` (thesis Fig 4.30(a) for BX with the thesis values).

    ``start`` = (x0, y0, z0) mm places the first block; else the setup's NC origin is used.
    ``campaign`` None: a standalone program from ``R_B_mm`` and ``start`` (bar 100 mm, R_C = Z_C = 0).
    """
    if start is not None and not all(math.isfinite(v) for v in start):
        raise ParameterError("start", "must be finite numbers")
    origin, desc = None, None
    if campaign is not None:
        desc = description_of(campaign.machine)
        mount = mount or (campaign.mount_for(pattern).id if pattern in PATTERNS else None)
        geo = geometry_for(campaign, setup, mount)
        R_B = R_B_mm if R_B_mm is not None else geo.R_B
        origin = None if start is not None else nc_origin(geo)
        L_B, Z_C, R_C, cr = campaign.ballbar.length, geo.Z_C, geo.R_C, campaign.ballbar.cr_geometry
    elif R_B_mm is None or start is None:
        raise ParameterError("R_B_mm", "a program without a campaign needs R_B_mm and start")
    else:
        R_B, L_B, Z_C, R_C, cr = R_B_mm, 100.0, 0.0, 0.0, "RC-LB"
    lines = pattern_program(pattern, R_B, step_deg, n, L_B=L_B, Z_C=Z_C, R_C=R_C, start=start, origin=origin,
                            feed=feed, cr_geometry=cr, desc=desc)
    return "\n".join(lines) + "\n"
