"""The sampler's parts: plain-numpy densities against scipy.stats, the approximation it starts from and
proposes with, the Hastings correction, burn-in detection, the exact sampler, the kinematic chain.

Statistical tolerances are stated in units of the posterior sd.
"""

import numpy as np
import pytest
from scipy import integrate, stats
from scipy.spatial.transform import Rotation

from mtmcal_bayes import IDENTIFIABLE
from mtmcal_bayes.inference import (
    LogPosterior,
    PosteriorApproximation,
    SamplerSettings,
    gaussian_posterior,
    run_ensembles,
    summarize,
    to_inference_data,
)
from mtmcal_bayes.inference.marginal import MarginalPosterior
from mtmcal_bayes.inference.priors import Prior, PriorSet
from mtmcal_bayes.io import parse_campaign
from mtmcal_bayes.machines.rotations import rotation
from mtmcal_bayes.models.ballbar import CHUNK_POINTS
from mtmcal_bayes.plugins.thesis.kinematic import HTMModel
from mtmcal_bayes.observations import ProbeKey
from mtmcal_bayes.parameters import weights

from . import variants


# --------------------------------------------------------------------------- densities
def test_prior_logpdf_is_scipy_stats():
    """Plain numpy against scipy.stats for every family, inside and outside the support (oracle to 1e-12)."""
    priors = [Prior("a", "normal", 0.3, 2.0, "um", ""), Prior("b", "halfnormal", 0.0, 1.5, "um", ""),
              Prior("c", "uniform", -1.0, 3.0, "um", ""), Prior("d", "normal", -4.0, 0.5, "arcsec", "")]
    ps = PriorSet(priors)
    x = np.random.default_rng(0).normal(size=(200, 4)) * 2.0
    x[:5, 1] = -0.1  # outside the half-normal's support
    x[5:9, 2] = 2.5  # outside the uniform's
    ref = sum(p.frozen().logpdf(x[:, i]) for i, p in enumerate(priors))
    got = ps.logpdf(x)
    assert np.array_equal(np.isneginf(got), np.isneginf(ref))
    ok = np.isfinite(ref)
    np.testing.assert_allclose(got[ok], ref[ok], rtol=0, atol=1e-12)
    for p in priors + [Prior("e", "halfnormal", 0.2, 0.7, "um", ""), Prior("f", "uniform", 2.0, 0.5, "um", "")]:
        assert p.mean == pytest.approx(p.frozen().mean(), rel=1e-12, abs=1e-15), p
        assert p.sd == pytest.approx(p.frozen().std(), rel=1e-12), p


@pytest.mark.parametrize("data", ["ballbar", "both"])
def test_likelihood_is_scipy_stats(thesis, data):
    """Each mean Normal with variance base + its own instrument's scale²: the ball bar's means take sigma_model,
    the probe's readings sigma_model_probe (two different values here, so a swap would show)."""
    post = LogPosterior(thesis, "linear", data=data)
    theta = post.to_theta(np.random.default_rng(1).normal(size=(20, len(post))))
    pred, sigma = post.forward.predict(theta[:, : post.p]), post.sigma(theta)
    probe = np.array([isinstance(k, ProbeKey) for k in post.forward.observations.keys])
    assert post.scales == (("sigma_model", "sigma_model_probe") if data == "both" else ("sigma_model",))
    own = np.where(probe[None], theta[:, -1:], theta[:, post.p: post.p + 1])  # (20, m): each mean's scale
    ref = stats.norm.logpdf(post.likelihood.y, loc=pred, scale=np.sqrt(post.likelihood.base_var + own**2)).sum(axis=1)
    np.testing.assert_allclose(post.likelihood.loglike(pred, sigma), ref, rtol=1e-12)


