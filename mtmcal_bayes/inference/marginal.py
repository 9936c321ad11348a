"""The posterior of a linear-Gaussian model with the noise scale sigma_model marginalised on a grid.

For a linear model ``y ~ N(c + Aθ, diag(b + σ²))`` with normal priors
``θ ~ N(μ0, diag v0)`` the posterior with ``σ`` = sigma_model unknown is a
mixture over σ of Gaussian posteriors, weighted by the marginal likelihood
``p(y | σ)·p(σ)``.  :class:`MarginalPosterior` evaluates it on a quadrature grid:
``G`` cells of equal width on ``[0, σ_max]`` (σ_max the 0.99999 quantile of the
prior), each represented by its midpoint.  The moments of θ are then exact to
the quadrature error, which is below 1e-4 of the posterior sd (96, 400 and
2 000 cells agree to that on the thesis campaign).

For the ``linear`` model this is the exact posterior: the reference the sampler
is checked against, the exact sampler of ``sample --sampler exact`` and of
simulation-based calibration, and the Monte-Carlo preposterior of the planner.
For a kinematic model, built on the model linearised at a point (``A`` its
Jacobian, ``c`` its offset), it is the linearised posterior from which the
sampler starts and proposes (:mod:`.approximation`).

:class:`GridProposal` is that mixture for one data vector as a continuous
density: a cell drawn by its weight, σ uniform within it, θ from the cell's
Gaussian.  Its draws and log-density make an independence Metropolis–Hastings
proposal.
"""

from __future__ import annotations

import math

import numpy as np

#: quadrature cells of sigma_model
GRID = 128
#: the scan of :func:`sigma_upper` runs from this fraction of the prior's 0.99999 quantile to this multiple of
#: the largest plausible scale
SCAN_FROM, SCAN_TO = 1e-3, 10.0


