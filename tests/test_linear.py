"""The linear model against SPEC §3.1, term by term."""

import numpy as np
import pytest

from mtmcal_bayes import LinearModel, ParameterSpace
from mtmcal_bayes.io import parse_campaign

from .conftest import DATA


def spec_eccentricity(pattern, comp, d, setup, mount):
    """SPEC §3.1 written out as printed; ``d`` maps parameter base names to values (mm, rad)."""
    R_B, Z_T, X_T, Z_C, R_C = setup.R_B, setup.Z_T, setup.X_T, mount.Z_C, mount.R_C
    return {
        ("BX", "ex"): d["dz_BT"] + d["zT"] - d["dRB"],
        ("BX", "ez"): d["dx_BT"] + R_B * d["beta_XB"] + d["xT"],
        ("BY", "ex"): -R_B * d["gamma_XB"],
        ("BY", "ez"): +R_B * d["alpha_XB"],
        ("CR", "ex"): d["dx_BT"] - d["dx_CZ"] - Z_T * d["beta_XB"] + Z_C * d["beta_CZ"] + d["xT"],
        ("CR", "ey"): (-d["dy_CZ"] + Z_T * (d["alpha_XB"] + d["alpha_BT"]) - Z_C * d["alpha_CZ"]
                       - X_T * d["gamma_XB"] + d["yT"]),
        ("CA", "ex"): +R_C * d["beta_CZ"],
        ("CA", "ey"): -R_C * d["alpha_CZ"],
    }[(pattern, comp)]


def _spec_predict(model, theta):
    space, bb = model.space, model.campaign.ballbar
    out = []
    for key in model.observations.keys:
        d = {p.base: theta[space.index(p.name)] for p in space.parameters
             if p.owner in (None, key.setup, key.mount)}
        out.append(spec_eccentricity(key.pattern, key.component, d, bb.setups[key.setup], bb.mounts[key.mount]))
    return np.array(out)


def test_each_parameter_alone(thesis):
    """Every column of the design matrix: one parameter at a time, all others zero."""
    model = LinearModel(thesis)
    for j, p in enumerate(model.space.parameters):
        theta = np.zeros(len(model.space))
        theta[j] = 1e-5 if p.kind == "angle" else 0.01
        np.testing.assert_allclose(model.predict(theta), _spec_predict(model, theta), rtol=1e-12, atol=1e-15,
                                   err_msg=p.name)


def test_random_batch_vectorised(thesis):
    model = LinearModel(thesis)
    rng = np.random.default_rng(1)
    theta = rng.normal(size=(200, len(model.space))) * model.space.display_scale() * 50
    pred = model.predict(theta)
    assert pred.shape == (200, len(model.observations))
    for i in (0, 57, 199):
        np.testing.assert_allclose(pred[i], _spec_predict(model, theta[i]), rtol=1e-12, atol=1e-15)


def test_thesis_sensitivities(thesis):
    """Spot values: R_B·beta_XB for 1″ at R_B = 356.3945 mm is 1.728 µm."""
    model = LinearModel(thesis)
    theta = model.space.vector({"beta_XB": np.pi / 648000})
    row = model.observations.labels.index("ez_BX@RB1/B")
    assert model.predict(theta)[row] * 1e3 == pytest.approx(356.3945 * np.pi / 648000 * 1e3)


def test_w_ball_offsets_do_not_enter(thesis):
    model = LinearModel(thesis)
    for p in model.space.parameters:
        if p.group == "mount":
            assert not model.design[:, model.space.index(p.name)].any(), p.name


def test_parameter_space_layout(thesis):
    space = ParameterSpace.for_campaign(thesis)
    assert len(space) == 13 + 2 * 4 + 2 * 3
    assert space.names[:2] == ["dx_BT", "dz_BT"]
    assert "xT[RB2]" in space.names and "zW[C]" in space.names


def test_patterns_beyond_the_thesis_get_rows():
    """BZ has no thesis relation: its row comes from the htm-thesis Jacobian (tested in test_kinematic)."""
    text = (DATA / "minimal_one_repeat.toml").read_text().replace('pattern = "BY"', 'pattern = "BZ"')
    model = LinearModel(parse_campaign(text, "bz.toml"))
    row = model.observations.labels.index("ez_BZ@RB1/B")
    assert model.design[row, model.space.index("dz_BT")] == pytest.approx(1.0, abs=1e-6)


def test_only_the_runs_without_a_relation_are_simulated_and_their_rows_are_the_whole_campaigns():
    """The Jacobian rows of the runs the thesis gives no relation for (BZ, BT, CZ here, among thesis patterns, CZ on
    a mount whose W ball a CR run places) are those of the htm-thesis Jacobian of the whole campaign, to round-off
    (1e-12 of the largest coefficient).  test_properties checks the same on random campaigns through the
    small-scale limit."""
    from mtmcal_bayes.campaign import Run
    from mtmcal_bayes.models import jacobian
    from mtmcal_bayes.plugins.thesis.kinematic import HTMModel
    from mtmcal_bayes.plugins.thesis.linear import LEFT_OUT
    from mtmcal_bayes.patterns import COMPONENTS

    text = (DATA / "minimal_one_repeat.toml").read_text().replace('pattern = "BY"', 'pattern = "BZ"')
    campaign = parse_campaign(text, "bz.toml")
    bb = campaign.ballbar
    bb.runs = bb.runs + [Run(p, run.setup, run.mount, {c: np.zeros(1) for c in COMPONENTS[p]})
                         for p, run in (("BT", bb.runs[0]), ("CZ", bb.runs[-1]))]
    model = LinearModel(campaign)
    whole = jacobian(HTMModel(campaign, "htm-thesis", model.space))
    for name in LEFT_OUT:  # the squareness of the linear axes, left out by the linear model
        whole[:, model.space.index(name)] = 0.0
    beyond = [i for i, k in enumerate(model.observations.keys) if k.pattern in ("BZ", "BT", "CZ")]
    assert len(beyond) >= 3
    np.testing.assert_allclose(model.design[beyond], whole[beyond], rtol=0, atol=1e-12 * np.abs(whole[beyond]).max())
