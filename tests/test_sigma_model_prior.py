"""A σ_model prior learnt elsewhere (a fleet of machines of one type) for one campaign: the file and its errors, the
log density, the exact σ-marginal posterior and the sampler under it, the analysis cache and the budget's statement.

Bad files of every kind are in the bad-input corpus (``tests/data/bad/sigma_prior``, ``tests/test_bad_inputs.py``).
"""

from __future__ import annotations

import json
import math
import textwrap

import numpy as np
import pytest
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.analysis import CampaignAnalysis, analysis_of
from mtmcal_bayes.errors import InputError, ParameterError
from mtmcal_bayes.figure_style import save_png
from mtmcal_bayes.html_page import Page
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.inference.priors import Prior, PriorSet, learnt_prior, make_prior
from mtmcal_bayes.io import sigma_prior_file
from mtmcal_bayes.io.sigma_prior_file import (
    FORMAT,
    parse_sigma_model_prior,
    read_sigma_model_prior,
    write_sigma_model_prior,
)
from mtmcal_bayes.parameters import IDENTIFIABLE
from mtmcal_bayes.reporting import budget_plot, build
from mtmcal_bayes.sigma_prior import SigmaModelPrior

from .conftest import DATA

SOURCE = 'fleet plant/: type "INTEGREX i-200", 3 machines, 14 campaigns'
#: the learnt prior of the brief: median 2.7 µm, sd of ln σ 0.2
LEARNT = SigmaModelPrior({"sigma_model": (2.7, 0.2)}, SOURCE)
#: the example file of the format's documentation (the module docstring of mtmcal_bayes.io.sigma_prior_file)
EXAMPLE = textwrap.dedent(sigma_prior_file.__doc__.split("::\n\n")[1].split("\nEvery problem")[0])


def _write(path, prior: SigmaModelPrior = LEARNT):
    write_sigma_model_prior(path, prior)
    return path


# --------------------------------------------------------------------------- the file
def test_round_trip(tmp_path):
    prior = SigmaModelPrior({"sigma_model": (2.74, 0.34), "sigma_model_probe": (1.2, 0.5)},
                            'fleet "a\\b": 3 machines\tüber')  # quotes, a backslash, a tab and non-ASCII survive
    path = tmp_path / "prior.toml"
    write_sigma_model_prior(path, prior)
    back = read_sigma_model_prior(path)
    assert back == prior and hash(back) == hash(prior)
    assert path.read_text(encoding="utf-8").startswith(f'format = "{FORMAT}"')
    write_sigma_model_prior(path, LEARNT)  # replaced whole, through a temporary file that does not stay
    assert read_sigma_model_prior(path) == LEARNT
    assert [p.name for p in tmp_path.iterdir()] == ["prior.toml"]


def test_the_documented_example_reads():
    prior = parse_sigma_model_prior(EXAMPLE, "example.toml")
    assert prior.source == SOURCE
    assert prior.scales == {"sigma_model": (2.74, 0.34), "sigma_model_probe": (1.2, 0.5)}


@pytest.mark.parametrize("scales,source,fragment", [
    ({"sigma_model_probe": (1.0, 0.2)}, SOURCE, "needs the ball bar's scale"),
    ({"sigma_model": (2.7, 0.2), "sigma_model_x": (1.0, 0.2)}, SOURCE, "not a discrepancy scale"),
    ({"sigma_model": (0.0, 0.2)}, SOURCE, "median_um must be positive"),
    ({"sigma_model": (2.7, math.nan)}, SOURCE, "log_sd must be positive"),
    ({"sigma_model": (2.7, 0.2)}, " ", "needs its source"),
])
def test_a_prior_built_in_python_is_checked(scales, source, fragment):
    with pytest.raises(ValueError, match=fragment):
        SigmaModelPrior(scales, source)


BAD_ROWS = [line.split("\t") for line in (DATA / "bad" / "sigma_prior" / "expected.tsv").read_text(encoding="utf-8")
            .splitlines() if line.strip() and not line.startswith("#")]


@pytest.mark.parametrize("name,key,fragment", BAD_ROWS, ids=[r[0] for r in BAD_ROWS])
def test_a_bad_file_is_an_input_error_naming_file_and_key(name, key, fragment):
    """The corpus read from Python (the CLI's one line and exit status 2: tests/test_bad_inputs.py)."""
    path = DATA / "bad" / "sigma_prior" / name
    with pytest.raises(InputError) as info:
        read_sigma_model_prior(path)
    assert (info.value.source, info.value.key) == (str(path), None if key == "-" else key)
    assert fragment in info.value.message


