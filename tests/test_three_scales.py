"""The σ-marginal posterior of three discrepancy scales (ball bar, touch probe, R-test), made scale by scale
(:data:`mtmcal_bayes.inference.marginal.BY_SCALE`): against references written cell by cell here, and its default
grid's quadrature against a finer grid, on the nutating head's demo and on a trunnion campaign with every instrument.

The references are independent of the scale-by-scale algebra: each cell's prior predictive covariance and posterior
precision written out in full and given to scipy/numpy.  Tolerances: the round-off of the algebra (1e-9 relative,
1e-6 nats on log densities of ~100 nats, as tests/test_sampler.py states), and the module's stated quadrature error,
1e-3 of the posterior sd, for the default grid against a finer one.
"""

import numpy as np
import pytest
from scipy import linalg, stats

from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.inference.marginal import BY_SCALE, GridProposal, MarginalPosterior
from mtmcal_bayes.io import parse_campaign

from .rtest_campaigns import with_every_instrument_text

MACHINES = ("nutating-head", "trunnion")


@pytest.fixture(scope="module", params=MACHINES)
def every_instrument(request):
    """The linear posterior of the machine's campaign with every instrument, and its marginal's arguments."""
    post = LogPosterior(parse_campaign(with_every_instrument_text(request.param)), "linear", data="all")
    priors = post.priors.priors[: post.p]
    args = (post.forward.design, post.likelihood.base_var, np.array([q.sd for q in priors]) ** 2,
            [q.frozen() for q in post.priors.priors[post.p:]])
    kwargs = {"prior_mean": np.array([q.mean for q in priors]), "groups": post.scale_of, "y": post.likelihood.y}
    return post, args, kwargs


def _deviation_rows(post) -> np.ndarray:
    """Unit rows picking the machine's deviations out of θ, ``(d, P)``."""
    idx = [i for i, p in enumerate(post.space.parameters[: post.p]) if p.group == "deviation"]
    return np.eye(post.p)[idx]


def test_a_campaign_with_every_instrument_has_three_scales_made_scale_by_scale(every_instrument):
    post, args, kwargs = every_instrument
    m = MarginalPosterior(*args, **kwargs, cells=4)
    assert len(post.scales) == 3 >= BY_SCALE and np.array_equal(np.unique(post.scale_of), [0, 1, 2])
    assert m._by_scale and m._blocks is not None and m._blocks.inner is not None  # the others' block by blocks


def test_three_scales_log_joint_moments_and_precisions_equal_each_cell_written_out(every_instrument):
    """On a grid of 5³ cells: each cell's ``log p(y | σ) + log p(σ)`` is scipy's multivariate normal of the data
    under ``S0 + diag(base + σ_g²)`` plus the log prior; each cell's posterior precision is
    ``Σ0⁻¹ + Aᵀ V⁻¹ A`` written out; the deviations' posterior means and sds are the mixture of the cells'
    Gaussian posteriors (each from numpy's inverse of its precision) weighted by those joints, and so is the
    posterior mean of θ."""
    post, args, kwargs = every_instrument
    m = MarginalPosterior(*args, **kwargs, cells=5)
    A, base, prior_var = args[:3]
    r = post.likelihood.y - A @ kwargs["prior_mean"]
    S0 = (A * prior_var) @ A.T
    V = base[None] + m.sigma[:, post.scale_of] ** 2  # (G, m)
    want_joint = np.array([stats.multivariate_normal(np.zeros(len(r)), S0 + np.diag(v)).logpdf(r) for v in V])
    want_joint += m.log_prior
    got_joint = m.log_joint(post.likelihood.y[None])[:, 0]
    np.testing.assert_allclose(got_joint, want_joint, rtol=1e-9, atol=1e-6)

    precision = np.diag(1.0 / prior_var)[None] + np.einsum("mp,gm,mq->gpq", A, 1.0 / V, A)
    cells = np.array([0, 31, 62, 124])
    np.testing.assert_allclose(m._precision_of(cells), precision[cells], rtol=1e-12,
                               atol=1e-12 * np.abs(precision).max())

    T = _deviation_rows(post)
    cov = np.linalg.inv(precision)  # (G, P, P)
    mean_g = kwargs["prior_mean"] + np.einsum("gpq,qm,gm->gp", cov, A.T, r[None] / V)
    w = np.exp(want_joint - want_joint.max())
    w /= w.sum()
    tm = mean_g @ T.T  # (G, d)
    tv = np.einsum("dp,gpq,dq->gd", T, cov, T)
    want_mean = w @ tm
    want_sd = np.sqrt(w @ (tm**2 + tv) - want_mean**2)
    mean, sd = m.target_moments(post.likelihood.y[None], T)
    assert np.max(np.abs(mean[0] - want_mean) / want_sd) < 1e-9
    np.testing.assert_allclose(sd[0], want_sd, rtol=1e-9)
    # the posterior mean of every parameter (a kinematic model's next linearisation point), in its posterior sd
    theta_sd = np.sqrt(w @ (mean_g**2 + np.diagonal(cov, axis1=1, axis2=2)) - (w @ mean_g) ** 2)
    assert np.max(np.abs(m.posterior_mean(post.likelihood.y) - w @ mean_g) / theta_sd) < 1e-9


