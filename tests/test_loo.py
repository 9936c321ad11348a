"""Leave-one-out consistency (issue 17, point 4): the pointwise log-likelihood in the InferenceData, PSIS-LOO per
observation, what it cannot see on the thesis' nearly saturated design and what it catches on a redundant one."""

import copy

import numpy as np
import pandas as pd
import pytest
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Mount, Run, Truth
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.inference.results import to_inference_data
from mtmcal_bayes.inference.sampling import SamplerSettings, run_ensembles
from mtmcal_bayes.parameters import quantity_unit
from mtmcal_bayes.posterior.loo import ELPD_DROP, K_INFLUENTIAL, loo_check

#: the gross error injected into one redundant measurement, µm (the means scatter by ~0.5 µm)
GROSS_UM = 20.0
#: the measurement it goes into: the C-axis tilt seen by the CA run at a third W-ball mount (R_C = 100 mm)
TARGET = "ex_CA@RB1/C3"


def _um(x):
    return units.to_internal(x, "um")


def _arcsec(x):
    return units.to_internal(x, "arcsec")


def redundant_campaign(campaign):
    """The thesis campaign plus runs that repeat what it measures: CA at three more W-ball mounts (R_C 75, 100,
    125 mm; alpha_CZ, beta_CZ seen four times), CR at the second mount (same tool setup, Z_C) and BY at the
    second tool length (alpha_XB, gamma_XB seen twice).  Each extra run has its own mount or setup, as a campaign
    file requires.  Probe data dropped: the ball bar's consistency is the point."""
    c = copy.deepcopy(campaign)
    bb, zeros = c.ballbar, np.zeros(3)
    for i, (z_c, r_c) in enumerate(((65.5348, 75.0), (120.0, 100.0), (65.5348, 125.0)), start=2):
        bb.mounts[f"C{i}"] = Mount(f"C{i}", Z_C=z_c, R_C=r_c)
        bb.runs.append(Run("CA", "RB1", f"C{i}", {"ex": zeros, "ey": zeros}))
    bb.runs += [Run("CR", "RB1", "C2", {"ex": zeros, "ey": zeros}), Run("BY", "RB2", "B", {"ex": zeros, "ez": zeros})]
    c.probe = None
    return c


TRUTH = Truth(deviations={"alpha_CZ": _arcsec(1.1), "beta_CZ": _arcsec(-25.2), "alpha_XB": _arcsec(-20.9),
                          "beta_XB": _arcsec(-24.1), "gamma_XB": _arcsec(5.6), "alpha_BT": _arcsec(9.6),
                          "dx_CZ": _um(53.1), "dy_CZ": _um(-45.6)})


def synthetic(thesis, seed: int, error_um: float = 0.0):
    """The redundant campaign simulated (linear model, seeded noise) with ``error_um`` added to every repeat of
    :data:`TARGET`."""
    c = mb.simulate(redundant_campaign(thesis), truth=TRUTH, model="linear", noise=True,
                    seed=seed).synthetic_campaign()
    c.probe = None
    for run in c.ballbar.runs:
        for comp in run.repeats:
            if f"{comp}_{run.label}" == TARGET:
                run.repeats[comp] = run.repeats[comp] + _um(error_um)
    return c


def _expected_loglik(idata, post):
    """scipy's Normal log density of every observed mean (µm) for every draw of ``idata``'s posterior."""
    theta = np.stack([units.to_internal(np.asarray(idata.posterior[n]), quantity_unit(n)) for n in post.names],
                     axis=-1)
    flat = theta.reshape(-1, theta.shape[-1])
    mu = post.forward.predict(flat[:, : post.p])
    sd = np.sqrt(post.likelihood.base_var + post.sigma(flat)[:, post.scale_of] ** 2)  # each mean its instrument's scale
    y = units.from_internal(post.likelihood.y, "um")
    return stats.norm.logpdf(y, units.from_internal(mu, "um"), units.from_internal(sd, "um")).reshape(
        theta.shape[:2] + (-1,))


