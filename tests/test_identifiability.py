"""Identifiability computed from a campaign's Jacobian (SPEC §19): what the data determine, alone, in
combination, or not at all.

The thesis machine is the check that nothing thesis-specific is needed; a hand-made Jacobian with made-up
names is the check of the classification itself.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.errors import ParameterError
from mtmcal_bayes.inference.identifiability import identifiability
from mtmcal_bayes.inference.log_posterior import SAMPLED_DEVIATIONS
from mtmcal_bayes.models import jacobian, make_model
from mtmcal_bayes.parameters import Parameter, ParameterSpace

CENTRED = ("xT", "yT", "zT")  # the thesis' centring check (Sec 4.2.2) fixes the T ball before the runs
THESIS_NINE = {"dx_BT", "alpha_BT", "alpha_XB", "beta_XB", "gamma_XB", "dx_CZ", "dy_CZ", "alpha_CZ", "beta_CZ"}


def _vector(weights: dict[str, float], names: list[str]) -> np.ndarray:
    c = np.zeros(len(names))
    for n, w in weights.items():
        c[names.index(n)] = w
    return c


def _estimable(jac, space, weights, known=()) -> bool:
    """Whether (c, 0) lies in the row space of the free columns of ``jac`` (display units): the definition."""
    free = [i for i, p in enumerate(space.parameters) if p.name not in known and p.base not in known]
    a = (np.asarray(jac) * space.display_scale())[:, free]
    c = _vector(weights, [space.names[i] for i in free])
    coef, *_ = np.linalg.lstsq(a.T, c, rcond=None)
    return np.linalg.norm(a.T @ coef - c) < 1e-6 * np.linalg.norm(c)


def _check_consistent(result, jac, space, known=()):
    """Every stated quantity is estimable; the deviations named are each classified once."""
    for d in result.determined:
        assert _estimable(jac, space, {d: 1.0}, known), d
    for comb in result.combinations:
        assert _estimable(jac, space, comb.weights, known), comb.name
        assert next(iter(comb.weights.values())) == 1.0
    for d in result.undetermined:
        assert not _estimable(jac, space, {d: 1.0}, known), d
    in_comb = {d for c in result.combinations for d in c.weights}
    assert not (in_comb & set(result.determined)) and not (in_comb & set(result.undetermined))


# ---------------------------------------------------------------------------------------------------------------
# a hand-made Jacobian: known null space, names of no machine


class _Space:
    """A parameter space with made-up names (the module needs only names, groups, units and display scales)."""

    def __init__(self, spec):
        self.parameters = tuple(Parameter(n, n.split("[")[0], g, None, k) for n, g, k in spec)
        self.names = [p.name for p in self.parameters]

    def __len__(self):
        return len(self.parameters)

    def display_scale(self):
        return np.array([units.to_internal(1.0, p.unit) for p in self.parameters])


SYNTHETIC = _Space([
    ("p", "deviation", "length"),   # measured alone: determined
    ("r", "deviation", "angle"),    # only as q + 2 µm/″·r
    ("q", "deviation", "length"),
    ("s", "deviation", "length"),   # always with the nuisance n1: undetermined
    ("t", "deviation", "angle"),    # in no measurement: undetermined
    ("u", "deviation", "length"),   # with n2, and n2 is measured alone: determined
    ("v", "deviation", "angle"),    # v, w, x only through their differences: two combinations
    ("w", "deviation", "angle"),
    ("x", "deviation", "angle"),
    ("n1[a]", "setup", "length"),
    ("n2[a]", "setup", "length"),
])


@pytest.fixture(scope="module")
def synthetic_jac():
    """(m, p) in internal units: a random mix (seeded) of the rows below, in display units, plus redundant rows."""
    names = SYNTHETIC.names
    rows = np.array([_vector(w, names) for w in (
        {"p": 1.0}, {"q": 1.0, "r": 2.0}, {"s": 1.0, "n1[a]": 1.0}, {"u": 1.0, "n2[a]": 1.0}, {"n2[a]": 1.0},
        {"w": 1.0, "v": -1.0}, {"x": 1.0, "v": -1.0})])
    rng = np.random.default_rng(20240519)
    mixed = rng.normal(size=(12, len(rows))) @ rows  # 12 measurements, rank 7
    return mixed / SYNTHETIC.display_scale()


def test_synthetic_classification(synthetic_jac):
    result = identifiability(synthetic_jac, SYNTHETIC)
    assert result.determined == ("p", "u")
    assert result.undetermined == ("s", "t")
    (qr, *vwx) = result.combinations
    assert qr.name == "q + 2 µm/″·r" and qr.unit == "um"
    assert list(qr.weights) == ["q", "r"] and qr.weights["r"] == pytest.approx(2.0, rel=1e-9)
    assert [c.name for c in vwx] == ["x − v", "w − v"]
    assert [c.unit for c in vwx] == ["arcsec", "arcsec"]
    assert vwx[0].weights == pytest.approx({"x": 1.0, "v": -1.0})
    _check_consistent(result, synthetic_jac, SYNTHETIC)
    assert json.loads(json.dumps(result.as_dict()))["combinations"][0] == {
        "name": qr.name, "weights": qr.weights, "unit": "um"}


def test_synthetic_known_and_subset(synthetic_jac):
    # n1 known (fixed by the set-up): s is measured through s + n1
    assert "s" in identifiability(synthetic_jac, SYNTHETIC, known=("n1",)).determined
    # r classified alone, q left free: r enters only with q, so on its own it is not determined
    sub = identifiability(synthetic_jac, SYNTHETIC, deviations=["p", "r"])
    assert sub.determined == ("p",) and sub.undetermined == ("r",) and sub.combinations == ()
    with pytest.raises(ParameterError, match="deviations"):
        identifiability(synthetic_jac, SYNTHETIC, deviations=["n1[a]"])
    with pytest.raises(ParameterError, match="jac"):
        identifiability(synthetic_jac[:, 1:], SYNTHETIC)


def test_noise_below_rtol_is_zero(synthetic_jac):
    """A central-difference-sized error (1e-10 relative) does not make a null direction estimable."""
    rng = np.random.default_rng(7)
    noisy = synthetic_jac + 1e-10 * np.abs(synthetic_jac).max() * rng.normal(size=synthetic_jac.shape)
    result = identifiability(noisy, SYNTHETIC)
    assert result.determined == ("p", "u") and result.undetermined == ("s", "t")
    assert [c.name for c in result.combinations] == ["q + 2 µm/″·r", "x − v", "w − v"]


# ---------------------------------------------------------------------------------------------------------------
# the thesis machine


def _one_tool_length(campaign):
    """The campaign without its second tool length (setup RB2 and its CR′ run)."""
    bb = campaign.ballbar
    return dataclasses.replace(campaign, ballbar=dataclasses.replace(
        bb, setups={"RB1": bb.setups["RB1"]}, runs=[r for r in bb.runs if r.setup != "RB2"]))


@pytest.fixture(scope="module")
def cases(thesis):
    """(campaign, model, deviations) -> (jacobian, space), built once."""
    out = {}
    for tag, campaign in (("thesis", thesis), ("one tool", _one_tool_length(thesis))):
        for model in ("htm-literal", "linear"):
            for devs in ("all", "sampled"):
                space = ParameterSpace.for_campaign(campaign, None if devs == "all" else SAMPLED_DEVIATIONS)
                m = make_model(model, campaign, space)
                out[tag, model, devs] = jacobian(m), m.space
    return out


@pytest.mark.parametrize("model", ["htm-literal", "linear"])
def test_thesis_with_the_t_ball_centred(cases, model):
    """The thesis' deviations (squareness not estimated) with the T ball centred: nine determined one by one,
    dx_CZ − dx_BT among what is estimable (with dx_BT in ez_BX, Table 2.6, both are determined), dz_BT not at
    all: the tool-length error dRB moves BX's ex the same way."""
    jac, space = cases["thesis", model, "sampled"]
    result = identifiability(jac, space, known=CENTRED)
    assert set(result.determined) == THESIS_NINE
    assert result.combinations == () and result.undetermined == ("dz_BT",)
    assert _estimable(jac, space, {"dx_CZ": 1.0, "dx_BT": -1.0}, CENTRED)
    _check_consistent(result, jac, space, CENTRED)
    # the confounder is the tool-length error: known, it lets dz_BT be determined
    assert "dz_BT" in identifiability(jac, space, known=CENTRED + ("dRB",)).determined


