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


def mount_conflict(pattern: str, mount_id: str | None, R_C: float) -> str | None:
    """Why ``pattern`` cannot be measured on a mount at radius ``R_C`` (mm), or None if it can.

    B patterns put the W ball on the C axis (Table 2.2), and one mount is one W-ball placement.
    """
    if pattern in B_PATTERNS and R_C != 0:
        which = f"mount {mount_id!r}" if mount_id else "the mount"
        return (f"pattern {pattern} measures with the W ball on the C axis (thesis Table 2.2), but {which} has "
                f"R_C_mm = {R_C:g}: use a mount with R_C_mm = 0")
    return None
