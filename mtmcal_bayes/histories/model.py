"""The drift model of a machine's history: deviations as Gaussian random walks, observed campaign by campaign.

States: the deviations ``x_t`` (d,) at each campaign date t (years ``τ_t`` since the first).  The first is
drawn from the deviation priors, N(μ0, diag(v0)); between campaigns each deviation j takes a Gaussian
random-walk step, ``x_{t+1} − x_t ~ N(0, q_j²·(τ_{t+1} − τ_t))``: ``q_j`` is its drift rate (per √year).

Observations: campaign t's means ``y_t = c_t + A_t x_t + B_t n_t + e_t`` (the linear model of that campaign),
with its own set-up offsets ``n_t`` (the W ball is clamped anew, the T ball re-centred: independent per
campaign, from their priors) and noise ``e_t ~ N(0, diag(base_var_t) + σ²·I)``, ``σ`` the model discrepancy
shared by all campaigns.  The offsets are Gaussian and independent of everything else, so they are
integrated out exactly: ``R_t = B_t P_n B_tᵀ + diag(base_var_t)``.

Given the scales (q, σ) the whole history is one linear-Gaussian system.  Stacking the campaigns,
``y ~ N(H μ_X, H Σ_X(q) Hᵀ + R + σ² I)`` with ``Cov(x_{s,j}, x_{t,j}) = v0_j + q_j²·min(τ_s, τ_t)``: the
marginal likelihood of the scales and the posterior of every state at every date jointly are exact (the
same answer a Kalman filter and RTS smoother give, computed in one step since a history has tens of
campaigns, not thousands).  Only the d + 1 scales are sampled (:mod:`.fit`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import MtmcalError
from ..inference.analytic import linearisation
from ..inference.log_posterior import LogPosterior

SECONDS_PER_YEAR = 365.25 * 86400.0


class HistoryModel:
    """The stacked linear-Gaussian system of a history (campaigns sorted by date, ``model`` linear).

    Attributes: ``deviations`` (d names), ``tau`` (T,) years since the first campaign, ``mu0``/``var0`` (d,)
    the deviation priors, ``H`` (M, T·d), ``resid`` (M,) the observations minus their prior mean, ``C0`` (M, M)
    the covariance without the random-walk and σ terms, ``G`` (d, M, M) with ``C = C0 + Σ_j q_j² G_j + σ² I``.
    """

    def __init__(self, campaigns, model: str = "linear"):
        if model != "linear":
            raise MtmcalError(f"the history model is built on the linear model; {model} is not supported yet "
                              "(its campaigns would have to be linearised at their estimates)")
        posts = [LogPosterior(c, "linear") for c in campaigns]
        first = posts[0]
        dev = [i for i, p in enumerate(first.space.parameters) if p.group == "deviation"]
        self.deviations = [first.space.parameters[i].name for i in dev]
        pri = first.priors.priors
        self.mu0 = np.array([pri[i].centre for i in dev])
        self.var0 = np.array([pri[i].sd for i in dev]) ** 2
        self.sigma_prior = first.priors.priors[-1]  # sigma_model's (the last of a sampled-σ posterior)
        t0 = campaigns[0].date
        self.tau = np.array([(c.date - t0).total_seconds() / SECONDS_PER_YEAR for c in campaigns])
        d, T = len(dev), len(campaigns)
        blocks, ys, Rs = [], [], []
        for post in posts:
            names = [p.name for p in post.space.parameters]
            cols = [names.index(n) for n in self.deviations]
            nuis = [i for i, p in enumerate(post.space.parameters) if p.group != "deviation"]
            A, c = linearisation(post)
            prior = post.priors.priors
            vn = np.array([prior[i].sd for i in nuis]) ** 2
            mn = np.array([prior[i].centre for i in nuis])
            B = A[:, nuis]
            blocks.append(A[:, cols])
            ys.append(post.likelihood.y - c - B @ mn)
            Rs.append((B * vn) @ B.T + np.diag(post.likelihood.base_var))
        sizes = [len(y) for y in ys]
        M = sum(sizes)
        self.sizes = sizes
        self.H = np.zeros((M, T * d))
        self.R = np.zeros((M, M))
        row = 0
        for t, (A, R) in enumerate(zip(blocks, Rs)):
            m = len(A)
            self.H[row:row + m, t * d:(t + 1) * d] = A
            self.R[row:row + m, row:row + m] = R
            row += m
        y = np.concatenate(ys)
        self.resid = y - self.H @ np.tile(self.mu0, T)
        self.campaign_of_row = np.repeat(np.arange(T), sizes)
        tmin = np.minimum.outer(self.tau, self.tau)  # (T, T)
        # per deviation j: h_j (M,) its column in every block; prior part v0_j h hᵀ and walk part min(τ)·h hᵀ
        Hj = self.H.reshape(M, T, d).sum(axis=1)  # (M, d): block-diagonal, so the sum picks each row's block
        tm = tmin[self.campaign_of_row][:, self.campaign_of_row]  # (M, M)
        self.C0 = self.R + (Hj * self.var0) @ Hj.T
        self.G = np.einsum("aj,bj,ab->jab", Hj, Hj, tm)
        self.d, self.T, self.M = d, T, M

    def covariance(self, q2: np.ndarray, s2: np.ndarray) -> np.ndarray:
        """``C`` (n, M, M) of the observations for drift rates² ``q2`` (n, d) and σ² ``s2`` (n,)."""
        C = self.C0 + np.einsum("nj,jab->nab", q2, self.G)
        C[:, np.arange(self.M), np.arange(self.M)] += s2[:, None]
        return C

    def log_marginal(self, q2: np.ndarray, s2: np.ndarray) -> np.ndarray:
        """Log marginal likelihood (n,) of the scales: ``log N(resid; 0, C)``, batched Cholesky."""
        C = self.covariance(q2, s2)
        try:
            L = np.linalg.cholesky(C)
        except np.linalg.LinAlgError:  # some rows numerically singular (absurd scales): those get −inf
            return np.array([self.log_marginal(q2[i:i + 1], s2[i:i + 1])[0] if _is_pd(C[i]) else -np.inf
                             for i in range(len(C))])
        z = np.linalg.solve(L, np.broadcast_to(self.resid, (len(C), self.M))[..., None])[..., 0]
        logdet = 2.0 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)
        return -0.5 * (np.einsum("ni,ni->n", z, z) + logdet + self.M * math.log(2 * math.pi))

    def prior_state_cov(self, q2: np.ndarray) -> np.ndarray:
        """Σ_X (n, T·d, T·d): ``v0_j + q_j²·min(τ_s, τ_t)`` between the states of one deviation, 0 across."""
        tmin = np.minimum.outer(self.tau, self.tau)
        n, d, T = len(q2), self.d, self.T
        S = np.zeros((n, T, d, T, d))
        j = np.arange(d)
        S[:, :, j, :, j] = self.var0[:, None, None, None] + q2.T[:, :, None, None] * tmin
        return S.reshape(n, T * d, T * d)

    def state_posterior(self, q2: np.ndarray, s2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean (n, T, d) and covariance (n, T·d, T·d) of every state at every date, given the scales."""
        S = self.prior_state_cov(q2)
        C = self.covariance(q2, s2)
        SH = S @ self.H.T  # (n, Td, M)
        K = np.linalg.solve(C, np.transpose(SH, (0, 2, 1)))  # C⁻¹ H S: (n, M, Td)
        mean = np.tile(self.mu0, self.T) + np.einsum("nmk,m->nk", K, self.resid)
        cov = S - SH @ K
        cov = 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
        return mean.reshape(-1, self.T, self.d), cov


def _is_pd(C: np.ndarray) -> bool:
    try:
        np.linalg.cholesky(C)
        return True
    except np.linalg.LinAlgError:
        return False
