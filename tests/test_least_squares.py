"""The least-squares identification on every machine, and the one comparison of a posterior with every deterministic
value the machine has (SPEC §19, §20; issue 42 point 2).

The least squares are checked against a computation written here from the definition (the forward model's Jacobian
by central differences, the whitened measurement rows stacked with the nuisance priors' pseudo-observations, solved
by numpy's SVD-based ``lstsq``) and, on the thesis campaign, against the thesis' own ball-bar equations where the
campaign determines a quantity by one equation and no other measurement.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.analysis import CampaignAnalysis
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines.plugins import provided
from mtmcal_bayes.parameters import weights as quantity_weights
from mtmcal_bayes.posterior.comparison import comparison, references
from mtmcal_bayes.posterior.least_squares import identify_least_squares, least_squares

TYPES = ("thesis", "trunnion", "vertical-turn-mill", "head-head")
#: agreement of two solutions of the same least-squares problem, in units of the stated standard uncertainty u
#: (different algorithms and units; round-off of a condition number of ~1e6 leaves ~1e-10 u)
SOLVER_U = 1e-6


def _campaign(machine: str):
    return mb.load_campaign() if machine == "thesis" else mb.load_campaign(demo_campaign(machine))


def _direct_gls(post, sigma_model: float):
    """The generalised least squares of ``post``'s data written from the definition, in internal units: the
    Jacobian of the forward model at zero by central differences, the data rows divided by their sd at
    ``sigma_model`` (mm), one pseudo-observation row per nuisance term (its prior centre over its prior sd; none for
    a deviation), solved by ``np.linalg.lstsq`` (minimum norm).  Returns the estimate (p,) and its covariance
    ``(MᵀM)⁺`` (p, p), both in display units (µm, ″)."""
    p, model = post.p, post.forward
    h = 1e-6  # mm / rad: the models are smooth, the linear one exactly linear
    steps = np.vstack([h * np.eye(p), -h * np.eye(p), np.zeros((1, p))])
    f = model.predict(steps)
    A = (f[:p] - f[p:2 * p]).T / (2 * h)
    c = f[-1]
    sd = np.sqrt(post.likelihood.variance_at(sigma_model))
    rows, rhs = [A / sd[:, None]], [(post.likelihood.y - c) / sd]
    for j, (par, prior) in enumerate(zip(post.space.parameters, post.priors.priors[:p])):
        if par.group != "deviation":
            e = np.zeros(p)
            e[j] = 1.0 / prior.sd
            rows.append(e[None, :])
            rhs.append(np.array([prior.centre / prior.sd]))
    M, b = np.vstack(rows), np.concatenate(rhs)
    theta = np.linalg.lstsq(M, b, rcond=1e-12)[0]
    M_pinv = np.linalg.pinv(M, rcond=1e-12)
    to_display = np.array([units.from_internal(1.0, par.unit) for par in post.space.parameters])
    return theta * to_display, (M_pinv @ M_pinv.T) * np.outer(to_display, to_display)


@pytest.mark.parametrize("machine", TYPES)
@pytest.mark.parametrize("data, sigma_um", [("ballbar", 0.0), ("both", 1.5)])
def test_least_squares_is_the_generalised_least_squares(machine, data, sigma_um):
    """Every quantity the least squares state (deviations determined one by one, combinations, derived quantities
    such as the thesis' dx_CZ − dx_BT) has the estimate and u of the direct solution, within SOLVER_U·u; each is
    estimable, so the two generalised inverses agree on it.  Both data sets, at σ_model = 0 and not."""
    c = _campaign(machine)
    post = LogPosterior(c, "linear", data=data, sigma_model=units.to_internal(sigma_um, "um"))
    ident = campaign_identifiability(post)
    ls = least_squares(post, ident, units.to_internal(sigma_um, "um"))
    theta, cov = _direct_gls(post, units.to_internal(sigma_um, "um"))
    names = post.space.names
    determined = set(ident.determined)
    assert determined and determined <= set(ls.table["quantity"])
    assert not set(ident.undetermined) & set(ls.table["quantity"])
    weights = {n: {n: 1.0} for n in ident.determined} | {k.name: k.weights for k in ident.combinations}
    weights |= {n: quantity_weights(n, names) for n in ls.table["quantity"] if n not in weights}
    for _, row in ls.table.iterrows():
        w = np.array([weights[row["quantity"]].get(n, 0.0) for n in names])
        u = float(np.sqrt(w @ cov @ w))
        assert row["u"] == pytest.approx(u, rel=SOLVER_U), row["quantity"]
        assert abs(row["estimate"] - w @ theta) <= SOLVER_U * u, row["quantity"]


#: the thesis' ball-bar equations that determine their quantity by themselves on the built-in campaign: each uses
#: components no other unknown of the campaign's ball-bar relations needs (Eqs 4.10, 4.11: CA's ey, ex; 4.12, 4.14:
#: BY's ez, ex; 4.17, 4.18: CR's ey at two tool lengths) and no assumption.  Eqs 4.13 and 4.15 are not among them:
#: they assume dx_BT = 0 (Eq 4.2), which the least squares do not, and leave out ex_CR at the second tool length.
SELF_DETERMINED = ("alpha_CZ", "beta_CZ", "alpha_XB", "gamma_XB", "alpha_BT", "dy_CZ")


def test_least_squares_reproduce_the_thesis_equations_where_they_stand_alone(thesis):
    """On the thesis campaign's ball-bar data the least squares of SELF_DETERMINED are the thesis' own values
    (Eqs 4.10–4.18 on the offsets read as the campaign reads them), within SOLVER_U·u: the same estimate by another
    road.  beta_XB, which Eq 4.13 takes from BX alone with dx_BT = 0, is not: the least squares move it by more
    than its u (the redundant ex_CR' of the thesis' own check, Eq 4.5)."""
    result = mb.identify(thesis)
    ls = result.least_squares.estimates.table.set_index("quantity")
    thesis_values = result.own.references()["ballbar"]
    for name in SELF_DETERMINED:
        assert abs(ls.loc[name, "estimate"] - thesis_values[name]) <= SOLVER_U * ls.loc[name, "u"], name
    assert abs(ls.loc["beta_XB", "estimate"] - thesis_values["beta_XB"]) > ls.loc["beta_XB", "u"]


@pytest.mark.parametrize("machine", TYPES)
def test_identify_gives_the_least_squares_and_the_plug_ins_own(machine):
    """``identify`` on every machine: the least squares of the machine's default data (its JSON keys and values as
    the least squares state them); where the machine's plug-in has a method of its own (the thesis'), every key and
    value of that method's JSON and text besides, unchanged."""
    c = _campaign(machine)
    result = mb.identify(c)
    doc, text = result.to_json(), result.to_text()
    ls = identify_least_squares(c, mb.api.data_of(None, c))
    own = provided(c.machine, "identify")
    mine = own(c).to_json() if own is not None else {}
    assert {k: doc[k] for k in mine} == mine
    assert {k: v for k, v in doc.items() if k not in mine} == {k: v for k, v in ls.to_json().items() if k not in mine}
    assert set(ls.to_json()) <= set(doc)
    assert text.endswith(ls.to_text())
    assert text.startswith(own(c).to_text()) if own is not None else text == ls.to_text()


