"""Touch probe: Eqs 5.1–5.19 on Table 5.2, and the sphere fit of DPRNT output."""

import numpy as np
import pytest

from mtmcal_bayes import fit_sphere, identify, read_dprnt
from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.errors import InputError, MtmcalError
from mtmcal_bayes.io.dprnt import parse_dprnt

DPRNT = data_path("fig5_13_dprnt_output.txt")


def test_c_axis_angles_not_reproducing_table_5_3(thesis):
    probe = identify(thesis).probe
    assert probe["beta_CZ"].display == pytest.approx(-30.46, abs=0.005)
    assert probe["alpha_CZ"].display == pytest.approx(-4.40, abs=0.005)
    assert probe["beta_CZ"].reported_display == pytest.approx(-26.28)
    assert probe["alpha_CZ"].reported_display == pytest.approx(-3.7)
    assert probe["beta_CZ"].reproduced is False and probe["alpha_CZ"].reproduced is False


def test_b_axis_values_carry_nominal_assumption(thesis):
    result = identify(thesis)
    for name in ("dx_BT", "dz_BT", "gamma_XB", "alpha_XB"):
        assert "nominal" in result.probe[name].note
    assert any("nominal positions" in a and "short" in a for a in result.assumptions)


def test_dprnt_sphere_fit_fig_5_13():
    pts = read_dprnt(DPRNT)
    assert pts.xyz.shape == (21, 3) and pts.declared == 40
    fit = fit_sphere(pts.xyz)
    np.testing.assert_allclose(fit.centre, [-390.2175, -0.0005, -472.4176], atol=1e-3)
    assert fit.radius == pytest.approx(7.9106, abs=1e-3)


def test_sphere_fit_recovers_known_sphere():
    rng = np.random.default_rng(3)
    centre, r = np.array([-390.1, 2.0, -472.3]), 12.7
    u = rng.normal(size=(30, 3))
    u[:, 2] = np.abs(u[:, 2])  # upper hemisphere only, as probed
    pts = centre + (r + 3.0) * u / np.linalg.norm(u, axis=1, keepdims=True)
    fit = fit_sphere(pts + rng.normal(0, 1e-4, pts.shape), stylus_radius=3.0)
    np.testing.assert_allclose(fit.centre, centre, atol=2e-4)
    assert fit.radius == pytest.approx(r, abs=2e-4)
    assert fit.rms < 2e-4


def test_sphere_fit_degenerate():
    with pytest.raises(MtmcalError, match="at least 4"):
        fit_sphere(np.zeros((3, 3)))
    flat = np.c_[np.random.default_rng(0).normal(size=(10, 2)), np.zeros(10)]
    with pytest.raises(MtmcalError, match="do not determine a sphere"):
        fit_sphere(flat)


def test_dprnt_bad_line_names_line():
    with pytest.raises(InputError, match="line 3"):
        parse_dprnt("%\nX1 Y2 Z3\nX1 Y2 Zabc\n", "f.txt")
    with pytest.raises(InputError, match="line 2: point without Z"):
        parse_dprnt("%\nX1 Y2\n", "f.txt")
    with pytest.raises(InputError, match="not a finite"):
        parse_dprnt("X1 Y2 Znan\n", "f.txt")