def test_rotation_is_scipy_rotation():
    """Rodrigues' formula against scipy.spatial.transform, from 1e-12 rad to 3 rad (no cancellation)."""
    rng = np.random.default_rng(2)
    v = rng.normal(size=(60, 3)) * np.repeat(10.0 ** np.arange(-12, 0.5, 1.0), 5)[:60, None] * 3.0
    np.testing.assert_allclose(rotation(v), Rotation.from_rotvec(v).as_matrix(), rtol=0, atol=2e-15)


# --------------------------------------------------------------------------- the approximation
def test_marginal_posterior_at_fixed_sigma_is_the_closed_form(thesis):
    """The grid posterior with one cell equals the closed-form Gaussian of analytic.py (two implementations)."""
    sigma = 0.4e-3
    post = LogPosterior(thesis, "linear", sigma_model=sigma)
    g = gaussian_posterior(post, sigma)
    prior_var = np.array([p.sd for p in post.priors.priors[: post.p]]) ** 2
    m = MarginalPosterior(post.forward.design, post.likelihood.base_var, prior_var, sigma_fixed=sigma)
    np.testing.assert_allclose(m.means(post.likelihood.y[None])[0, 0], g.mean, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(m.cov[0], g.cov, rtol=1e-9, atol=1e-20)


@pytest.mark.parametrize("data", ["ballbar", "both"])
def test_target_moments_in_the_data_space_equal_those_of_the_cells_posteriors(thesis, data):
    """``target_moments`` works in the data's space (``T K S⁻¹ r``, ``T Σ0 Tᵀ − T K S⁻¹ Kᵀ Tᵀ``); the same
    moments from each cell's posterior of θ (mean ``μ0 + gain r``, covariance ``cov``) agree to 1e-9."""
    post = LogPosterior(thesis, "linear", data=data)
    a = PosteriorApproximation(post)
    m = a.marginal
    y = post.likelihood.y[None] + np.random.default_rng(4).normal(scale=2e-3, size=(3, len(post.likelihood.y)))
    T = np.random.default_rng(5).normal(size=(4, post.p))
    mean, sd = m.target_moments(y, T)
    w = m.weights(y)
    mean_g = np.einsum("tp,gnp->gnt", T, m.means(y))
    var_g = np.einsum("tp,gpq,tq->gt", T, m.cov, T)
    ref_mean = np.einsum("gn,gnt->nt", w, mean_g)
    ref_sd = np.sqrt(np.einsum("gn,gnt->nt", w, mean_g**2 + var_g[:, None, :]) - ref_mean**2)
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-9, atol=1e-12 * np.abs(ref_mean).max())
    np.testing.assert_allclose(sd, ref_sd, rtol=1e-9)


@pytest.mark.parametrize("data", ["ballbar", "probe", "both"])
def test_grid_log_joint_is_scipys_multivariate_normal_in_every_cell(thesis, data):
    """Each cell's ``log p(y | σ) + log p(σ)`` (whitened by blocks: one eigendecomposition per cell of the second
    scale) equals ``scipy.stats.multivariate_normal.logpdf`` of the means under that cell's
    prior predictive covariance plus the grid's log prior, for data vectors near the campaign's.  Tolerance: 1e-6
    nats, the round-off of a quadratic form of ~100 nats in a covariance of condition 3e7 (the probe's; ε·cond·100
    ≈ 7e-7, which is what a Cholesky solve of scipy's own covariance also misses by), 1e-9 relative at most."""
    post = LogPosterior(thesis, "linear", data=data)
    m = PosteriorApproximation(post).marginal
    assert m._blocks is not None and (m._blocks.L_b is None) == (data != "both")  # one scale: no second block
    y = post.likelihood.y[None] + np.random.default_rng(8).normal(scale=2e-3, size=(2, len(post.likelihood.y)))
    got = m.log_joint(y)  # (G, 2)
    S0 = (m.A * m.prior_var) @ m.A.T
    mean = m.offset + m.A @ m.prior_mean
    cells = np.unique(np.linspace(0, len(m.sigma) - 1, 9).astype(int))
    for g in cells:
        want = stats.multivariate_normal(mean, S0 + np.diag(m.V[g])).logpdf(y) + m.log_prior[g]
        np.testing.assert_allclose(got[g], want, rtol=1e-9, atol=1e-6)


