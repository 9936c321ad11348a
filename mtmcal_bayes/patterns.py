"""The 12 ball-bar measuring patterns of thesis Tables 2.2/2.3 and their components.

B patterns swivel the B axis over a 0–90° arc (X, Z interpolating); their
trajectories live in the XZ plane and give eccentricities ``ex`` and ``ez``.
C patterns turn the C axis through 360° (X, Y interpolating); they give
``ex`` and ``ey``.  The second letter is the sensitive direction of the bar:
R radial, T tangential, A axial, X/Y/Z Cartesian.
"""

from __future__ import annotations

B_PATTERNS = ("BR", "BT", "BA", "BX", "BY", "BZ")
C_PATTERNS = ("CR", "CT", "CA", "CX", "CY", "CZ")
PATTERNS = B_PATTERNS + C_PATTERNS

#: eccentricity components each pattern yields
COMPONENTS: dict[str, tuple[str, str]] = {
    **{p: ("ex", "ez") for p in B_PATTERNS},
    **{p: ("ex", "ey") for p in C_PATTERNS},
}