@pytest.mark.parametrize("model", ["htm-literal", "linear"])
def test_thesis_data_alone(cases, model):
    """Every nuisance term free: the T-ball offsets of each tool setup absorb what its CR run says about the
    spindle side, so the ball bar alone leaves dx_BT, alpha_BT, dy_CZ and dz_BT to their priors, and the second
    tool length adds nothing."""
    jac, space = cases["thesis", model, "sampled"]
    result = identifiability(jac, space)
    assert {"dx_BT", "dz_BT", "alpha_BT", "dy_CZ"} <= set(result.undetermined)
    if model == "linear":
        assert set(result.determined) == {"alpha_XB", "gamma_XB", "alpha_CZ", "beta_CZ"}
        (comb,) = result.combinations  # ez_BX − ex_CR: dx_CZ + (R_B + Z_T)·beta_XB
        assert comb.name == "dx_CZ + 2.272 µm/″·beta_XB"
    else:  # htm-literal's lever for beta_XB is R_B in BX and CR alike: ez_BX − ex_CR is dx_CZ (+ beta_CZ)
        assert set(result.determined) == {"alpha_XB", "gamma_XB", "dx_CZ", "alpha_CZ", "beta_CZ"}
        assert result.undetermined == ("dx_BT", "dz_BT", "alpha_BT", "beta_XB", "dy_CZ")
    _check_consistent(result, jac, space)
    one = identifiability(*cases["one tool", model, "sampled"])
    assert (one.determined, one.undetermined) == (result.determined, result.undetermined)
    assert [c.name for c in one.combinations] == [c.name for c in result.combinations]


