"""The 12 ball-bar measuring patterns of thesis Tables 2.2/2.3: names, components, angle grids, eccentricities.

B patterns swivel the B axis over a 0–90° arc (X, Z interpolating); their
trajectories live in the XZ plane and give eccentricities ``ex`` and ``ez``.
C patterns turn the C axis through 360° (X, Y interpolating); they give
``ex`` and ``ey``.  The second letter is the sensitive direction of the bar:
R radial, T tangential, A axial, X/Y/Z Cartesian.

Frame (SPEC §3.2): origin on the C-axis centreline at the table surface, +Z
towards the spindle; commands are the position of the B-axis centre; B rotates
about +Y, C about +Z; the tool points to −Z at B = 0.

Eccentricities are read in the polar-plot frame: ``dL = r0 + e_a·u_a + e_b·u_b``
by least squares, with ``(u_a, u_b) = (sin φ, cos φ)`` giving ``(ex, ez)`` for B
patterns and ``(cos ψ, sin ψ)`` giving ``(ex, ey)`` for C patterns, ψ = θ except
CR with the Table 2.3 geometry (T ball at radius R_C − L_B), where ψ = θ + 180°:
the direction of the bar from the W ball to the T ball, ``T − W = −L_B·(cos θ, sin θ)``
whatever the sign of R_C − L_B (for R_C ≥ L_B as well as for the thesis' R_C < L_B).
The same extractor reads measured traces and simulated ones.  The Tables' commands themselves are the thesis
plug-in's (``plugins/thesis/pattern_tables.py``, its models'); every other command the package gives comes from a
machine's chain (:mod:`mtmcal_bayes.machines.patterns`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

B_PATTERNS = ("BR", "BT", "BA", "BX", "BY", "BZ")
C_PATTERNS = ("CR", "CT", "CA", "CX", "CY", "CZ")
PATTERNS = B_PATTERNS + C_PATTERNS

#: eccentricity components each pattern yields
COMPONENTS: dict[str, tuple[str, str]] = {
    **{p: ("ex", "ez") for p in B_PATTERNS},
    **{p: ("ex", "ey") for p in C_PATTERNS},
}


def mount_conflict(pattern: str, mount_id: str | None, R_C: float) -> str | None:
    """Why ``pattern`` cannot be measured on a mount at radius ``R_C`` (mm), or None if it can.

    B patterns put the W ball on the C axis (Table 2.2), and one mount is one W-ball placement.
    """
    if pattern in B_PATTERNS and R_C != 0:
        which = f"mount {mount_id!r}" if mount_id else "the mount"
        return (f"pattern {pattern} measures with the W ball on the C axis (thesis Table 2.2), but {which} has "
                f"R_C_mm = {R_C:g}: use a mount with R_C_mm = 0")
    return None


#: CR geometries: T ball at radius R_C − L_B (thesis Table 2.3) or R_C + L_B (Fig 2.6)
CR_GEOMETRIES = ("RC-LB", "RC+LB")

#: default angle grids: B patterns over 0–90°, C patterns over one turn
B_ANGLES_DEG = np.linspace(0.0, 90.0, 91)
C_ANGLES_DEG = np.arange(0.0, 360.0, 5.0)


def polar_angle(pattern: str, theta: np.ndarray, cr_geometry: str = "RC-LB") -> np.ndarray:
    """Polar-plot angle ψ (rad) of C-pattern angles θ (rad): θ, or θ + 180° for CR in the Table 2.3
    geometry, where the bar points from W to T along θ + 180° whatever the sign of R_C − L_B."""
    return theta + np.pi if pattern == "CR" and cr_geometry == "RC-LB" else theta


def polar_basis(pattern: str, psi: np.ndarray) -> np.ndarray:
    """Design matrix ``(k, 3)`` of the eccentricity fit: columns 1, u_a, u_b."""
    if pattern in B_PATTERNS:
        return np.c_[np.ones_like(psi), np.sin(psi), np.cos(psi)]
    return np.c_[np.ones_like(psi), np.cos(psi), np.sin(psi)]


@dataclass
class EccentricityFit:
    """Least-squares fit of ΔL traces.

    ``coef`` (..., 3): r0, e_a, e_b (mm); ``components``: names of e_a, e_b;
    ``rms`` (...,): rms residual of the fit, mm.
    """

    coef: np.ndarray
    components: tuple[str, str]
    rms: np.ndarray

    def component(self, name: str) -> np.ndarray:
        return self.coef[..., 1 + self.components.index(name)]


@functools.lru_cache(maxsize=256)
def _pinv(pattern: str, psi_bytes: bytes) -> tuple[np.ndarray, np.ndarray]:
    D = polar_basis(pattern, np.frombuffer(psi_bytes))
    return D, np.linalg.pinv(D)


def fit_eccentricity(pattern: str, psi: np.ndarray, dL: np.ndarray) -> EccentricityFit:
    """Fit ``dL`` of shape ``(..., k)`` over polar angles ``psi`` (k,) in one linear solve."""
    D, pinv = _pinv(pattern, np.ascontiguousarray(psi, dtype=float).tobytes())
    coef = dL @ pinv.T
    resid = dL - coef @ D.T
    return EccentricityFit(coef, COMPONENTS[pattern], np.sqrt(np.mean(resid**2, axis=-1)))