def test_a_missing_file_is_one_line(run_cli, tmp_path):
    missing = tmp_path / "nowhere.toml"
    code, out, err = run_cli("sample", "--sigma-model-prior", missing, "-o", tmp_path / "p.nc", "--quiet")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert str(missing) in err and "file not found" in err and not (tmp_path / "p.nc").exists()


@pytest.mark.parametrize("extra", [("--sigma-model-um", "1"), ("--closed-form",)])
def test_refused_with_a_fixed_sigma_model(run_cli, tmp_path, extra):
    """A fixed σ_model (or the closed form, which fixes it) has no prior: one line naming the flag, exit 2."""
    prior = _write(tmp_path / "prior.toml")
    code, out, err = run_cli("sample", "--sigma-model-prior", prior, *extra, "-o", tmp_path / "p.nc", "--quiet")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith("mtmcal-bayes sample: error: --sigma-model-prior: ") and "fix" in err
    assert not (tmp_path / "p.nc").exists()
    with pytest.raises(ParameterError) as info:
        mb.sample(sigma_model_um=1.0, sigma_model_prior=LEARNT)
    assert info.value.parameter == "sigma_model_prior"


def test_refused_where_the_campaign_already_sets_the_prior(tmp_path):
    campaign = tmp_path / "c.toml"
    campaign.write_text((DATA / "minimal_one_repeat.toml").read_text()
                        + '\n[priors]\nsigma_model = {dist = "halfnormal", sd_um = 3}\n')
    with pytest.raises(ParameterError, match=r"sigma_model already has a prior in the campaign's \[priors\]"):
        mb.sample(campaign, sigma_model_prior=LEARNT)


# --------------------------------------------------------------------------- the log density
def test_log_density_against_scipy():
    """The plain-numpy joint log density of a set mixing every family, against scipy.stats term by term, inside
    and outside the log-normal's support (σ ≤ 0 is −inf)."""
    lognormal = learnt_prior("sigma_model", LEARNT)
    wide = Prior("sigma_model_probe", "lognormal", 0.0, units.to_internal(0.3, "um"), "um", "test", shape=1.1)
    priors = [make_prior("beta_XB", "beta_XB", "angle", {}), make_prior("xT[RB1]", "xT", "length", {}),
              Prior("u", "uniform", -1e-3, 2e-3, "um", "test"), Prior("h", "halfnormal", 0.0, 2e-3, "um", "test"),
              lognormal, wide]
    ps = PriorSet(priors)
    rng = np.random.default_rng(3)
    theta = ps.rvs(500, rng)
    theta[::7, 4] = 0.0  # σ = 0 and below: outside the support
    theta[::11, 5] = -theta[::11, 5]
    want = sum(p.frozen().logpdf(theta[:, i]) for i, p in enumerate(priors))
    got = ps.logpdf(theta)
    assert np.array_equal(np.isinf(got), np.isinf(want)) and np.isinf(got).sum() > 50
    ok = np.isfinite(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12, atol=1e-9)

    frozen = stats.lognorm(s=0.2, scale=units.to_internal(2.7, "um"))
    assert LEARNT.frozen("sigma_model").ppf(0.3) == pytest.approx(frozen.ppf(0.3), rel=1e-14)
    assert lognormal.frozen().logpdf(2.2e-3) == pytest.approx(frozen.logpdf(2.2e-3), rel=1e-14)
    for p in (lognormal, wide):
        assert p.sd == pytest.approx(p.frozen().std(), rel=1e-12)
        assert p.mean == pytest.approx(p.frozen().mean(), rel=1e-12)
    assert lognormal.describe() == LEARNT.describe("sigma_model") == "LogNormal(median 2.7 µm, log sd 0.2)"


def test_the_log_posterior_takes_the_learnt_prior(thesis):
    post = LogPosterior(thesis, sigma_prior=LEARNT)
    default = LogPosterior(thesis)
    q = post.priors.priors[post.p]
    assert (q.name, q.dist, q.reason) == ("sigma_model", "lognormal", f"learnt elsewhere: {SOURCE}")
    assert default.priors.priors[default.p].dist == "halfnormal"
    theta = post.priors.rvs(200, np.random.default_rng(1))
    # the two differ exactly by the σ prior's log densities
    diff = post.log_prob_theta(theta) - default.log_prob_theta(theta)
    sig = theta[:, post.p]
    np.testing.assert_allclose(diff, LEARNT.frozen("sigma_model").logpdf(sig) - stats.halfnorm(scale=2e-3).logpdf(sig),
                               rtol=1e-9)
    both = LogPosterior(thesis, data="both", sigma_prior=LEARNT)  # the probe's scale keeps its assumed prior
    assert [p.dist for p in both.priors.priors[both.p:]] == ["lognormal", "halfnormal"]


