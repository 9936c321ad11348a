"""The thesis' program format: measuring NC programs of its ball-bar patterns (Tables 2.2/2.3, Fig 4.30(a)).

The pattern commands (the B-axis centre in the C-table frame of Tables 2.2/2.3: the engine's commands of the
pattern on the ``integrex-i200`` description, :func:`.translation.commands`) are shifted into the NC frame so that
the first block sits at ``(x0, y0, z0)``; without them, the NC origin of a campaign setup is used:
``(X_T, 0, Z_C + R_B + Z_T)``.  The block format is the thesis' own.
Thesis Fig 4.30(a) is BX from R_B = 356.3945 mm, x0 = −390, z0 = −112.2605 mm,
B steps of 2.5/9°, F2000: X = x0 + R_B·sin B, Z = z0 − R_B·(1 − cos B).
"""

from __future__ import annotations

import numpy as np

from ...campaign import Mount
from ...errors import ParameterError
from ...io.gcode import block_line
from ...io.machine_reader import THESIS_TYPE, builtin_description
from ...patterns import B_PATTERNS, PATTERNS
from .translation import commands


def pattern_program(pattern: str, R_B: float, step_deg: float, n: int | None = None, *, L_B: float = 100.0,
                    Z_C: float = 0.0, R_C: float = 0.0, start: tuple | None = None, origin: tuple | None = None,
                    feed: float | None = None, cr_geometry: str = "RC-LB", desc=None) -> list[str]:
    """Motion blocks of ``pattern``: ``n`` blocks from angle 0 in steps of ``step_deg`` (deg).

    ``desc`` the machine's description (default the built-in ``integrex-i200``); ``start`` (x0, y0, z0) places the
    first block; else ``origin`` (model-frame NC origin, mm) is subtracted.
    Default ``n`` covers the pattern's range: 0–90° for B patterns, one turn for C patterns.
    """
    if pattern not in PATTERNS:
        raise ParameterError("pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(PATTERNS)})")
    for name, v in (("step_deg", step_deg), ("R_B_mm", R_B)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(name, f"must be a positive number, got {v}")
    span = 90.0 if pattern in B_PATTERNS else 360.0
    if n is None:
        n = int(round(span / step_deg)) + (1 if pattern in B_PATTERNS else 0)
    if n < 1:
        raise ParameterError("n", f"must be at least 1, got {n}")
    angles = step_deg * np.arange(n)
    desc = builtin_description(THESIS_TYPE) if desc is None else desc
    cmd = commands(desc, pattern, R_B=R_B, mount=Mount("", Z_C, R_C), L_B=L_B, cr_geometry=cr_geometry,
                   angles_deg=angles)
    xyz = np.c_[cmd.q["X"], cmd.q["Y"], cmd.q["Z"]]
    if start is not None:
        xyz = xyz - xyz[0] + np.asarray(start, dtype=float)
    elif origin is not None:
        xyz = xyz - np.asarray(origin)
    B = np.degrees(cmd.q["B"])
    C = np.degrees(cmd.q["C"])
    return [block_line((x, y, z, b, c), feed=feed) for (x, y, z), b, c in zip(xyz, B, C)]
