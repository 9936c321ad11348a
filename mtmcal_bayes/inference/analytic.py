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
from ..machines.plugins import provided
from ..models import jacobian
from ..parameters import weights
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


def linearisation(post: LogPosterior, theta0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (m, p) and ``c`` (m,) with ``f(θ) ≈ c + A θ``: the design of the ``linear`` model (exact), else the
    Jacobian of the forward model at ``theta0`` (default zero), internal units."""
    model = post.forward
    if hasattr(model, "design"):
        return model.design, np.zeros(model.design.shape[0])
    theta0 = np.zeros(post.p) if theta0 is None else np.asarray(theta0, float)
    A = jacobian(model, theta0)
    return A, model.predict(theta0) - A @ theta0


def gaussian_posterior(post: LogPosterior, sigma_model=0.0, *, theta0: np.ndarray | None = None,
                       allow_non_normal: bool = False, prior_scale: np.ndarray | None = None) -> GaussianPosterior:
    """Gaussian posterior of ``post``'s forward parameters at fixed discrepancy scales ``sigma_model`` (mm; one
    value for every scale, or one per scale of ``post.scales``).

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
    A, c = linearisation(post, theta0)
    V = post.likelihood.variance_at(sigma_model)
    # solved in prior-sd units: in mm and rad the precision's condition number is ~1e11 (lever arms of 400 mm
    # against 1), in prior-sd units it is that of the data's information against the prior (~1e5), and the
    # posterior of a weakly determined direction keeps eight more digits.  The same posterior: with S = diag(s),
    # Σ0⁻¹ + AᵀV⁻¹A = S⁻¹(I + (AS)ᵀV⁻¹(AS))S⁻¹, so Σ = S (I + …)⁻¹ S; and Σ(Σ0⁻¹μ0 + AᵀV⁻¹(y − c)) =
    # μ0 + ΣAᵀV⁻¹(y − c − Aμ0), since Σ(Σ0⁻¹ + AᵀV⁻¹A)μ0 = μ0
    s = np.sqrt(var0)
    Aw = A * s
    cov_w = np.linalg.inv(np.eye(len(s)) + Aw.T @ (Aw / V[:, None]))
    cov_w = 0.5 * (cov_w + cov_w.T)
    mean = mu0 + s * (cov_w @ (Aw.T @ ((post.likelihood.y - c - A @ mu0) / V)))
    return GaussianPosterior(list(post.space.names), mean, s[:, None] * cov_w * s[None, :])


#: widening factor of the priors in :func:`prior_sensitivity`
WIDEN = 10.0
#: a quantity whose posterior sd grows more than this when its priors widen ``WIDEN``-fold has a width that follows
#: them (a diagnostic: what the data determine is the Jacobian's statement, :mod:`.identifiability`)
NOT_IDENTIFIED_GROWTH = 2.0
#: "removing" a prior in :func:`prior_sensitivity` widens it this much
REMOVED = 1e4
#: a nuisance prior whose ``WIDEN``-fold widening alone widens a quantity this much is named among those the
#: quantity rests on, where no single prior's removal leaves it unidentified
NAMED_GROWTH = 1.1
def reported(post) -> tuple[str, ...]:
    """The quantities a posterior reports: its machine's plug-in's (the thesis' eight of Table 4.5 and dx_CZ, dx_BT, dz_BT), else the
    machine's deviations."""
    own = provided(post.campaign.machine, "summary_quantities")
    return own if own is not None else tuple(p.name for p in post.space.parameters if p.group == "deviation")


@dataclass(frozen=True)
class PriorSensitivity:
    """How each reported quantity's posterior sd depends on the priors (closed form, linearised at zero).

    A diagnostic, never the verdict on what the data determine (that is the campaign's Jacobian's,
    :func:`~.identifiability.campaign_identifiability`; SPEC §20).  ``deviation_growth[name]``: sd growth when
    every deviation prior widens ``WIDEN``-fold; above ``NOT_IDENTIFIED_GROWTH`` its width follows those priors.
    ``nuisance_growth[name]``: the same for the nuisance priors (T-ball centring, tool length, W-ball clamping,
    probe terms); above the threshold the quantity's interval rests on them, and ``through[name]`` names them (base names,
    e.g. ``("dRB", "zT")``): each prior whose removal alone leaves the quantity unidentified, or, where no
    single one does, each whose ``WIDEN``-fold widening alone widens it by ``NAMED_GROWTH`` or more.
    """

    deviation_growth: dict[str, float]
    nuisance_growth: dict[str, float]
    through: dict[str, tuple[str, ...]]


def prior_sensitivity(post: LogPosterior, sigma_model=0.0) -> PriorSensitivity:
    """Widen the deviation priors, then separately the nuisance priors, and see whose sd follows.

    A quantity the data determine keeps its width (growth ≈ 1); one whose width is set by the priors grows
    with them (≈ 10).  Nuisance priors carry real physical knowledge (the centring check, the dial gauge),
    so resting on them is not an error, but the reader must be told: the interval is then a statement about
    that set-up knowledge as much as about the machine.
    """
    params = post.space.parameters
    base = gaussian_posterior(post, sigma_model, allow_non_normal=True)
    names = [n for n in reported(post) if weights(n, base.names)]
    sd0 = {n: base.linear_combination(weights(n, base.names))[1] for n in names}

    def growth(widen) -> dict[str, float]:
        scale = np.array([widen(p) for p in params], dtype=float)
        wide = gaussian_posterior(post, sigma_model, allow_non_normal=True, prior_scale=scale)
        return {n: wide.linear_combination(weights(n, base.names))[1] / sd0[n] for n in names}

    deviation = growth(lambda p: WIDEN if p.group == "deviation" else 1.0)
    nuisance = growth(lambda p: 1.0 if p.group == "deviation" else WIDEN)
    resting = [n for n in names if nuisance[n] > NOT_IDENTIFIED_GROWTH]
    through: dict[str, tuple[str, ...]] = {n: () for n in names}
    if resting:
        bases = list(dict.fromkeys(p.base for p in params if p.group != "deviation"))
        removed = {b: growth(lambda p, b=b: REMOVED if p.base == b else 1.0) for b in bases}
        widened = {b: growth(lambda p, b=b: WIDEN if p.base == b else 1.0) for b in bases}
        for n in resting:
            needed = [b for b in bases if removed[b][n] > NOT_IDENTIFIED_GROWTH]
            named = needed or [b for b in bases if widened[b][n] >= NAMED_GROWTH]
            through[n] = tuple(sorted(named, key=lambda b: -widened[b][n]))  # the most telling first
    return PriorSensitivity(deviation, nuisance, through)