# --------------------------------------------------------------------------- the posterior under it
def _exact_moments(analysis, names):
    return analysis.approximation.moments(names)


def test_the_learnt_prior_sets_the_width_of_alpha_CZ(thesis):
    """The exact σ-marginal posterior (deterministic quadrature) of the thesis campaign.  Under the assumed
    HalfNormal(2 µm) the data hardly narrow σ_model (posterior mean 1.54 µm, sd 1.16 µm; the prior's 1.60, 1.21)
    and alpha_CZ has sd 8.03″.  A learnt LogNormal(median 2.7 µm, log sd 0.2) puts σ_model at 2.74 ± 0.55 µm,
    above where the assumed prior left it, so alpha_CZ's sd grows to 11.45″ (× 1.43), not shrinks: a learnt prior
    narrows the intervals only when the type's σ_model is smaller than the assumed prior's (median 1.0 µm, log sd
    0.2: 4.75″, × 0.59).  What it always removes is the arbitrariness: the width now rests on the type's σ_model."""
    a = CampaignAnalysis(thesis)
    default = _exact_moments(a, ["alpha_CZ", "sigma_model"])
    learnt = _exact_moments(a.variant(sigma_prior=LEARNT), ["alpha_CZ", "sigma_model"])
    small = _exact_moments(a.variant(sigma_prior=SigmaModelPrior({"sigma_model": (1.0, 0.2)}, SOURCE)), ["alpha_CZ"])
    assert default["alpha_CZ"][1] == pytest.approx(8.03, abs=0.01)
    assert learnt["alpha_CZ"][1] / default["alpha_CZ"][1] == pytest.approx(1.426, abs=0.005)
    assert small["alpha_CZ"][1] / default["alpha_CZ"][1] == pytest.approx(0.591, abs=0.005)
    assert learnt["sigma_model"] == pytest.approx((2.738, 0.549), abs=0.002)  # the prior's 2.754, 0.555: kept
    # the closed form at σ_model fixed near the learnt one's posterior says the same: sd(σ = 2.7 µm) = 11.1″
    fixed = a.variant(sigma_model=units.to_internal(2.7, "um"))
    assert _exact_moments(fixed, ["alpha_CZ"])["alpha_CZ"][1] == pytest.approx(learnt["alpha_CZ"][1], rel=0.04)


def test_the_grid_covers_the_log_normal(thesis):
    """The σ grid of a log-normal runs in log σ where the posterior is, whatever the log sd: its 128 cells agree with
    4 000 cells over the prior's whole range (quantiles 1e-12 to 1 − 1e-12) to far below the Monte-Carlo error of
    any run (equal widths in σ from 0 were 5 % off in the sd at a log sd of 1)."""
    from mtmcal_bayes.inference.marginal import MarginalPosterior

    for median, log_sd in ((2.7, 0.2), (1.0, 1.0), (2.7, 3.0), (0.3, 0.01)):
        prior = SigmaModelPrior({"sigma_model": (median, log_sd)}, SOURCE)
        post = CampaignAnalysis(thesis, sigma_prior=prior).log_posterior
        frozen = prior.frozen("sigma_model")
        var0 = np.array([q.sd for q in post.priors.priors[: post.p]]) ** 2
        T = np.eye(post.p)[[list(post.space.names).index("alpha_CZ")]]
        y = post.likelihood.y
        grids = {"default": {}, "whole prior": dict(cells=4000, sigma_min=frozen.ppf(1e-12),
                                                     sigma_max=frozen.ppf(1 - 1e-12))}
        moments = {}
        for label, kw in grids.items():
            m = MarginalPosterior(post.forward.design, post.likelihood.base_var, var0, [frozen], y=y, **kw)
            mean, sd = m.target_moments(y[None], T)
            moments[label] = (mean[0, 0], sd[0, 0], m.sigma_moments(y)[0][0], len(m.sigma))
        (m1, s1, g1, n1), (m2, s2, g2, n2) = moments.values()
        assert (n1, n2) == (128, 4000)
        assert abs(m1 - m2) < 1e-5 * s2 and abs(s1 / s2 - 1) < 1e-5 and abs(g1 / g2 - 1) < 1e-5, (median, log_sd)