def test_default_three_scale_grid_gives_the_moments_of_a_finer_grid(every_instrument):
    """The default grid (48 cells per scale, 110 592 cells) against one of 72 per scale (3.4 times as many): the
    deviations' posterior means and sds agree within 1e-3 of the posterior sd, the quadrature error the module
    states, although the scales of the nutating head's demo are piled against 0 (its first cells hold 2–23 % of
    each scale's mass)."""
    post, args, kwargs = every_instrument
    T = _deviation_rows(post)
    y = post.likelihood.y[None]
    coarse = MarginalPosterior(*args, **kwargs).target_moments(y, T)
    fine = MarginalPosterior(*args, **kwargs, cells=72).target_moments(y, T)
    sd = fine[1][0]
    assert np.max(np.abs(coarse[0][0] - fine[0][0]) / sd) < 1e-3
    assert np.max(np.abs(coarse[1][0] - sd) / sd) < 1e-3


def test_three_scale_proposal_factors_cells_when_used_as_all_at_once(every_instrument):
    """The proposal factors a cell when first drawn or evaluated: those cells' factors and means equal the
    marginal's factors of the same cells made in one go (to rounding), its draws are ``μ_j + C_j z``, and its
    log density at the draws is the cell's probability times the normal density of the cell's posterior
    (covariance ``C Cᵀ``, by a triangular solve with ``C``) times the uniform density of σ in the cell."""
    post, args, kwargs = every_instrument
    m = MarginalPosterior(*args, **kwargs, cells=6)
    prop = GridProposal(m, post.likelihood.y)
    assert not prop._have.any()  # nothing factored before it is used
    theta, sigma = prop.draw(200, np.random.RandomState(3))
    have = np.flatnonzero(prop._have)
    assert 0 < len(have) < len(prop.kept)
    np.testing.assert_array_equal(have, np.arange(len(have)))  # the factored cells fill the first slots
    cells = prop.cells[have]
    assert set(cells) <= set(prop.kept) and (prop.slot[cells] == have).all()
    chol, _ = m.cov_factors(cells)
    np.testing.assert_allclose(prop.chol[have], chol, rtol=0, atol=1e-12 * np.abs(chol).max())
    np.testing.assert_allclose(prop.mean[have], m.means_from_factors(post.likelihood.y, chol, cells),
                               rtol=1e-12, atol=1e-12 * np.abs(prop.mean[have]).max())
    r = np.random.RandomState(3)
    j = r.choice(prop.cell_prob.size, size=200, p=prop.cell_prob)
    r.rand(200, 3)
    z = r.randn(200, prop.P)
    k = prop.slot[j]
    np.testing.assert_allclose(theta, prop.mean[k] + np.einsum("nij,nj->ni", prop.chol[k], z), rtol=0,
                               atol=1e-12 * np.abs(theta).max())
    got = prop.logpdf(theta[:20], sigma[:20])

    def normal(i):  # the cell's normal density by a triangular solve with its factor (not the kept inverse)
        C = prop.chol[k[i]]
        u = linalg.solve_triangular(C, theta[i] - prop.mean[k[i]], lower=True)
        return -0.5 * u @ u - np.log(np.diag(C)).sum() - 0.5 * prop.P * np.log(2 * np.pi)

    want = [np.log(prop.cell_prob[j[i]]) - np.log(prop.width[j[i]]).sum() + normal(i) for i in range(20)]
    np.testing.assert_allclose(got, want, rtol=1e-9)


@pytest.mark.parametrize("scales", [1, 2, 3])
def test_moments_of_many_data_vectors_equal_each_vectors_own(every_instrument, scales):
    """A design's check asks the moments of hundreds of simulated data vectors at once, from the whitened inner
    products (:meth:`_BlockWhitening.inner_pairs`); one data vector's moments (below three scales) come from each cell's
    whitened data.  The two agree to the algebra's round-off (1e-9 relative) on one, two and three scales."""
    post, (A, base, prior_var, priors), kwargs = every_instrument
    groups = np.minimum(post.scale_of, scales - 1)
    m = MarginalPosterior(A, base, prior_var, priors[:scales], prior_mean=kwargs["prior_mean"], groups=groups,
                          y=kwargs["y"], cells={1: None, 2: 12, 3: 5}[scales])
    rng = np.random.default_rng(3)
    y = kwargs["y"][None] + rng.normal(0.0, 1e-3, (6, len(kwargs["y"])))
    T = _deviation_rows(post)
    mean, sd = m.target_moments(y, T)
    one = [m.target_moments(y[i:i + 1], T) for i in range(len(y))]
    np.testing.assert_allclose(mean, np.vstack([o[0] for o in one]), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sd, np.vstack([o[1] for o in one]), rtol=1e-9, atol=1e-12)
