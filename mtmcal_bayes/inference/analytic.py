"""Closed-form Gaussian posterior for a linear(ised) forward model at fixed sigma_model.

With normal priors N(μ0, Σ0), a linear model ``f(θ) = c + A θ`` and the Gaussian
likelihood of :mod:`.likelihood` at fixed noise variances V, the posterior is
Normal with precision ``Σ0⁻¹ + Aᵀ V⁻¹ A`` and mean
``Σ⁻¹ (Σ0⁻¹ μ0 + Aᵀ V⁻¹ (y − c))``.  For the ``linear`` model this is exact:
the instant answer, and the oracle the sampler is tested against.  For the
kinematic models, linearised at a point, it is the Laplace-like approximation
used to start the sampler.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import MtmcalError
from ..models import jacobian
from ..parameters import IDENTIFIABLE, weights
from .log_posterior import LogPosterior


@dataclass
class GaussianPosterior:
    """Normal distribution over the forward-model parameters ``names`` (internal units)."""

    names: list[str]
    mean: np.ndarray  # (p,)
    cov: np.ndarray  # (p, p)

    @property
    def sd(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))

    def linear_combination(self, weights: dict[str, float]) -> tuple[float, float]:
        """Mean and sd of ``Σ w_i θ_i``."""
        a = np.zeros(len(self.names))
        for n, w in weights.items():
            a[self.names.index(n)] = w
        return float(a @ self.mean), float(np.sqrt(a @ self.cov @ a))

    def draws(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return rng.multivariate_normal(self.mean, self.cov, size=n, method="cholesky")


def gaussian_posterior(post: LogPosterior, sigma_model: float = 0.0, *, theta0: np.ndarray | None = None,
                       allow_non_normal: bool = False, prior_scale: np.ndarray | None = None) -> GaussianPosterior:
    """Gaussian posterior of ``post``'s forward parameters at fixed ``sigma_model`` (mm).

    Exact for the ``linear`` model; other models are linearised at ``theta0``
    (default zero).  Non-normal priors (half-normal, uniform overrides) are an
    error unless ``allow_non_normal``, which replaces them by normals of the
    same mean and sd (used only to start the sampler).  ``prior_scale`` (p,)
    multiplies the prior sds (for prior-sensitivity checks).
    """
    p = post.p
    priors = post.priors.priors[:p]
    if not allow_non_normal:
        bad = [q.name for q in priors if q.dist != "normal"]
        if bad:
            raise MtmcalError(f"the closed-form posterior needs normal priors; {', '.join(bad)} "
                              "has another prior in [priors]")
    mu0 = np.array([q.centre for q in priors])
    var0 = (np.array([q.sd for q in priors]) * (1.0 if prior_scale is None else prior_scale)) ** 2
    model = post.forward
    if hasattr(model, "design"):
        A, c = model.design, np.zeros(model.design.shape[0])
    else:
        theta0 = np.zeros(p) if theta0 is None else np.asarray(theta0, float)
        A = jacobian(model, theta0)
        c = model.predict(theta0) - A @ theta0
    V = post.likelihood.base_var + sigma_model**2
    prec = np.diag(1.0 / var0) + A.T @ (A / V[:, None])
    cov = np.linalg.inv(prec)
    cov = 0.5 * (cov + cov.T)
    mean = cov @ (mu0 / var0 + A.T @ ((post.likelihood.y - c) / V))
    return GaussianPosterior(list(post.space.names), mean, cov)


#: widening factor of the deviation priors in :func:`prior_sensitivity`
WIDEN = 10.0
#: a quantity whose posterior sd grows more than this when its priors widen ``WIDEN``-fold is not identified
NOT_IDENTIFIED_GROWTH = 2.0


def prior_sensitivity(post: LogPosterior, sigma_model: float = 0.0) -> dict[str, float]:
    """How much each identifiable quantity's posterior sd grows when the deviation priors widen 10×.

    Closed form (linearised at zero), nuisance priors unchanged (they carry real
    physical knowledge: the centring check, the dial gauge).  A quantity the
    data determine keeps its width (growth ≈ 1); one whose width is set by the
    priors grows with them (≈ 10).  Returns ``{name: growth}``.
    """
    scale = np.array([WIDEN if p.group == "deviation" else 1.0 for p in post.space.parameters])
    base = gaussian_posterior(post, sigma_model, allow_non_normal=True)
    wide = gaussian_posterior(post, sigma_model, allow_non_normal=True, prior_scale=scale)
    out = {}
    for name in IDENTIFIABLE:
        w = weights(name, base.names)
        out[name] = wide.linear_combination(w)[1] / base.linear_combination(w)[1]
    return out