def test_grid_without_observations_of_its_first_scale_is_whitened_by_cholesky_factors_alike():
    """A grid whose first scale has no observations (whitened cell by cell through Cholesky factors, not by blocks)
    gives scipy's log joint too, and the same as when its scales are given the other way round (by blocks), to
    1e-9 relative."""
    rng = np.random.default_rng(9)
    m, P = 12, 4
    A, prior_var, base = rng.normal(size=(m, P)), rng.uniform(0.5, 2.0, P), rng.uniform(0.01, 0.1, m)
    y = A @ rng.normal(size=P) + rng.normal(scale=0.3, size=m)
    prior = stats.halfnorm(scale=0.5)
    two = np.r_[np.ones(8), np.ones(4) * 2].astype(int)  # scales 1 and 2 observed, scale 0 not
    chol = MarginalPosterior(A, base, prior_var, [prior] * 3, groups=two, cells=5, sigma_max=[1.5] * 3,
                             sigma_min=[0.0] * 3)
    assert chol._blocks is None
    got = chol.log_joint(y[None])[:, 0]
    S0 = (A * prior_var) @ A.T
    for g in range(0, len(chol.sigma), 17):
        want = stats.multivariate_normal(np.zeros(m), S0 + np.diag(chol.V[g])).logpdf(y) + chol.log_prior[g]
        assert got[g] == pytest.approx(want, rel=1e-9)
    blocks = MarginalPosterior(A, base, prior_var, [prior] * 2, groups=two - 1, cells=5, sigma_max=[1.5] * 2,
                               sigma_min=[0.0] * 2)
    assert blocks._blocks is not None
    # the same two observed scales: chol's cells with σ0 at its first cell are blocks' cells, in the same order
    np.testing.assert_allclose(blocks.log_joint(y[None])[:, 0] - blocks.log_prior,
                               (got - chol.log_prior)[:25], rtol=1e-9)


def test_first_use_solves_and_later_uses_multiply_alike_and_a_kept_joint_is_never_stale(thesis):
    """A fresh grid's first ``target_moments`` (one solve for the residuals and the targets) equals one made with
    ``L⁻¹`` already at hand, to 1e-9; the log joint kept for the last data vector is returned for it alone, and a
    caller changing the array it got changes nothing kept."""
    post = LogPosterior(thesis, "linear", data="both")

    prior_var = np.array([q.sd for q in post.priors.priors[: post.p]]) ** 2

    def fresh():
        return MarginalPosterior(post.forward.design, post.likelihood.base_var, prior_var,
                                 [q.frozen() for q in post.priors.priors[post.p:]], groups=post.scale_of,
                                 y=post.likelihood.y, cells=12)

    y1 = post.likelihood.y
    y2 = y1 + np.random.default_rng(6).normal(scale=2e-3, size=y1.shape)
    T = np.random.default_rng(7).normal(size=(3, post.p))
    solved, inverted = fresh(), fresh()
    inverted._whitening  # L⁻¹ made before any use
    for a, b in zip(solved.target_moments(y1[None], T), inverted.target_moments(y1[None], T)):
        np.testing.assert_allclose(a, b, rtol=1e-9)
    ref = {k: fresh().log_joint(y[None]) for k, y in (("y1", y1), ("y2", y2))}
    m = fresh()
    got = m.log_joint(y1[None])
    got += 1.0  # the caller's copy
    # to round-off (the first use solves, the later ones multiply by L⁻¹); the two data vectors' joints differ by
    # far more than that
    close = dict(rtol=1e-9, atol=1e-9 * np.abs(ref["y1"]).max())
    assert np.abs(ref["y1"] - ref["y2"]).max() > 1e3 * close["atol"]
    np.testing.assert_allclose(m.log_joint(y1[None]), ref["y1"], **close)
    np.testing.assert_allclose(m.log_joint(y2[None]), ref["y2"], **close)
    np.testing.assert_allclose(m.log_joint(y1[None]), ref["y1"], **close)
    assert m.log_evidence(y2) == pytest.approx(fresh().log_evidence(y2), rel=1e-9)


