"""Rows reduced to their rank (:class:`mtmcal_bayes.inference.row_reduction.RowReduction`): the reduced model with
the rest of the likelihood (:meth:`~mtmcal_bayes.inference.row_reduction.RowReduction.log_rest`, as
:class:`~mtmcal_bayes.inference.row_reduction.RestTerms` or made dense) gives every cell the full model's weight and
every target the full model's posterior mean and sd, for many data vectors at once, on a grid of three scales.

Tolerance: the round-off of the algebra, 1e-9 relative on the moments and 1e-12 absolute on weights that sum to one.
"""

import numpy as np
from scipy import stats

from mtmcal_bayes.inference.marginal import MarginalPosterior
from mtmcal_bayes.inference.row_reduction import RestTerms, RowReduction


def _model(seed: int = 3):
    """Readings of three scales in blocks of one base variance each, many more rows than the parameters: ``A``
    (m, P), base variances, scales, prior variances, priors of the scales, targets (t, P), data (N, m)."""
    rng = np.random.default_rng(seed)
    P = 6
    blocks = [(0, 1e-6, 12), (0, 4e-6, 9), (1, 2e-6, 15), (2, 1e-6, 11)]  # (scale, base variance, rows)
    A = np.vstack([rng.standard_normal((n, 3)) @ rng.standard_normal((3, P)) for *_, n in blocks])  # rank 3 each
    base = np.concatenate([np.full(n, b) for _, b, n in blocks])
    groups = np.concatenate([np.full(n, g) for g, _, n in blocks])
    prior_var = rng.uniform(0.5, 2.0, P) * 1e-6
    priors = [stats.halfnorm(scale=s) for s in (2e-3, 1e-3, 3e-3)]
    theta = rng.standard_normal((5, P)) * np.sqrt(prior_var)
    scales = np.array([1.5e-3, 0.5e-3, 2e-3])[groups]
    y = theta @ A.T + rng.standard_normal((5, len(A))) * np.sqrt(base + scales**2)
    return A, base, groups, prior_var, priors, rng.standard_normal((2, P)), y


def test_the_reduced_rows_and_the_rest_give_the_full_posterior():
    A, base, groups, prior_var, priors, T, y = _model()
    rows = RowReduction(A, base, groups)
    assert len(rows.A) == 12  # each block of 9–15 rows is rank 3
    kw = dict(sigma_min=[1e-4] * 3, sigma_max=[6e-3] * 3, cells=10)
    full = MarginalPosterior(A, base, prior_var, priors, groups=groups, **kw)
    reduced = MarginalPosterior(rows.A, rows.base_var, prior_var, priors, groups=rows.groups, **kw)
    np.testing.assert_array_equal(full.sigma, reduced.sigma)
    rest = rows.log_rest(y, reduced.sigma)
    assert isinstance(rest, RestTerms)
    mean_f, sd_f, w_f = full.target_moments(y, T, with_weights=True)
    y_r = rows.data(y)
    for extra in (rest, rest.dense()):  # the terms folded into the weights, or added as a (G, N) array
        mean_r, sd_r, w_r = reduced.target_moments(y_r, T, log_extra=extra, with_weights=True)
        np.testing.assert_allclose(w_r, w_f, atol=1e-12)
        np.testing.assert_allclose(mean_r, mean_f, rtol=1e-9)
        np.testing.assert_allclose(sd_r, sd_f, rtol=1e-9)
    np.testing.assert_allclose(reduced.weights(y_r, log_extra=rest), w_f, atol=1e-12)
    # the rest is what tells the scales apart here: without it the weights are not the full model's
    assert np.abs(reduced.target_moments(y_r, T, with_weights=True)[2] - w_f).max() > 1e-3
