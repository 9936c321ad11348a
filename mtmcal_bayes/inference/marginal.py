"""The exact posterior of the linear model with sigma_model marginalised on a grid.

For the ``linear`` model (zero-mean normal priors, the Gaussian likelihood of
:mod:`.likelihood`) the posterior with ``sigma_model`` unknown is a mixture
over ``sigma_model`` of Gaussian posteriors, weighted by the marginal
likelihood ``p(y | sigma_model)·p(sigma_model)``.  :class:`MarginalPosterior`
evaluates it exactly on a quadrature grid of ``sigma_model`` (no sampling):
the same posterior the emcee sampler targets, for thousands of data sets in
one vectorised call.  It is the reference the sampler is tested against, the
exact sampler of simulation-based calibration and the Monte-Carlo
preposterior of the planner.
"""

from __future__ import annotations

import numpy as np

#: quadrature points of sigma_model
GRID = 96


class MarginalPosterior:
    """Exact posterior of a linear-Gaussian model with the noise scale marginalised on a grid.

    Parameters
    ----------
    A : (m, P) design matrix, mm per internal unit
    base_var : (m,) variance of each mean without sigma_model, mm²
    prior_var : (P,) prior variances (zero-mean normal priors), internal units²
    sigma_prior : frozen scipy distribution of sigma_model, mm
    """

    def __init__(self, A: np.ndarray, base_var: np.ndarray, prior_var: np.ndarray, sigma_prior):
        hi = sigma_prior.ppf(0.99999)
        self.sigma = np.linspace(hi / (2 * GRID), hi, GRID)  # (G,) midpoints: the prior may be infinite at 0
        self.log_prior = sigma_prior.logpdf(self.sigma)
        V = base_var[None, :] + self.sigma[:, None] ** 2  # (G, m)
        self.A = A
        S = (A * prior_var) @ A.T  # (m, m) prior predictive covariance of the means, without noise
        S = S[None] + np.stack([np.diag(v) for v in V])  # (G, m, m)
        self.S_chol = np.linalg.cholesky(S)
        self.S_logdet = 2.0 * np.log(np.diagonal(self.S_chol, axis1=1, axis2=2)).sum(axis=1)
        prec = np.diag(1.0 / prior_var)[None] + np.einsum("mp,gm,mq->gpq", A, 1.0 / V, A)
        self.cov = np.linalg.inv(prec)  # (G, P, P)
        self.gain = np.einsum("gpq,mq,gm->gpm", self.cov, A, 1.0 / V)  # (G, P, m): mean = gain @ y

    def weights(self, y: np.ndarray) -> np.ndarray:
        """Posterior weights of the grid, ``(G, N)`` for data ``y`` of shape ``(N, m)``."""
        z = np.linalg.solve(self.S_chol[:, None], y[None, :, :, None])[..., 0]  # (G, N, m)
        loglik = -0.5 * (np.sum(z**2, axis=-1) + self.S_logdet[:, None] + y.shape[1] * np.log(2 * np.pi))
        lw = loglik + self.log_prior[:, None]
        lw -= lw.max(axis=0)
        w = np.exp(lw)
        return w / w.sum(axis=0)

    def target_moments(self, y: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and sd of the targets ``T @ θ``, each ``(N, t)``, for data ``(N, m)``."""
        w = self.weights(y)  # (G, N)
        Tg = np.einsum("tp,gpm->gtm", T, self.gain)
        mean_g = np.einsum("gtm,nm->gnt", Tg, y)  # (G, N, t)
        var_g = np.einsum("tp,gpq,tq->gt", T, self.cov, T)  # (G, t)
        mean = np.einsum("gn,gnt->nt", w, mean_g)
        second = np.einsum("gn,gnt->nt", w, mean_g**2 + var_g[:, None, :])
        return mean, np.sqrt(np.maximum(second - mean**2, 0.0))

    def draw(self, y: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws ``(theta (n, P), sigma (n,))`` from the posterior given data ``y`` (m,)."""
        w = self.weights(y[None])[:, 0]
        g = rng.choice(len(self.sigma), size=n, p=w)
        theta = np.empty((n, self.A.shape[1]))
        for k in np.unique(g):  # one Cholesky per grid point used, not per draw
            idx = np.flatnonzero(g == k)
            mean = self.gain[k] @ y
            theta[idx] = rng.multivariate_normal(mean, self.cov[k], size=len(idx), method="cholesky")
        return theta, self.sigma[g]
