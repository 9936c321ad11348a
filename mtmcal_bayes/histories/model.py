"""The drift model of a machine's history: deviations as Gaussian random walks, observed campaign by campaign.

States: the deviations ``x_t`` (d,) at each campaign date t (years ``τ_t`` since the first).  The first is
drawn from the deviation priors, N(μ0, diag(v0)); between campaigns each deviation j takes a Gaussian
random-walk step, ``x_{t+1} − x_t ~ N(0, q_j²·(τ_{t+1} − τ_t))``: ``q_j`` is its drift rate (per √year).

Observations: campaign t's means ``y_t = c_t + A_t x_t + B_t n_t + e_t`` (the linear model of that campaign, on
its data: every instrument it has by default, as ``sample``), with its own set-up offsets ``n_t`` (the W ball is
clamped anew, the T ball re-centred, the probe's stylus and sphere and the R-test's sphere, nest and zeros set anew:
independent per campaign, from their priors) and noise ``e_t ~ N(0, diag(base_var_t) + σ_i²)``, ``σ_i`` the model
discrepancy of the reading's instrument (the ball bar's ``sigma_model``, ``sigma_model_probe``,
``sigma_model_rtest``), each shared by all campaigns.  The offsets are Gaussian and independent of everything
else, so they are integrated out exactly: ``R_t = B_t P_n B_tᵀ + diag(base_var_t)``.

Given the scales (q, σ) the whole history is one linear-Gaussian system.  Stacking the campaigns,
``y ~ N(H μ_X, H Σ_X(q) Hᵀ + R + σ² I)`` with ``Cov(x_{s,j}, x_{t,j}) = v0_j + q_j²·min(τ_s, τ_t)``: the
marginal likelihood of the scales and the posterior of every state at every date jointly are exact (the
same answer a Kalman filter and RTS smoother give, computed in one step since a history has tens of
campaigns, not thousands).  Only the d + 1 scales are sampled (:mod:`.fit`).

Two static Gaussian terms keep the system linear-Gaussian:

* **Trend.** A deviation j with a trend drifts at a rate ``r_j ~ N(0, vr_j)`` (per year) on top of its random
  walk: ``x_t = x_0 + r τ_t + w_t``, adding ``vr_j·τ_s·τ_t`` to the states' covariance (``vr_j = 0``: no trend).
* **Temperature.** The states are the deviations at 20 °C; campaign t, measured at ``temperature_C``, sees
  ``x_t + κ·(T_t − 20)`` with a thermal sensitivity ``κ_j ~ N(0, vk_j)`` per °C, adding ``vk_j·ΔT_s·ΔT_t``.

The posterior of the augmented state ``Z = (x_1 … x_T, r, κ)`` is exact in the same way
(:meth:`HistoryModel.augmented_posterior`).
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from ..campaign import REFERENCE_TEMPERATURE_C
from ..inference.analytic import linearisation
from ..inference.log_posterior import LogPosterior
from ..models import default_data
from ..parameters import quantity_unit

SECONDS_PER_YEAR = 365.25 * 86400.0
#: nodes per further discrepancy scale integrated in :meth:`HistoryModel.log_marginal_grid` (equal probability)
OTHER_SCALE_NODES = 8
#: prior sd of a thermal sensitivity, display units per °C
THERMAL_SCALE = {"arcsec": 2.0, "um": 3.0}


class HistoryModel:
    """The stacked linear-Gaussian system of a history (campaigns sorted by date, ``model`` linear).

    Attributes: ``deviations`` (d names), ``tau`` (T,) years since the first campaign, ``mu0``/``var0`` (d,)
    the deviation priors, ``H`` (M, T·d), ``resid`` (M,) the observations minus their prior mean, ``C0`` (M, M)
    the covariance without the random-walk and σ terms, ``G`` (d, M, M) with ``C = C0 + Σ_j q_j² G_j + diag(σ²)``;
    ``scales`` the S discrepancy scales of the instruments the campaigns' data use (the ball bar's first),
    ``scale_of_row`` (M,) each observation's, ``sigma_priors`` their priors (``sigma_prior`` the first's).
    """

    def __init__(self, campaigns, model: str = "linear", *, thermal: bool = True,
                 points: list[np.ndarray] | None = None, data: str | None = None):
        """``thermal``: model the thermal sensitivities (prior sd :data:`THERMAL_SCALE` per °C) when every campaign
        has its ``temperature_C``.  ``points``: per campaign the parameter vector (internal units) at which a
        kinematic ``model`` is linearised (default: zero, the prior centre); the ``linear`` model is linear
        already.  ``data``: what every campaign's likelihood uses (default: each campaign's every instrument, as
        ``sample``)."""
        posts = [LogPosterior(c, model, data=default_data(c) if data is None else data) for c in campaigns]
        first = posts[0]
        dev = [i for i, p in enumerate(first.space.parameters) if p.group == "deviation"]
        self.deviations = [first.space.parameters[i].name for i in dev]
        pri = first.priors.priors
        self.mu0 = np.array([pri[i].centre for i in dev])
        self.var0 = np.array([pri[i].sd for i in dev]) ** 2
        self.scales = tuple(dict.fromkeys(s for post in posts for s in post.scales))
        # each scale's prior: the first campaign's that has it (the scales follow the deviations in a posterior)
        self.sigma_priors = [next(post.priors.priors[post.p + post.scales.index(s)] for post in posts
                                  if s in post.scales) for s in self.scales]
        self.sigma_prior = self.sigma_priors[0]
        t0 = campaigns[0].date
        self.tau = np.array([(c.date - t0).total_seconds() / SECONDS_PER_YEAR for c in campaigns])
        d, T = len(dev), len(campaigns)
        blocks, ys, Rs = [], [], []
        self.model = model
        for t, post in enumerate(posts):
            names = [p.name for p in post.space.parameters]
            cols = [names.index(n) for n in self.deviations]
            nuis = [i for i, p in enumerate(post.space.parameters) if p.group != "deviation"]
            A, c = linearisation(post, None if points is None else points[t])
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
        self.scale_of_row = np.concatenate([np.array([self.scales.index(post.scales[i]) for i in post.scale_of],
                                                     dtype=int) for post in posts])
        tmin = np.minimum.outer(self.tau, self.tau)  # (T, T)
        # per deviation j: h_j (M,) its column in every block; prior part v0_j h hᵀ and walk part min(τ)·h hᵀ
        Hj = self.H.reshape(M, T, d).sum(axis=1)  # (M, d): block-diagonal, so the sum picks each row's block
        tm = tmin[self.campaign_of_row][:, self.campaign_of_row]  # (M, M)
        self.posts = posts
        self.d, self.T, self.M = d, T, M
        self.G = np.einsum("aj,bj,ab->jab", Hj, Hj, tm)
        self.G_trend = np.einsum("aj,bj,a,b->jab", Hj, Hj, self.tau[self.campaign_of_row], self.tau[self.campaign_of_row])
        temps = [c.temperature_C for c in campaigns]
        self.thermal = thermal and all(x is not None for x in temps)
        self.dT = np.array([x - REFERENCE_TEMPERATURE_C for x in temps]) if self.thermal else np.zeros(T)
        self.thermal_var = np.array([units.to_internal(THERMAL_SCALE[quantity_unit(n)], quantity_unit(n)) ** 2
                                     for n in self.deviations]) if self.thermal else np.zeros(d)
        dTrow = self.dT[self.campaign_of_row]
        self.H_thermal = Hj * dTrow[:, None]  # (M, d): campaign t's rows of A_t·ΔT_t
        self.C_base = self.R + (Hj * self.var0) @ Hj.T + (self.H_thermal * self.thermal_var) @ self.H_thermal.T
        self.noise_floor = float(min(np.min(post.likelihood.base_var) for post in posts))  # mm², the least noise
        self.set_trend(np.zeros(d))

    def set_trend(self, trend_var: np.ndarray) -> None:
        """The prior variance (d,) of each deviation's drift rate (internal units per year, squared; 0: no trend)."""
        self.trend_var = np.asarray(trend_var, float)
        self.C0 = self._static_cov(self.trend_var)

    def _static_cov(self, trend_var: np.ndarray) -> np.ndarray:
        """The covariance (M, M) of the observations without the random walks and σ, for rate variances (d,)."""
        return self.C_base + np.einsum("j,jab->ab", trend_var, self.G_trend)

    def log_marginal_with_trend(self, q2: np.ndarray, s2: np.ndarray, j: int, var: float) -> np.ndarray:
        """:meth:`log_marginal` (n,) with deviation ``j``'s rate variance set to ``var`` (the others as they are)."""
        tv = self.trend_var.copy()
        tv[j] = var
        return self.log_marginal(q2, s2, static=self._static_cov(tv))

    def covariance(self, q2: np.ndarray, s2: np.ndarray, static: np.ndarray | None = None) -> np.ndarray:
        """``C`` (n, M, M) of the observations for drift rates² ``q2`` (n, d) and σ² ``s2`` (n, S) (or (n,) with
        one scale); ``static``: the part without the random walks and σ (default that of the rate variances set)."""
        C = (self.C0 if static is None else static) + (q2 @ self.G.reshape(self.d, -1)).reshape(len(q2), self.M, self.M)
        C[:, np.arange(self.M), np.arange(self.M)] += _per_scale(s2)[:, self.scale_of_row]
        return C

    def log_marginal(self, q2: np.ndarray, s2: np.ndarray, static: np.ndarray | None = None) -> np.ndarray:
        """Log marginal likelihood (n,) of the scales: ``log N(resid; 0, C)``, one batched Cholesky.

        The Cholesky factor of C bordered by the residual r, ``[[C, r], [rᵀ, c]]``, holds both terms: its first M
        pivots give log det C, its last pivot² is ``c − rᵀC⁻¹r``, so no triangular solve is needed (numpy has no
        batched one; a general solve cost twice the factorisation).  c must exceed rᵀC⁻¹r: since every C holds the
        measurement noise and σ², ``λ_min(C) ≥ min(noise variance) + σ²`` and ``rᵀC⁻¹r ≤ |r|² / λ_min``."""
        n, M = len(q2), self.M
        A = np.empty((n, M + 1, M + 1))
        A[:, :M, :M] = self.covariance(q2, s2, static)
        A[:, :M, M] = self.resid
        A[:, M, :M] = self.resid
        c = 2.0 * float(self.resid @ self.resid) / (self.noise_floor + _per_scale(s2).min(axis=1)) + 1.0
        A[:, M, M] = c
        try:
            L = np.linalg.cholesky(A)
        except np.linalg.LinAlgError:  # some rows numerically singular (absurd scales): those get −inf
            return np.array([self.log_marginal(q2[i:i + 1], s2[i:i + 1], static)[0] if _is_pd(A[i]) else -np.inf
                             for i in range(n)])
        diag = np.diagonal(L, axis1=1, axis2=2)
        logdet = 2.0 * np.log(diag[:, :M]).sum(axis=1)
        quad = c - diag[:, M] ** 2
        return -0.5 * (quad + logdet + M * math.log(2 * math.pi))

    def log_marginal_grid(self, q2: np.ndarray, s2: np.ndarray) -> np.ndarray:
        """:meth:`log_marginal` ``(n, G)`` of every drift-rate vector of ``q2`` (n, d) with every σ² of ``s2`` (G,).

        One eigendecomposition per rate vector of the covariance without σ, ``C(q) = V diag(λ) Vᵀ``: adding σ²·I
        shifts every eigenvalue, so ``log N(r; 0, C(q) + σ² I) = −½ (Σ_k z_k² / (λ_k + σ²) + Σ_k log(λ_k + σ²)
        + M log 2π)`` with ``z = Vᵀ r``, for the whole σ grid at once (``λ_k ≥`` the least noise variance > 0).
        With more than one scale (several instruments) the grid is the first scale's and the others are integrated
        over their priors (:meth:`_log_marginal_grid_others`)."""
        if len(self.scales) > 1:
            return self._log_marginal_grid_others(np.atleast_2d(q2), np.asarray(s2, float))
        lam, V = np.linalg.eigh(self.covariance(np.atleast_2d(q2), np.zeros(len(np.atleast_2d(q2)))))
        z2 = np.einsum("nmk,m->nk", V, self.resid) ** 2  # (n, M)
        total = lam[:, :, None] + np.asarray(s2, float)[None, None, :]  # (n, M, G)
        return -0.5 * (np.sum(z2[:, :, None] / total, axis=1) + np.sum(np.log(total), axis=1)
                       + self.M * math.log(2 * math.pi))

    def _log_marginal_grid_others(self, q2: np.ndarray, s2: np.ndarray) -> np.ndarray:
        """:meth:`log_marginal_grid` with several scales: the first scale ``s2`` (G,) on the grid, the others
        integrated over their priors by :data:`OTHER_SCALE_NODES` equal-probability nodes each (their midpoints'
        quantiles).  Per rate vector and node, ``D`` the covariance without the first scale (Cholesky ``L``) and
        ``F = L⁻¹E`` (E the first scale's rows): ``C = L (I + σ² F Fᵀ) Lᵀ``, so with ``F = U diag(√μ) Wᵀ`` and
        ``w = L⁻¹ r``, ``log det C = log det D + Σ log(1 + σ²μ_k)``, ``rᵀC⁻¹r = |w|² − Σ (Uᵀw)_k² σ²μ_k/(1 + σ²μ_k)``."""
        others = [p.frozen().ppf((np.arange(OTHER_SCALE_NODES) + 0.5) / OTHER_SCALE_NODES) ** 2
                  for p in self.sigma_priors[1:]]
        nodes = np.stack(np.meshgrid(*others, indexing="ij"), axis=-1).reshape(-1, len(others))  # (J, S − 1)
        rows = np.flatnonzero(self.scale_of_row == 0)
        n, J = len(q2), len(nodes)
        s_all = np.concatenate([np.zeros((J, 1)), nodes], axis=1)  # (J, S): the first scale 0 in D
        D = self.covariance(np.repeat(q2, J, axis=0), np.tile(s_all, (n, 1)))  # (n·J, M, M)
        L = np.linalg.cholesky(D)
        rhs = np.concatenate([np.eye(self.M)[:, rows], self.resid[:, None]], axis=1)
        X = np.linalg.solve(L, np.broadcast_to(rhs, (len(D),) + rhs.shape))  # (n·J, M, m0 + 1): L⁻¹[E r]
        F, w = X[..., :-1], X[..., -1]
        U, sv, _ = np.linalg.svd(F, full_matrices=False)
        mu = sv**2  # (n·J, m0)
        z2 = np.einsum("nmk,nm->nk", U, w) ** 2
        sig = s2[None, None, :]
        shrink = sig * mu[:, :, None] / (1.0 + sig * mu[:, :, None])  # (n·J, m0, G)
        quad = np.sum(w**2, axis=1)[:, None] - np.sum(z2[:, :, None] * shrink, axis=1)
        logdet = 2.0 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)[:, None] + \
            np.sum(np.log1p(sig * mu[:, :, None]), axis=1)
        ll = (-0.5 * (quad + logdet + self.M * math.log(2 * math.pi))).reshape(n, J, len(s2))
        return np.logaddexp.reduce(ll, axis=1) - math.log(J)

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
        mean, cov = self.augmented_posterior(q2, s2)
        k = self.T * self.d
        return mean[:, :k].reshape(-1, self.T, self.d), cov[:, :k, :k]

    def augmented_prior_cov(self, q2: np.ndarray) -> np.ndarray:
        """Prior covariance (n, K, K) of ``Z = (x_1 … x_T, r, κ)``, K = T·d + 2d (module docstring)."""
        n, d, T = len(q2), self.d, self.T
        k = T * d
        S = np.zeros((n, k + 2 * d, k + 2 * d))
        Sx = self.prior_state_cov(q2).reshape(n, T, d, T, d)
        j = np.arange(d)
        Sx[:, :, j, :, j] += self.trend_var[:, None, None, None] * np.multiply.outer(self.tau, self.tau)
        S[:, :k, :k] = Sx.reshape(n, k, k)
        rows = (np.arange(T)[:, None] * d + j).ravel()  # x_{t,j}, t-major
        S[:, rows, k + np.tile(j, T)] = np.repeat(self.tau, d) * np.tile(self.trend_var, T)
        S[:, k + np.tile(j, T), rows] = S[:, rows, k + np.tile(j, T)]
        S[:, k + j, k + j] = self.trend_var
        S[:, k + d + j, k + d + j] = self.thermal_var
        return S

    def augmented_posterior(self, q2: np.ndarray, s2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean (n, K) and covariance (n, K, K) of ``Z = (x_1 … x_T, r, κ)`` given the scales: the states
        at 20 °C (t-major), the drift rates (per year), the thermal sensitivities (per °C); internal units."""
        S = self.augmented_prior_cov(q2)
        HZ = np.hstack([self.H, np.zeros((self.M, self.d)), self.H_thermal])
        C = self.covariance(q2, s2)
        SH = S @ HZ.T  # (n, K, M)
        K = np.linalg.solve(C, np.transpose(SH, (0, 2, 1)))  # C⁻¹ H S: (n, M, K)
        mu = np.concatenate([np.tile(self.mu0, self.T), np.zeros(2 * self.d)])
        mean = mu + np.einsum("nmk,m->nk", K, self.resid)
        cov = S - SH @ K
        cov = 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
        return mean, cov


def _per_scale(s2) -> np.ndarray:
    """σ² as ``(n, S)``: a ``(n,)`` vector is one scale's."""
    s2 = np.asarray(s2, float)
    return s2[:, None] if s2.ndim == 1 else s2


def _is_pd(C: np.ndarray) -> bool:
    try:
        np.linalg.cholesky(C)
        return True
    except np.linalg.LinAlgError:
        return False