def test_exact_draws_factor_only_the_cells_drawn_and_equal_numpys_multivariate_normal(thesis):
    """``MarginalPosterior.draw`` factors only the cells it draws from their precision; its draws are those of
    ``Generator.multivariate_normal(mean, cov, method="cholesky")`` of each cell's posterior, with the same seed,
    to 1e-9 of their spread."""
    post = LogPosterior(thesis, "linear", data="both")
    m = PosteriorApproximation(post).marginal
    y = post.likelihood.y
    theta, sigma = m.draw(y, 3000, np.random.default_rng(11))
    rng = np.random.default_rng(11)
    g = rng.choice(len(m.sigma), size=3000, p=m.weights(y[None])[:, 0])
    means = m.means(y[None])[:, 0]
    want = np.empty_like(theta)
    for k in np.unique(g):
        idx = np.flatnonzero(g == k)
        want[idx] = rng.multivariate_normal(means[k], m.cov[k], size=len(idx), method="cholesky")
    assert (np.abs(theta - want) / theta.std(axis=0)).max() <= 1e-9  # each parameter in its own posterior sd
    assert len(np.unique(g)) < len(m.sigma)  # fewer cells factored than the grid has
    # a cell's factors do not depend on the cells made with it (a draw does not depend on the draws before it)
    some, more = np.array([3, 500, 901]), np.arange(0, 1200, 1)
    assert np.array_equal(m.cov_factors(some)[0], m.cov_factors(more)[0][some])


def test_linear_approximation_is_exact_and_its_grid_follows_the_data(thesis):
    """Data that only a sigma_model far beyond the prior's 0.99999 quantile explains (50 µm noise added, seeded):
    the grid reaches where they put sigma_model, and its posterior mean and sd of sigma_model are those of an
    independent quadrature (scipy.integrate.quad of scipy.stats.multivariate_normal), within 1e-4 posterior sd."""
    post = LogPosterior(thesis, "linear")
    a = PosteriorApproximation(post)
    assert a.exact and a.kind == "exact σ-marginal posterior"
    sigma_prior = post.priors.priors[-1].frozen()
    assert a.marginal.edges[0][-1] >= sigma_prior.ppf(0.99999)

    y = post.likelihood.y + np.random.default_rng(8).normal(scale=0.05, size=len(post.likelihood.y))
    far = PosteriorApproximation(post.with_means(y)).marginal
    (mean,), (sd,) = far.sigma_moments(y)
    A, base = post.forward.design, post.likelihood.base_var
    S0 = (A * np.array([q.sd for q in post.priors.priors[: post.p]]) ** 2) @ A.T

    def log_post(s):
        return stats.multivariate_normal(cov=S0 + np.diag(base + s * s)).logpdf(y) + sigma_prior.logpdf(s)

    mode = 0.015  # mm, near the quadrature's peak; only normalises the integrand
    def moment(k):
        return integrate.quad(lambda s: s**k * np.exp(log_post(s) - log_post(mode)), 0, 0.2, points=[mode],
                              limit=200)[0]

    z = moment(0)
    ref_mean = moment(1) / z
    ref_sd = np.sqrt(moment(2) / z - ref_mean**2)
    assert mean > 1.5 * sigma_prior.ppf(0.99999)  # the data, not the prior, place sigma_model
    assert far.edges[0][-1] > mean + 8 * sd
    assert abs(mean - ref_mean) < 1e-4 * ref_sd and abs(sd / ref_sd - 1) < 1e-4