def test_log_likelihood_group_is_the_normal_density_of_each_mean(thesis_posterior):
    idata, post = thesis_posterior.idata, thesis_posterior.log_posterior
    ll = idata.log_likelihood["eccentricity"]
    assert ll.dims == ("chain", "draw", "observation")
    assert ll.shape == (idata.posterior.sizes["chain"], idata.posterior.sizes["draw"], 10)
    assert list(ll["observation"].values) == list(idata.observed_data["observation"].values)
    np.testing.assert_allclose(np.asarray(ll), _expected_loglik(idata, post), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("data", ["ballbar", "both"])
def test_log_likelihood_with_fixed_sigma_and_probe_readings(thesis, data):
    """A fixed sigma_model (no sigma_model draws) and the probe readings' own variable."""
    post = LogPosterior(thesis, "linear", sigma_model=_um(0.3), data=data)
    idata = to_inference_data(run_ensembles(post, SamplerSettings(sampler="exact", seed=3, min_steps=20)), seed=3)
    assert "sigma_model" not in idata.posterior
    expected = _expected_loglik(idata, post)
    got = np.concatenate([np.asarray(idata.log_likelihood[v]) for v in idata.log_likelihood.data_vars], axis=-1)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    assert ("probe_reading" in idata.log_likelihood) == (data == "both")
    if data == "both":
        assert idata.log_likelihood["probe_reading"].dims[-1] == "probe_reading_observation"


def test_loo_has_little_power_on_the_saturated_thesis_design(thesis_posterior):
    """Thesis campaign, seed 1: elpd_loo −26.2 (se 0.5), p_loo 12.1 on 10 means, Pareto k > 0.7 for all 10
    (0.77–1.26) — each mean is the only one fixing some of the 25 parameters — and no elpd outlier
    (pointwise elpd −3.1 to −2.5)."""
    loo = loo_check(thesis_posterior.idata)
    assert loo.n_observations == 10 and loo.n_parameters == 25
    assert len(loo.influential) >= 8 and loo.saturated
    assert loo.outliers == []
    assert loo.p_loo > 8
    assert "little power" in loo.power_sentence()
    assert loo.table["note"].str.contains("LOO unreliable here: the observation is influential").sum() >= 8


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_loo_flags_a_gross_error_in_a_redundant_measurement(thesis, seed):
    """+20 µm in ex_CA@RB1/C3 (one of four CA runs seeing the C-axis tilt) of the redundant synthetic campaign.

    The criterion: the injected observation is the only *outlier* — its pointwise elpd_loo lies ≥ 4.5 below
    the median (a residual of about three predictive sds) and ≥ 4.5 below every other observation — and
    it is influential (Pareto k > 0.7).  Pareto k alone would not do: the runs nothing repeats (BX, CR at
    R'_B) have k > 0.7 with or without the error.  Seen here (exact sampler, seeds 0–5, noise seed = sampler
    seed): injected elpd_loo −12.2 to −14.0 (elpd_drop 9.5–11.2) with k 1.23–1.55; every other observation
    above −6.1 with elpd_drop ≤ 3.3 (the CA run at R_C = 125 mm, sharing beta_CZ, is dragged down most; σ_model
    grows from about 0.3 to 4.2–4.6 µm to absorb the error).  Exact leave-one-out refits give −49 for it: PSIS understates the drop, never invents it.
    """
    loo = loo_check(mb.sample(synthetic(thesis, seed, GROSS_UM), seed=seed, sampler="exact").idata)
    t = loo.table
    assert not loo.saturated
    assert loo.outliers == [TARGET], t
    assert t.loc[TARGET, "pareto_k"] > K_INFLUENTIAL
    assert t.loc[TARGET, "elpd_drop"] > 2 * ELPD_DROP
    others = t.drop(index=TARGET)
    assert t.loc[TARGET, "elpd_loo"] < others["elpd_loo"].min() - ELPD_DROP
    assert "check this measurement" in loo.outlier_sentences()[0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_loo_flags_nothing_without_the_error(thesis, seed):
    """The same campaigns without the error: no outlier (largest elpd_drop 0.6–2.7 in seeds 0–5) and the
    redundant CA run not influential (k 0.39–0.52); 4–6 of the 20 observations have k > 0.7 all the same."""
    loo = loo_check(mb.sample(synthetic(thesis, seed), seed=seed, sampler="exact").idata)
    assert loo.outliers == []
    assert loo.table["elpd_drop"].max() < ELPD_DROP
    assert loo.table.loc[TARGET, "pareto_k"] < K_INFLUENTIAL


def test_emcee_posterior_flags_it_too(thesis):
    """The default sampler's draws (correlated, thinned) give the same verdict (seed 1: k 1.27, elpd −12.7)."""
    loo = loo_check(mb.sample(synthetic(thesis, 1, GROSS_UM), seed=1).idata)
    assert loo.outliers == [TARGET]


def test_report_shows_loo_and_writes_loo_csv(thesis, run_cli, tmp_path):
    """The report of the synthetic campaign with the error: loo.csv, loo.png, the paragraph and the warning."""
    src = tmp_path / "redundant_with_error.toml"
    mb.save_campaign(synthetic(thesis, 0, GROSS_UM), src)
    out = tmp_path / "rep"
    code, _out, err = run_cli("report", src, "-o", out, "--seed", "0", "--sampler", "exact", "--quiet")
    assert code == 0, err
    t = pd.read_csv(out / "loo.csv", index_col="observation")
    assert list(t.index[t["outlier"]]) == [TARGET]
    assert (out / "loo.png").is_file()
    html = (out / "index.html").read_text(encoding="utf-8")
    assert "Leave-one-out consistency of the posterior" in html and "<strong>loo.png.</strong>" in html
    assert f"{TARGET}: elpd_loo" in html and "check this measurement" in html


def _loo_table(m: int, outliers=(), influential=()):
    """A LooResult of ``m`` observations of two kinds, the given rows flagged (elpd 6 below the median, k 0.9)."""
    from mtmcal_bayes.posterior.loo import LooResult

    rng = np.random.default_rng(0)
    elpd = -0.5 + 0.1 * rng.standard_normal(m)
    elpd[list(outliers)] -= 6.0
    k = np.full(m, 0.2)
    k[list(influential)] = 0.9
    names = [f"obs{i}" for i in range(m)]
    kinds = ["eccentricity"] * (m // 3) + ["rtest_reading"] * (m - m // 3)
    t = pd.DataFrame({"variable": kinds, "elpd_loo": elpd, "pareto_k": k}, index=pd.Index(names, name="observation"))
    t["influential"] = t["pareto_k"] > K_INFLUENTIAL
    t["elpd_drop"] = t.groupby("variable")["elpd_loo"].transform("median") - t["elpd_loo"]
    t["outlier"] = t["elpd_drop"] >= ELPD_DROP
    t["note"] = ""
    return LooResult(t, float(elpd.sum()), 1.0, 3.0, m, 5, 1000)


def test_many_observations_are_drawn_compact_with_the_flagged_ones_named():
    """Beyond ROWS_LABELLED observations the figure is the compact form (two panels of a fixed height, each
    observation a point) naming exactly the flagged observations, each in the panel of its flag; up to it, one
    labelled row per observation."""
    from mtmcal_bayes.reporting import loo_plot

    many = _loo_table(loo_plot.ROWS_LABELLED + 20, outliers=(3, 50), influential=(10, 11, 51))
    fig = loo_plot.loo_figure(many)
    top, bottom = fig.axes
    assert fig.get_figheight() == pytest.approx(6.4) and len(top.get_yticklabels()) < 20
    named = {a: {t.get_text() for t in a.texts if t.get_text().startswith("obs")} for a in (top, bottom)}
    assert named == {top: {"obs3", "obs50"}, bottom: {"obs10", "obs11", "obs51"}}
    assert loo_plot.caption(many) == loo_plot.COMPACT_CAPTION
    few = _loo_table(loo_plot.ROWS_LABELLED, outliers=(3,))
    fig = loo_plot.loo_figure(few)
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()] == list(few.table.index)
    assert loo_plot.caption(few) == loo_plot.CAPTION