class MarginalPosterior:
    """The σ-marginal posterior of a linear-Gaussian model on a grid of σ.

    Parameters
    ----------
    A : (m, P) design matrix, mm per internal unit
    base_var : (m,) variance of each mean without sigma_model, mm²
    prior_var : (P,) prior variances, internal units²
    sigma_prior : frozen scipy distribution of sigma_model (mm), or None with ``sigma_fixed``
    prior_mean : (P,) prior means (default zero)
    offset : (m,) prediction at θ = 0, mm (default zero: a linear, not affine, model)
    sigma_fixed : sigma_model known, mm: one cell of zero width
    sigma_max : upper end of the grid, mm (default the prior's 0.99999 quantile; see :func:`sigma_upper`)
    """

    def __init__(self, A: np.ndarray, base_var: np.ndarray, prior_var: np.ndarray, sigma_prior=None, *,
                 prior_mean: np.ndarray | None = None, offset: np.ndarray | None = None,
                 sigma_fixed: float | None = None, sigma_max: float | None = None):
        P = A.shape[1]
        self.A = A
        self.prior_mean = np.zeros(P) if prior_mean is None else np.asarray(prior_mean, dtype=float)
        self.offset = np.zeros(A.shape[0]) if offset is None else np.asarray(offset, dtype=float)
        if sigma_fixed is not None:
            self.edges = np.array([sigma_fixed, sigma_fixed], dtype=float)
            self.sigma = np.array([float(sigma_fixed)])
            self.log_prior = np.zeros(1)
        else:
            self.edges = np.linspace(0.0, sigma_max or sigma_prior.ppf(0.99999), GRID + 1)
            self.sigma = 0.5 * (self.edges[:-1] + self.edges[1:])  # (G,) midpoints: the prior may be infinite at 0
            self.log_prior = sigma_prior.logpdf(self.sigma)
        V = base_var[None, :] + self.sigma[:, None] ** 2  # (G, m)
        S = (A * prior_var) @ A.T  # (m, m) prior predictive covariance of the means, without noise
        S = S[None] + np.stack([np.diag(v) for v in V])  # (G, m, m)
        self.S_chol = np.linalg.cholesky(S)
        self.S_logdet = 2.0 * np.log(np.diagonal(self.S_chol, axis1=1, axis2=2)).sum(axis=1)
        prec = np.diag(1.0 / prior_var)[None] + np.einsum("mp,gm,mq->gpq", A, 1.0 / V, A)
        self.cov = np.linalg.inv(prec)  # (G, P, P)
        self.cov = 0.5 * (self.cov + np.swapaxes(self.cov, 1, 2))
        self.gain = np.einsum("gpq,mq,gm->gpm", self.cov, A, 1.0 / V)  # (G, P, m): mean = μ0 + gain @ residual

    def _residual(self, y: np.ndarray) -> np.ndarray:
        """Data minus the prediction at the prior mean, ``(N, m)``."""
        return np.atleast_2d(y) - self.offset - self.A @ self.prior_mean

    def weights(self, y: np.ndarray) -> np.ndarray:
        """Posterior weights of the grid, ``(G, N)`` for data ``y`` of shape ``(N, m)``."""
        r = self._residual(y)
        z = np.linalg.solve(self.S_chol[:, None], r[None, :, :, None])[..., 0]  # (G, N, m)
        loglik = -0.5 * (np.sum(z**2, axis=-1) + self.S_logdet[:, None] + r.shape[1] * np.log(2 * np.pi))
        lw = loglik + self.log_prior[:, None]
        lw -= lw.max(axis=0)
        w = np.exp(lw)
        return w / w.sum(axis=0)

    def means(self, y: np.ndarray) -> np.ndarray:
        """Posterior mean of θ in each cell, ``(G, N, P)``."""
        return self.prior_mean + np.einsum("gpm,nm->gnp", self.gain, self._residual(y))

    def target_moments(self, y: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and sd of the targets ``T @ θ``, each ``(N, t)``, for data ``(N, m)``."""
        w = self.weights(y)  # (G, N)
        mean_g = np.einsum("tp,gnp->gnt", T, self.means(y))  # (G, N, t)
        var_g = np.einsum("tp,gpq,tq->gt", T, self.cov, T)  # (G, t)
        mean = np.einsum("gn,gnt->nt", w, mean_g)
        second = np.einsum("gn,gnt->nt", w, mean_g**2 + var_g[:, None, :])
        return mean, np.sqrt(np.maximum(second - mean**2, 0.0))

    def sigma_moments(self, y: np.ndarray) -> tuple[float, float]:
        """Posterior mean and sd of sigma_model (mm) for one data vector ``y`` (m,)."""
        w = self.weights(y[None])[:, 0]
        mean = float(w @ self.sigma)
        return mean, float(np.sqrt(max(w @ self.sigma**2 - mean**2, 0.0)))

    def draw(self, y: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws ``(theta (n, P), sigma (n,))`` from the posterior given data ``y`` (m,), σ at the midpoints."""
        w = self.weights(y[None])[:, 0]
        g = rng.choice(len(self.sigma), size=n, p=w)
        means = self.means(y[None])[:, 0]
        theta = np.empty((n, self.A.shape[1]))
        for k in np.unique(g):  # one Cholesky per grid point used, not per draw
            idx = np.flatnonzero(g == k)
            theta[idx] = rng.multivariate_normal(means[k], self.cov[k], size=len(idx), method="cholesky")
        return theta, self.sigma[g]


def sigma_upper(A: np.ndarray, base_var: np.ndarray, prior_var: np.ndarray, sigma_prior, *, y: np.ndarray,
                prior_mean: np.ndarray | None = None, offset: np.ndarray | None = None, drop: float = 30.0) -> float:
    """Upper end of a σ grid covering the posterior of σ given ``y``, mm: the prior's 0.99999 quantile, or beyond it
    where the data put σ (a model that cannot fit them: σ in the prior's far tail); the σ at which the marginal
    posterior has fallen ``drop`` nats below its maximum, on a log-spaced scan."""
    prior_hi = float(sigma_prior.ppf(0.99999))
    P = A.shape[1]
    r = y - (np.zeros(A.shape[0]) if offset is None else offset) - A @ (np.zeros(P) if prior_mean is None else prior_mean)
    top = max(prior_hi, 10.0 * float(np.sqrt(np.mean(r**2))))
    scan = np.geomspace(prior_hi * SCAN_FROM, top * SCAN_TO, 400)
    S0 = (A * prior_var) @ A.T
    S = S0[None] + np.stack([np.diag(base_var + s**2) for s in scan])
    L = np.linalg.cholesky(S)
    z = np.linalg.solve(L, np.broadcast_to(r, (len(scan), len(r)))[..., None])[..., 0]
    with np.errstate(divide="ignore"):
        logp = -0.5 * np.sum(z**2, axis=1) - np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1) + sigma_prior.logpdf(scan)
    above = np.flatnonzero(logp >= logp.max() - drop)
    return max(prior_hi, float(scan[min(above[-1] + 1, len(scan) - 1)]))