def test_the_proposal_factors_its_cells_without_forming_their_covariance(thesis):
    """The grid proposal's factors come from each cell's precision (the fused posterior: 2 304 cells of two
    scales; only the cells of some weight): the lower Cholesky factor of the covariance, its inverse and the cell
    means, each equal to the covariance way (``numpy.linalg.inv`` of the precision, then ``cholesky``) to 1e-9 of
    its largest entry."""
    a = PosteriorApproximation(LogPosterior(thesis, "linear", data="both"))
    m, prop = a.marginal, a.proposal
    assert len(m.sigma) == 48 * 48
    kept = prop.kept  # only the cells of some weight are factored
    assert 0 < len(kept) < len(m.sigma) and (prop.cell_prob[prop.slot < 0] == 0).all()
    chol = np.linalg.cholesky(m.cov[kept])
    for got, want in ((prop.chol, chol), (prop.chol_inv, np.linalg.inv(chol)),
                      (prop.mean, m.means(a.post.likelihood.y[None])[kept, 0])):
        assert np.abs(got - want).max() <= 1e-9 * np.abs(want).max()
    assert np.all(np.triu(prop.chol, 1) == 0) and np.all(np.diagonal(prop.chol, axis1=1, axis2=2) > 0)


def test_kinematic_approximation_is_its_linearisation(thesis):
    post = LogPosterior(thesis, "htm-thesis")
    a = PosteriorApproximation(post)
    assert not a.exact and a.kind == "linearised posterior"
    lin = PosteriorApproximation(LogPosterior(thesis, "linear"))
    names = list(IDENTIFIABLE)
    ma, ml = a.moments(names), lin.moments(names)
    for n in names:  # thesis magnitudes: the htm-thesis posterior linearised is the linear one, within 0.05 sd
        assert abs(ma[n][0] - ml[n][0]) < 0.05 * ml[n][1], n


# --------------------------------------------------------------------------- the sampler
def _eight_moments(result, post):
    s = summarize(to_inference_data(result, seed=0), post)
    return {n: (s.loc[n, "mean"], s.loc[n, "sd"]) for n in IDENTIFIABLE}


def test_hastings_correction_keeps_a_wrong_proposal_exact(thesis, monkeypatch):
    """Independence moves only, from an approximation shifted by 0.5 (Mahalanobis) along a random direction and
    15 % too narrow in every direction: the Metropolis–Hastings test must still give the exact posterior (means
    within 0.1 sd, sds within 5 %, i.e. about 4 MCSE at ESS 3000), and accept less often than the right proposal.
    Without the Hastings factor the same run gives sds 35 % too small (checked by hand when the test was written)."""
    import mtmcal_bayes.inference.sampling as sampling

    post = LogPosterior(thesis, "linear", sigma_model=0.4e-3)
    right = run_ensembles(post, SamplerSettings(seed=3, independence_weight=1.0))
    exact = right.approximation.moments(list(IDENTIFIABLE))

    class Wrong(PosteriorApproximation):
        def __init__(self, p):
            super().__init__(p)
            g = self.proposal
            u = np.random.default_rng(0).normal(size=g.P)
            g.mean = g.mean + 0.5 * np.einsum("kij,j->ki", g.chol, u / np.linalg.norm(u))
            g.chol, g.chol_inv = 0.85 * g.chol, g.chol_inv / 0.85
            g.log_det = g.log_det + 2 * g.P * np.log(0.85)

    monkeypatch.setattr(sampling, "PosteriorApproximation", Wrong)
    wrong = run_ensembles(post, SamplerSettings(seed=3, independence_weight=1.0, target_ess=3000))
    assert wrong.converged
    assert wrong.independence_acceptance < right.independence_acceptance - 0.2
    got = _eight_moments(wrong, post)
    for n in IDENTIFIABLE:
        m, s = exact[n]
        assert abs(got[n][0] - m) < 0.1 * s, (n, got[n], exact[n])
        assert abs(got[n][1] / s - 1) < 0.05, (n, got[n], exact[n])


