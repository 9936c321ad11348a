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


def _nc_origin(setup, mount) -> np.ndarray:
    """The NC origin of a set-up and mount, ``(X_T, 0, Z_C + R_B + Z_T)`` mm (Fig 4.30(a)'s frame)."""
    return np.array([setup.X_T, 0.0, mount.Z_C + setup.R_B + setup.Z_T])


@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
def test_each_campaign_run_gets_the_program_of_tables_2_2_and_2_3(cr_geometry):
    """``ncgen --run N`` on the thesis campaign (the engine's selection of a campaign run, in Fig 4.30(a)'s format):
    each run's blocks are the commands the thesis prints (``plugins/thesis/pattern_tables.py``) at the run's set-up
    and mount, over its span by 2.5° (B 0–90°, C one turn), in its NC frame; by 1° with ``step_deg``."""
    from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands

    c = copy.deepcopy(api.campaign_of(None))
    c.ballbar.cr_geometry = cr_geometry
    bb = c.ballbar
    assert len(bb.runs) == 5
    for number, run in enumerate(bb.runs, start=1):
        s, m = bb.setups[run.setup], bb.mounts[run.mount]
        for step in (2.5, 1.0):
            got = _blocks(api.ncgen(run=number, campaign=c, step_deg=None if step == 2.5 else step))
            angle = step * np.arange(round(90.0 / step) + 1 if run.pattern[0] == "B" else round(360.0 / step))
            t = pattern_commands(run.pattern, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, angles_deg=angle,
                                 cr_geometry=cr_geometry)
            want = np.c_[np.c_[t.X, t.Y, t.Z] - _nc_origin(s, m), np.degrees(t.B), np.degrees(t.C)]
            assert got.shape == want.shape
            np.testing.assert_allclose(got, want, rtol=0, atol=0.5e-4 + 1e-9, err_msg=f"run {number} by {step}°")


def test_a_thesis_pattern_over_an_arc_with_a_held_axis():
    """``--arc-deg`` and ``--hold`` on the thesis machine: CR with B held at β puts the B-axis centre at the T ball
    plus R_B·(sin β, 0, cos β) (B turns the tool, −Z at B = 0, about +Y), so the Table 2.3 commands move by
    R_B·(sin β, 0, cos β − 1); BX from −30° to 30° is Table 2.2's formula over that arc."""
    c = api.campaign_of(None)
    bb = c.ballbar
    s, m = bb.setups["RB1"], bb.mounts["C"]
    beta = 30.0
    got = _blocks(api.ncgen("CR", campaign=c, arc_deg=(0.0, 90.0), step_deg=5.0, hold_deg={"B": beta}))
    angle = np.arange(0.0, 90.0 + 1e-9, 5.0)
    b = np.deg2rad(beta)
    xyz = _table("CR", angle, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, cr_geometry=bb.cr_geometry)
    xyz = xyz + s.R_B * np.array([np.sin(b), 0.0, np.cos(b) - 1.0]) - _nc_origin(s, m)
    np.testing.assert_allclose(got, np.c_[xyz, np.full(len(angle), beta), angle], rtol=0, atol=0.5e-4 + 1e-9)
    got = _blocks(api.ncgen("BX", campaign=c, arc_deg=(-30.0, 30.0)))
    angle = np.arange(-30.0, 30.0 + 1e-9, 2.5)
    m = bb.mounts["B"]
    xyz = _table("BX", angle, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, cr_geometry=bb.cr_geometry)
    np.testing.assert_allclose(got, np.c_[xyz - _nc_origin(s, m), angle, np.zeros(len(angle))], rtol=0,
                               atol=0.5e-4 + 1e-9)


def test_a_planned_run_with_a_bar_of_its_own_is_programmed_for_that_bar(tmp_path):
    """A planned run's ``length_mm`` (a bar other than the campaign's) is its program's L_B: the blocks of ``--run``
    for it are Table 2.2's with L_B = 150 mm, not the campaign's 100 mm."""
    import re

    from mtmcal_bayes.datasets import builtin_campaign_text
    from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands

    text = "\n".join(ln for ln in builtin_campaign_text()[0].splitlines()
                     if not ln.startswith(("alternative_", "trace_"))) + "\n"
    path = tmp_path / "planned.toml"
    path.write_text(re.sub(r"^(e[xyz]_um = \[.*\]\n)+", "planned = true\nrepeats = 3\nlength_mm = 150.0\n", text,
                           count=1, flags=re.MULTILINE), encoding="utf-8")
    c = api.campaign_of(path)
    (planned,) = c.ballbar.planned
    assert planned.pattern == "BX" and planned.length == 150.0 and c.ballbar.length == 100.0
    got = _blocks(api.ncgen(run=len(c.ballbar.runs) + 1, campaign=c))
    s, m = c.ballbar.setups[planned.setup], c.ballbar.mounts[planned.mount]
    angle = 2.5 * np.arange(37)
    t = pattern_commands("BX", R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=150.0, angles_deg=angle)
    want = np.c_[np.c_[t.X, t.Y, t.Z] - _nc_origin(s, m), angle, np.zeros(len(angle))]
    np.testing.assert_allclose(got, want, rtol=0, atol=0.5e-4 + 1e-9)
