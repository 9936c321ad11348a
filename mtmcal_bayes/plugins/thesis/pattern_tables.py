"""The axis commands of thesis Tables 2.2 (B patterns) and 2.3 (C patterns), as printed: the commands a thesis-format
campaign states for its runs (:func:`.translation.table_commands`), which every ball-bar model of it evaluates.  The
engine's commands of the same patterns come from the machine's chain (:func:`mtmcal_bayes.machines.patterns.
pattern_commands`, through :mod:`.translation`: programs, feasibility, reading frames); they equal these to rounding
(~1e-13 mm, ``tests/test_chain.py``, ``tests/test_thesis_programs.py``), and rounding decides a tie between two of
``plan``'s candidate runs, so the thesis' numbers are computed with these bits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG, CR_GEOMETRIES, polar_angle


@dataclass(frozen=True)
class Commands:
    """Axis commands of one pattern over its angle grid, each shape ``(k,)``.

    X, Y, Z in mm (B-axis centre), B and C in rad, ``psi`` the polar-plot angle
    in rad used for the eccentricity fit.
    """

    X: np.ndarray
    Y: np.ndarray
    Z: np.ndarray
    B: np.ndarray
    C: np.ndarray
    psi: np.ndarray


def pattern_commands(pattern: str, *, R_B: float, Z_C: float, R_C: float, L_B: float,
                     angles_deg: np.ndarray | None = None, cr_geometry: str = "RC-LB") -> Commands:
    """Commands of thesis Tables 2.2 (B patterns) and 2.3 (C patterns), programmed values in mm.

    ``R_B`` tool length, ``Z_C``/``R_C`` height and radius of the W ball, ``L_B`` bar length (mm);
    ``angles_deg`` the B or C angles (default :data:`B_ANGLES_DEG` / :data:`C_ANGLES_DEG`).
    """
    if pattern in B_PATTERNS:
        phi = np.deg2rad(B_ANGLES_DEG if angles_deg is None else np.asarray(angles_deg, float))
        s, c, zero = np.sin(phi), np.cos(phi), np.zeros_like(phi)
        if pattern == "BR":
            X, Y, Z = (L_B + R_B) * s, zero, Z_C + (L_B + R_B) * c
        elif pattern == "BT":
            R_BT, a = np.hypot(R_B, L_B), np.arctan2(L_B, R_B)
            X, Y, Z = R_BT * np.sin(phi + a), zero, Z_C + R_BT * np.cos(phi + a)
        elif pattern in ("BA", "BY"):  # the thesis notes these two motions are the same
            X, Y, Z = R_B * s, zero + L_B, Z_C + R_B * c
        elif pattern == "BX":
            X, Y, Z = L_B + R_B * s, zero, Z_C + R_B * c
        else:  # BZ
            X, Y, Z = R_B * s, zero, L_B + Z_C + R_B * c
        return Commands(X, Y, Z, phi, zero, phi)

    th = np.deg2rad(C_ANGLES_DEG if angles_deg is None else np.asarray(angles_deg, float))
    s, c, zero = np.sin(th), np.cos(th), np.zeros_like(th)
    Zr = Z_C + R_B + zero
    if pattern == "CR":
        if cr_geometry not in CR_GEOMETRIES:
            raise ValueError(f"unknown CR geometry {cr_geometry!r}")
        radius = R_C - L_B if cr_geometry == "RC-LB" else R_C + L_B
        X, Y, Z = radius * c, radius * s, Zr
    elif pattern == "CT":
        R_CT, a = np.hypot(R_C, L_B), np.arctan2(L_B, R_C)
        X, Y, Z = R_CT * np.cos(th + a), R_CT * np.sin(th + a), Zr
    elif pattern in ("CA", "CZ"):  # the same motion
        X, Y, Z = R_C * c, R_C * s, Zr + L_B
    elif pattern == "CX":
        X, Y, Z = L_B + R_C * c, R_C * s, Zr
    else:  # CY
        X, Y, Z = R_C * c, L_B + R_C * s, Zr
    return Commands(X, Y, Z, zero, th, polar_angle(pattern, th, cr_geometry))