def test_a_start_not_forgotten_is_detected(thesis, monkeypatch):
    """Walkers started 6 posterior sd away, DE moves only: the time-split R-hat sees the start, the burn-in
    grows beyond 2τ, and the kept draws still match the exact posterior (means within 0.15 sd)."""
    import mtmcal_bayes.inference.sampling as sampling

    post = LogPosterior(thesis, "linear", sigma_model=0.4e-3)
    starts = sampling._starts

    def far_starts(p, approx, n, random):
        z = starts(p, approx, n, random)
        return z + 6.0 * z.std(axis=0)

    monkeypatch.setattr(sampling, "_starts", far_starts)
    r = run_ensembles(post, SamplerSettings(seed=4, independence_weight=0.0, max_steps=4000))
    assert r.checks[0].max_rhat > 1.01 or r.checks[0].burn > 2 * np.nanmax(r.tau) + 1
    assert r.burn >= r.n_steps // 4 and r.converged
    exact = r.approximation.moments(list(IDENTIFIABLE))
    got = _eight_moments(r, post)
    for n in IDENTIFIABLE:
        assert abs(got[n][0] - exact[n][0]) < 0.15 * exact[n][1], n


def test_exact_sampler_draws_the_exact_posterior(thesis):
    """--sampler exact: independent draws whose moments are the reference's (means within 0.05 sd, sds 4 %)."""
    post = LogPosterior(thesis, "linear")
    r = run_ensembles(post, SamplerSettings(seed=5, sampler="exact"))
    assert r.converged and r.chains.shape[2] == 1 and r.burn == 0
    exact = r.approximation.moments(list(IDENTIFIABLE))
    got = _eight_moments(r, post)
    for n in IDENTIFIABLE:
        assert abs(got[n][0] - exact[n][0]) < 0.05 * exact[n][1], n
        assert abs(got[n][1] / exact[n][1] - 1) < 0.04, n


def test_exact_sampler_refuses_the_kinematic_models(thesis):
    from mtmcal_bayes.errors import ParameterError

    with pytest.raises(ParameterError, match="exact"):
        run_ensembles(LogPosterior(thesis, "htm-thesis"), SamplerSettings(sampler="exact"))


def test_campaign_without_second_tool_length_still_converges_quickly():
    """Not identified is not hard to sample: the linearised posterior is still the posterior."""
    c = parse_campaign(variants.without_second_tool_length(), "no_cr2.toml")
    r = run_ensembles(LogPosterior(c, "linear"), SamplerSettings(seed=6))
    assert r.converged and r.n_steps == 50 and r.independence_acceptance > 0.9


# --------------------------------------------------------------------------- the kinematic chain
def test_kinematic_chunks_are_the_whole_batch(thesis):
    """A batch larger than the chunk gives the rows it gives one chunk at a time (memory bound, same numbers)."""
    m = HTMModel(thesis, "htm-thesis")
    rows = CHUNK_POINTS // len(m.points().length)  # the rows of one chunk
    theta = np.random.default_rng(7).normal(size=(rows + 37, len(m.space))) * m.space.display_scale() * 30
    whole = m.predict(theta)
    parts = np.vstack([m.predict(theta[:50]), m.predict(theta[50:])])
    np.testing.assert_allclose(whole, parts, rtol=0, atol=1e-15)


def test_derived_weights_reach_the_reference(thesis):
    """dx_CZ − dx_BT's reference moments come from the parameter layer's weights."""
    post = LogPosterior(thesis, "linear")
    a = PosteriorApproximation(post)
    m = a.moments(["dx_CZ", "dx_BT", "dx_CZ_minus_dx_BT"])
    assert weights("dx_CZ_minus_dx_BT") == {"dx_CZ": 1.0, "dx_BT": -1.0}
    assert m["dx_CZ_minus_dx_BT"][1] < min(m["dx_CZ"][1], m["dx_BT"][1])  # the combination is what the data fix
