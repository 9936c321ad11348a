"""The thesis machine's measuring programs (``ncgen``, Fig 4.30(a)'s format): the engine's commands of every thesis
pattern against Tables 2.2/2.3 written out here, independently of both the engine and the thesis' own module."""

import copy
import math

import numpy as np
import pytest

from mtmcal_bayes import api

PATTERNS = ("BR", "BT", "BA", "BX", "BY", "BZ", "CR", "CT", "CA", "CX", "CY", "CZ")


def _table(pattern: str, angle_deg: np.ndarray, *, R_B, Z_C, R_C, L_B, cr_geometry) -> np.ndarray:
    """X, Y, Z (k, 3) of the B-axis centre in the C-table frame, thesis Table 2.2 (B, angle φ) and 2.3 (C, θ)."""
    a = np.deg2rad(angle_deg)
    s, c, z = np.sin(a), np.cos(a), np.zeros_like(a)
    table = {
        "BR": ((L_B + R_B) * s, z, Z_C + (L_B + R_B) * c),
        "BT": (math.hypot(R_B, L_B) * np.sin(a + math.atan2(L_B, R_B)), z,
               Z_C + math.hypot(R_B, L_B) * np.cos(a + math.atan2(L_B, R_B))),
        "BA": (R_B * s, z + L_B, Z_C + R_B * c),
        "BY": (R_B * s, z + L_B, Z_C + R_B * c),
        "BX": (L_B + R_B * s, z, Z_C + R_B * c),
        "BZ": (R_B * s, z, L_B + Z_C + R_B * c),
        "CR": ((R_C - L_B if cr_geometry == "RC-LB" else R_C + L_B) * c,
               (R_C - L_B if cr_geometry == "RC-LB" else R_C + L_B) * s, z + Z_C + R_B),
        "CT": (math.hypot(R_C, L_B) * np.cos(a + math.atan2(L_B, R_C)),
               math.hypot(R_C, L_B) * np.sin(a + math.atan2(L_B, R_C)), z + Z_C + R_B),
        "CA": (R_C * c, R_C * s, z + Z_C + R_B + L_B),
        "CZ": (R_C * c, R_C * s, z + Z_C + R_B + L_B),
        "CX": (L_B + R_C * c, R_C * s, z + Z_C + R_B),
        "CY": (R_C * c, L_B + R_C * s, z + Z_C + R_B),
    }
    return np.stack(table[pattern], axis=-1)


def _blocks(text: str) -> np.ndarray:
    """X, Y, Z, B, C (k, 5) of a program's G01 blocks."""
    return np.array([[float(w[1:]) for w in line.split()[1:6]] for line in text.splitlines()
                     if line.startswith("G01")])


@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
@pytest.mark.parametrize("pattern", PATTERNS)
def test_every_thesis_program_moves_as_tables_2_2_and_2_3(pattern, cr_geometry):
    """Every pattern at both set-ups and on both placements (a B pattern on the C placement too: its W ball stays on
    the C axis), over its default range by 2.5° and by 9°: the blocks are the table's commands shifted to the NC
    origin ``(X_T, 0, Z_C + R_B + Z_T)``, to the programs' 4 decimals."""
    c = copy.deepcopy(api.campaign_of(None))
    c.ballbar.cr_geometry = cr_geometry
    bb = c.ballbar
    for sid, s in bb.setups.items():
        for mid, m in bb.mounts.items():
            for step in (2.5, 9.0):
                got = _blocks(api.ncgen(pattern, campaign=c, setup=sid, mount=mid, step_deg=step))
                n = round((90.0 if pattern[0] == "B" else 360.0) / step) + (pattern[0] == "B")
                angle = step * np.arange(n)
                xyz = _table(pattern, angle, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, cr_geometry=cr_geometry)
                xyz = xyz - np.array([s.X_T, 0.0, m.Z_C + s.R_B + s.Z_T])
                rotary = np.c_[angle, np.zeros(n)] if pattern[0] == "B" else np.c_[np.zeros(n), angle]
                assert got.shape == (n, 5)
                np.testing.assert_allclose(got, np.c_[xyz, rotary], rtol=0, atol=0.5e-4 + 1e-9,
                                           err_msg=f"{pattern} {sid}/{mid} by {step}°")
