"""The thesis' program format: measuring NC programs of its ball-bar patterns (Tables 2.2/2.3, Fig 4.30(a)).

The pattern commands (B-axis centre in the C-table frame, :mod:`mtmcal_bayes.patterns`)
are shifted into the NC frame so that the first block sits at ``(x0, y0, z0)``;
without them, the NC origin of a campaign setup is used: ``(X_T, 0, Z_C + R_B + Z_T)``.
Thesis Fig 4.30(a) is BX from R_B = 356.3945 mm, x0 = −390, z0 = −112.2605 mm,
B steps of 2.5/9°, F2000: X = x0 + R_B·sin B, Z = z0 − R_B·(1 − cos B).
"""

from __future__ import annotations

import numpy as np

from ...errors import ParameterError
from ...patterns import B_PATTERNS, PATTERNS, pattern_commands
from ...io.gcode import block_line


def pattern_program(pattern: str, R_B: float, step_deg: float, n: int | None = None, *, L_B: float = 100.0,
                    Z_C: float = 0.0, R_C: float = 0.0, start: tuple | None = None, origin: tuple | None = None,
                    feed: float | None = None, cr_geometry: str = "RC-LB") -> list[str]:
    """Motion blocks of ``pattern``: ``n`` blocks from angle 0 in steps of ``step_deg`` (deg).

    ``start`` (x0, y0, z0) places the first block; else ``origin`` (model-frame NC origin, mm) is subtracted.
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
    cmd = pattern_commands(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B, angles_deg=angles, cr_geometry=cr_geometry)
    xyz = np.c_[cmd.X, cmd.Y, cmd.Z]
    if start is not None:
        xyz = xyz - xyz[0] + np.asarray(start, dtype=float)
    elif origin is not None:
        xyz = xyz - np.asarray(origin)
    B = np.degrees(cmd.B)
    C = np.degrees(cmd.C)
    return [block_line((x, y, z, b, c), feed=feed) for (x, y, z), b, c in zip(xyz, B, C)]