def test_exact_and_sampled_posteriors_agree_under_the_learnt_prior(thesis):
    """emcee against independent exact draws of the σ-marginal posterior, both under the learnt prior: each mean
    (the eight and σ_model) within 4 Monte-Carlo sd of the difference, sd·√(1/ESS_emcee + 1/ESS_exact) with each
    run's bulk ESS; and σ_model's mean where the learnt prior puts it, many of those sd from the assumed prior's."""
    sampled = mb.sample(thesis, seed=11, sigma_model_prior=LEARNT)
    exact = mb.sample(thesis, seed=12, sampler="exact", sigma_model_prior=LEARNT)
    assert sampled.diagnostics.converged
    names = [*IDENTIFIABLE, "sigma_model"]
    for n in names:
        a, b = sampled.summary.loc[n], exact.summary.loc[n]
        mc = b["sd"] * math.sqrt(1.0 / a["ess_bulk"] + 1.0 / b["ess_bulk"])
        assert abs(a["mean"] - b["mean"]) < 4.0 * mc, (n, a["mean"], b["mean"], mc)
    assumed = _exact_moments(CampaignAnalysis(thesis), ["sigma_model"])["sigma_model"][0]
    s = sampled.summary.loc["sigma_model"]
    assert abs(s["mean"] - assumed) > 20 * s["sd"] / math.sqrt(s["ess_bulk"])


# --------------------------------------------------------------------------- the analysis cache
def test_the_analysis_cache_tells_priors_apart(thesis):
    a = CampaignAnalysis(thesis)
    b = a.variant(sigma_prior=LEARNT)
    assert b is not a and b.key != a.key and b.key[-1] == LEARNT and a.key[-1] is None
    assert a.variant(sigma_prior=SigmaModelPrior(dict(LEARNT.scales), SOURCE)) is b  # an equal prior: the same
    other = a.variant(sigma_prior=SigmaModelPrior({"sigma_model": (1.0, 0.2)}, SOURCE))
    assert other is not b and other.marginal is not b.marginal
    assert b.variant(data="probe").sigma_prior == LEARNT and b.variant(sigma_prior=None) is a
    fixed = b.variant(sigma_model=1e-3)  # a fixed scale has no prior: the same analysis as the default's
    assert fixed.sigma_prior is None and fixed is a.variant(sigma_model=1e-3)
    assert [x.log_posterior.priors.priors[-1].dist for x in (a, b)] == ["halfnormal", "lognormal"]
    assert analysis_of(thesis, sigma_prior=LEARNT).key == ("linear", "ballbar", False, None, LEARNT)
    result = mb.sample(b, seed=1, sampler="exact", sigma_model_prior=LEARNT)
    assert result.sampling.approximation is b.approximation  # the analysis' own, not rebuilt
    assert mb.sample(b, seed=1, sampler="exact").log_posterior.sigma_prior is None  # the keywords choose


# --------------------------------------------------------------------------- the budget states the source
def test_the_budget_names_the_source(thesis, run_cli, tmp_path):
    learnt = mb.sample(thesis, seed=1, sampler="exact", sigma_model_prior=_write(tmp_path / "prior.toml"))
    assumed = mb.sample(thesis, seed=1, sampler="exact")
    statement = (f"σ_model (ball bar) prior: learnt elsewhere, LogNormal(median 2.7 µm, log sd 0.2), from {SOURCE}.")
    assert statement in learnt.to_text()
    default = "σ_model (ball bar) prior: assumed, HalfNormal(2 µm) (the default; not learnt from data)."
    assert default in assumed.to_text()
    assert learnt.to_json()["sigma_model_prior"] == {"sigma_model": {
        "source": "learnt", "prior": "LogNormal(median 2.7 µm, log sd 0.2)", "from": SOURCE}}
    assert assumed.to_json()["sigma_model_prior"]["sigma_model"]["source"] == "assumed"
    code, out, err = run_cli("sample", "--sampler", "exact", "--seed", "1", "--quiet", "--json",
                             "--sigma-model-prior", tmp_path / "prior.toml")
    assert code == 0, err
    assert json.loads(out)["sigma_model_prior"]["sigma_model"]["from"] == SOURCE

    # the report's budget section and its opening sentence (the figures it embeds drawn as the report draws them)
    save_png(budget_plot.budget_figure(learnt.summary), tmp_path / "budget.png")
    save_png(budget_plot.sigma_figure(learnt, IDENTIFIABLE), tmp_path / "sigma_model.png")
    page = Page("test")
    build._budget_section(page, learnt, tmp_path, sigma_names=IDENTIFIABLE)
    html = "".join(page.parts)
    assert statement.replace('"', "&quot;") in html
    assert "σ_model of the ball bar (its prior learnt elsewhere) dominates" in \
        budget_plot.dominant_sentence(learnt.summary, IDENTIFIABLE, post=learnt.log_posterior)
    assert "assumed model-discrepancy scale σ_model of the ball bar dominates" in \
        budget_plot.dominant_sentence(assumed.summary, IDENTIFIABLE, post=assumed.log_posterior)