def test_identify_without_ball_bar_runs_takes_the_probe(thesis):
    """A campaign without ball-bar runs on a machine whose default data are the ball bar's (the thesis'): the least
    squares of its touch-probe readings, and the plug-in's own method as before."""
    c = copy.deepcopy(thesis)
    c.ballbar.runs = []
    result = mb.identify(c)
    assert result.least_squares.data == "probe"
    assert result.least_squares.estimates.table["quantity"].tolist()  # the probe determines something
    assert result.probe["beta_CZ"].value is not None  # the thesis' Eqs 5.x as before


@pytest.mark.parametrize("machine", TYPES)
def test_the_comparison_on_every_machine(machine):
    """One comparison of a posterior with every deterministic value its machine has: the least squares on every
    machine, the thesis' ball-bar and touch-probe values where the plug-in gives them.  Columns: the posterior's,
    then value / in HDI / z per kind; rows: the summary's quantities that some method addresses, every deviation the
    campaign determines one by one among them with a least-squares value, no undetermined one with one; each z and
    in-HDI flag computed from the posterior's mean, sd and HDI."""
    c = _campaign(machine)
    analysis = CampaignAnalysis(c, model="linear", data="both")
    post = mb.sample(analysis, sampler="exact", seed=1)
    s = post.summary
    ls = least_squares(post.log_posterior, post.identifiability, units.to_internal(post.sigma_model_um, "um"))
    own = analysis.identification
    table = comparison(s, references(own, ls))
    kinds = (["ballbar", "probe_reported", "probe_recomputed"] if provided(c.machine, "identify") is not None
             else []) + ["least_squares"]
    assert list(table.columns) == ["unit", "mean", "sd", "hdi_low", "hdi_high"] + [
        f"{k}{suffix}" for k in kinds for suffix in ("", "_in_hdi", "_z")]
    ident = post.identifiability
    assert set(ident.determined) & set(s.index) <= set(table.index)
    assert table.loc[[n for n in ident.determined if n in s.index], "least_squares"].notna().all()
    assert table.reindex([n for n in ident.undetermined if n in table.index])["least_squares"].isna().all()
    assert list(table.index) == [n for n in s.index if n in table.index]  # the summary's order
    for key in kinds:
        v = table[key].astype(float)
        has = v.notna()
        assert has.any(), key
        z = (v[has] - s.loc[has[has].index, "mean"]) / s.loc[has[has].index, "sd"]
        assert np.allclose(table.loc[has, f"{key}_z"].astype(float), z)
        inside = (v[has] >= s.loc[has[has].index, "hdi_low"]) & (v[has] <= s.loc[has[has].index, "hdi_high"])
        assert (table.loc[has, f"{key}_in_hdi"].astype(bool) == inside).all()
    values = ls.values()
    assert all(table.loc[n, "least_squares"] == values[n] for n in table.index if n in values)
    if own is not None:  # the thesis' ball-bar values: the equations on the offsets as the campaign reads them
        ballbar = own.ballbar_in_convention if own.ballbar_in_convention is not None else own.ballbar
        assert all(table.loc[n, "ballbar"] == pytest.approx(v.display) for n, v in ballbar.items() if n in s.index)
    # sample's own comparison: the plug-in's published values alone (the least squares join them in the report)
    assert list(post.comparison.columns) == ([] if own is None else list(table.columns[:-3]))