class GridProposal:
    """The grid posterior of one data vector as a continuous density of ``(θ, σ)``.

    A cell ``j`` drawn with probability ``w_j``, σ uniform within it, θ ~ N(μ_j, Σ_j);
    ``log g(θ, σ)`` is that density for the cell holding σ (−inf beyond the grid); with a
    fixed σ there is one cell and no σ dimension.  No heavier-tailed defensive component
    is mixed in: on the thesis campaign it cost 10 % of the effective sample size and, in
    24 dimensions, did not rescue a proposal that was badly wrong (the acceptance stayed
    near zero either way).  A poor proposal shows instead as a low independence acceptance,
    the differential-evolution moves carry the chains, and R-hat and ESS decide as usual.
    """

    def __init__(self, marginal: MarginalPosterior, y: np.ndarray):
        self.fixed = marginal.edges[0] == marginal.edges[-1]
        w = marginal.weights(y[None])[:, 0]
        keep = w > 1e-12 * w.max()  # cells of no weight are never drawn; their density is −inf
        self.cell_prob = np.where(keep, w, 0.0) / w[keep].sum()  # (G,)
        with np.errstate(divide="ignore"):
            self.log_cell_prob = np.log(self.cell_prob)
        self.edges = marginal.edges
        self.sigma = marginal.sigma
        self.mean = marginal.means(y[None])[:, 0]  # (G, P)
        self.chol = np.linalg.cholesky(marginal.cov)  # (G, P, P)
        self.chol_inv = np.linalg.inv(self.chol)
        self.log_det = 2.0 * np.log(np.diagonal(self.chol, axis1=1, axis2=2)).sum(axis=1)
        self.P = self.mean.shape[1]

    def draw(self, n: int, random) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws ``(theta (n, P), sigma (n,))``; ``random`` a numpy RandomState (emcee's)."""
        j = random.choice(self.cell_prob.size, size=n, p=self.cell_prob)
        sigma = (self.edges[j] + (self.edges[j + 1] - self.edges[j]) * random.rand(n) if not self.fixed
                 else np.full(n, self.sigma[0]))
        theta = self.mean[j] + np.einsum("nij,nj->ni", self.chol[j], random.randn(n, self.P))
        return theta, sigma

    def logpdf(self, theta: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """Log-density ``(n,)`` of ``theta`` (n, P) and ``sigma`` (n,) (without the σ width when σ is fixed)."""
        if self.fixed:
            j = np.zeros(len(theta), dtype=int)
            inside = np.ones(len(theta), dtype=bool)
            log_width = np.zeros(len(theta))
        else:
            j = np.clip(np.searchsorted(self.edges, sigma, side="right") - 1, 0, self.cell_prob.size - 1)
            inside = (sigma >= self.edges[0]) & (sigma < self.edges[-1])
            log_width = np.log(self.edges[j + 1] - self.edges[j])
        u = np.einsum("nij,nj->ni", self.chol_inv[j], theta - self.mean[j])
        r2 = np.einsum("ni,ni->n", u, u)
        log_norm = -0.5 * self.log_det[j] - 0.5 * self.P * math.log(2 * math.pi)
        return np.where(inside, self.log_cell_prob[j] + log_norm - 0.5 * r2 - log_width, -np.inf)