def test_thesis_squareness_htm_literal(cases):
    """With the linear axes' squareness free (the thesis' rigid M_XY, M_YZ), the ball bar cannot tell alpha_YZ,
    beta_YZ from the B and C axes' tilts and says nothing of gamma_XY."""
    jac, space = cases["thesis", "htm-literal", "all"]
    result = identifiability(jac, space, known=CENTRED)
    assert result.determined == ("dx_BT", "alpha_BT", "gamma_XB")
    assert result.undetermined == ("dz_BT", "gamma_XY")
    assert {c.name for c in result.combinations} == {
        "alpha_CZ + alpha_XB", "dy_CZ + 0.3177 µm/″·alpha_XB", "alpha_YZ + alpha_XB",
        "beta_CZ + beta_XB", "dx_CZ − 0.3177 µm/″·beta_XB", "beta_YZ + beta_XB"}
    _check_consistent(result, jac, space, CENTRED)
    alone = identifiability(jac, space)  # every nuisance term free
    assert alone.determined == ("gamma_XB",)
    assert alone.undetermined == ("dx_BT", "dz_BT", "alpha_BT", "beta_XB", "gamma_XY", "dy_CZ")
    assert {c.name for c in alone.combinations} == {
        "alpha_CZ + alpha_XB", "alpha_YZ + alpha_XB", "beta_CZ − beta_YZ", "dx_CZ + 0.3177 µm/″·beta_YZ"}


def test_thesis_squareness_linear(cases):
    """The thesis relations have no squareness terms: the linear model leaves all three to their priors."""
    jac, space = cases["thesis", "linear", "all"]
    result = identifiability(jac, space, known=CENTRED)
    assert set(result.determined) == THESIS_NINE
    assert result.undetermined == ("dz_BT", "gamma_XY", "alpha_YZ", "beta_YZ")


@pytest.mark.parametrize("model,lever", [("htm-literal", "R_B"), ("linear", "Z_T")])
def test_one_tool_length(thesis, cases, model, lever):
    """Without R'_B, CR's ey gives dy_CZ only together with alpha_BT, through the lever of the one tool setup
    (htm-literal: R_B, the thesis relations: Z_T)."""
    jac, space = cases["one tool", model, "sampled"]
    result = identifiability(jac, space, known=CENTRED)
    assert not {"alpha_BT", "dy_CZ"} & set(result.determined)
    (comb,) = [c for c in result.combinations if "dy_CZ" in c.weights]
    arm_um_per_arcsec = getattr(thesis.ballbar.setups["RB1"], lever) * units.ARCSEC / units.UM
    assert list(comb.weights) == ["dy_CZ", "alpha_BT"] and comb.unit == "um"
    assert comb.weights["alpha_BT"] == pytest.approx(-arm_um_per_arcsec, rel=1e-6)
    assert comb.name == f"dy_CZ − {arm_um_per_arcsec:.4g} µm/″·alpha_BT"
    assert {"alpha_XB", "gamma_XB", "alpha_CZ", "beta_CZ"} <= set(result.determined)
    _check_consistent(result, jac, space, CENTRED)


@pytest.mark.parametrize("model", ["htm-literal", "linear", "chain"])
def test_without_bx_the_thesis_combination_is_rediscovered(thesis, model):
    """Without the BX run (the only one whose ez carries dx_BT, Table 2.6 — the term the thesis' Eq 4.2 drops), the
    campaign determines the C axis' X position only relative to the spindle: exactly the thesis' eighth quantity
    dx_CZ − dx_BT, found from the Jacobian with no thesis-specific code; the other seven one by one."""
    bb = thesis.ballbar
    c = dataclasses.replace(thesis, ballbar=dataclasses.replace(bb, runs=[r for r in bb.runs if r.pattern != "BX"]))
    m = make_model(model, c, ParameterSpace.for_campaign(c, SAMPLED_DEVIATIONS))
    result = identifiability(jacobian(m), m.space, known=CENTRED)
    (comb,) = result.combinations
    assert comb.name == "dx_CZ − dx_BT" and comb.weights == pytest.approx({"dx_CZ": 1.0, "dx_BT": -1.0})
    assert set(result.determined) == THESIS_NINE - {"dx_CZ", "dx_BT"} and result.undetermined == ("dz_BT",)
