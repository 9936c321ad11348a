"""Raw ball-bar traces: reading ``angle_deg, dL_um, direction`` CSV files and extracting eccentricities.

Each direction (CW, CCW) is fitted separately with the same least-squares
extractor the kinematic models use, and the two are averaged (thesis Sec 4.3.2);
a file must hold both.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass

import numpy as np

from .. import units
from ..errors import InputError
from ..patterns import B_PATTERNS, COMPONENTS, fit_eccentricity, polar_angle
from .textfiles import read_user_text

DIRECTIONS = ("CW", "CCW")


@dataclass
class TraceExtraction:
    """Eccentricities of one trace file: ``values`` component -> mm (CW/CCW average), fit rms per direction, mm."""

    values: dict[str, float]
    rms: dict[str, float]


def read_trace(path, pattern: str, L_B: float, cr_geometry: str = "RC-LB") -> TraceExtraction:
    """Read a trace CSV and extract the pattern's eccentricities; bad content names file and line."""
    text = read_user_text(path, "trace CSV file")
    src = str(path)
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError(src, None, "empty file (expected columns angle_deg, dL_um, direction)")
    header = [c.strip() for c in rows[0]]
    if header != ["angle_deg", "dL_um", "direction"]:
        raise InputError(src, "line 1", f"expected the header angle_deg,dL_um,direction, got {','.join(header)!r}")
    data: dict[str, list[tuple[float, float]]] = {d: [] for d in DIRECTIONS}
    for no, r in enumerate(rows[1:], start=2):
        if len(r) != 3:
            raise InputError(src, f"line {no}", f"expected 3 columns, got {len(r)}")
        try:
            a, dl = float(r[0]), float(r[1])
        except ValueError:
            raise InputError(src, f"line {no}", f"not a number: {r[0].strip()!r} or {r[1].strip()!r}") from None
        if not (math.isfinite(a) and math.isfinite(dl)):
            raise InputError(src, f"line {no}", "NaN or infinite value")
        d = r[2].strip().upper()
        if d not in DIRECTIONS:
            raise InputError(src, f"line {no}", f"direction must be CW or CCW, got {r[2].strip()!r}")
        if abs(a) > 360.0:
            raise InputError(src, f"line {no}", f"angle_deg = {a:g} is outside -360…360°")
        if units.to_internal(abs(dl), "um") >= L_B:
            raise InputError(src, f"line {no}", f"dL_um = {dl:g} is not below the bar length "
                             f"L_B = {L_B:g} mm: not a ball-bar reading")
        data[d].append((a, dl))
    fits = {}
    for d, pts in data.items():
        if not pts:
            continue
        arr = np.array(pts)
        span = np.ptp(arr[:, 0])
        if pattern in B_PATTERNS and span > 180.0:
            raise InputError(src, None, f"{d} trace spans {span:g}°, more than the 180° a B pattern can swing "
                             "(0–90° in the thesis): is this a C-pattern trace?")
        if len(arr) < 4 or span < (30.0 if pattern in B_PATTERNS else 90.0):
            raise InputError(src, None, f"{d} trace too short to fit ({len(arr)} points over {span:g}°)")
        psi = polar_angle(pattern, np.deg2rad(arr[:, 0]), cr_geometry)
        fits[d] = fit_eccentricity(pattern, psi, units.to_internal(arr[:, 1], "um"))
    if not fits:
        raise InputError(src, None, "no data rows")
    missing = [d for d in DIRECTIONS if d not in fits]
    if missing:  # each repeat is the mean of a CW and a CCW run (thesis Sec 4.3.2); one alone is not guessed
        raise InputError(src, None, f"no {missing[0]} rows: a trace needs both directions, CW and CCW "
                         "(their mean cancels the direction-dependent errors)")
    values = {c: float(np.mean([f.component(c) for f in fits.values()])) for c in COMPONENTS[pattern]}
    return TraceExtraction(values, {d: float(f.rms) for d, f in fits.items()})
