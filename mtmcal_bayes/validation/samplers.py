"""Posterior draws for one simulated data set: what simulation-based calibration checks.

Two ways to draw from the posterior of a :class:`~mtmcal_bayes.inference.log_posterior.LogPosterior`:

* :class:`EmceeDraws` — the package's sampler exactly as ``sample`` runs it
  (:func:`~mtmcal_bayes.inference.sampling.run_ensembles` with the default
  :class:`~mtmcal_bayes.inference.sampling.SamplerSettings`: started from the
  linearised posterior, stopped at the ESS and R-hat targets).  The kept chain
  is thinned by the largest integrated autocorrelation time τ of the ranked
  quantities, so the draws ranked by SBC are close to independent
  (autocorrelated draws distort the rank histogram even when the sampler is right).
* :class:`ExactDraws` — the exact posterior of the ``linear`` model with
  sigma_model marginalised on a grid (:class:`MarginalPosterior`): independent
  draws, no sampler.  It checks the simulation/ranking machinery itself and is
  the reference the emcee results are compared with.

Both return draws ``(n, q)`` in internal units over ``post.names``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ..inference.log_posterior import LogPosterior
from ..inference.marginal import MarginalPosterior
from ..inference.sampling import SamplerSettings, check_step_budget, run_ensembles


@dataclass
class Draws:
    """Posterior draws of one data set.

    ``ranked``: (L, q) near-independent draws, ranked against the truth;
    ``all``: (n, q) every kept draw, for the intervals;
    ``converged``/``n_steps``/``tau_max`` describe the sampler run (exact: True, 0, 1).
    """

    ranked: np.ndarray
    all: np.ndarray
    converged: bool = True
    n_steps: int = 0
    tau_max: float = 1.0


@dataclass
class EmceeDraws:
    """The package's emcee sampler with the production settings (see module docstring)."""

    max_steps: int = SamplerSettings.max_steps
    name: str = "emcee"

    def check(self, post: LogPosterior) -> None:
        check_step_budget(self.max_steps, SamplerSettings.min_steps)

    def __call__(self, post: LogPosterior, n_ranked: int, rng: np.random.Generator) -> Draws:
        r = run_ensembles(post, SamplerSettings(max_steps=self.max_steps, seed=int(rng.integers(2**63 - 1))))
        K, S, W, q = r.chains.shape
        tau = float(np.nanmax(r.tau))
        thinned = r.chains[:, :: max(1, int(np.ceil(tau)))].reshape(-1, q)
        if len(thinned) < n_ranked:
            raise ParameterError("max_steps", f"only {len(thinned)} posterior draws for {n_ranked} ranks: "
                                 "raise the step budget")
        pick = rng.choice(len(thinned), size=n_ranked, replace=False)
        return Draws(thinned[pick], r.chains.reshape(-1, q), r.converged, r.n_steps, tau)


@dataclass
class ExactDraws:
    """Independent draws of the exact linear-model posterior (sigma_model on a grid)."""

    n_all: int = 4000
    name: str = "exact"
    _cache: dict = field(default_factory=dict, repr=False)

    def check(self, post: LogPosterior) -> None:
        if post.model_name != "linear":
            raise ParameterError("sampler", f"exact: the exact posterior exists for the linear model only, "
                                 f"not {post.model_name} (use the emcee sampler)")
        bad = [p.name for p in post.priors.priors[: post.p] if p.dist != "normal"]
        if bad:
            raise ParameterError("sampler", f"exact needs normal priors; {bad[0]} has another prior in "
                                 "[priors] (use the emcee sampler)")
        if post.fixed_sigma is not None:
            raise ParameterError("sampler", "exact marginalises sigma_model; it cannot be fixed")

    def _marginal(self, post: LogPosterior):
        key = id(post.forward)  # the data sets of one SBC run share the model, priors and noise
        if key not in self._cache:
            priors = post.priors.priors[: post.p]
            self._cache[key] = MarginalPosterior(post.forward.design, post.likelihood.base_var,
                                                 np.array([p.sd for p in priors]) ** 2,
                                                 [p.frozen() for p in post.priors.priors[post.p:]],
                                                 prior_mean=np.array([p.loc for p in priors]), groups=post.scale_of)
        return self._cache[key]

    def __call__(self, post: LogPosterior, n_ranked: int, rng: np.random.Generator) -> Draws:
        theta, sigma = self._marginal(post).draw(post.likelihood.y, n_ranked + self.n_all, rng)
        draws = np.column_stack([theta, sigma])
        return Draws(draws[:n_ranked], draws[n_ranked:])


def make_sampler(name: str, max_steps: int = SamplerSettings.max_steps):
    """The draw strategy called ``name`` (``"emcee"`` or ``"exact"``)."""
    if name == "emcee":
        return EmceeDraws(max_steps=max_steps)
    if name == "exact":
        return ExactDraws()
    raise ParameterError("sampler", f"unknown sampler {name!r} (emcee or exact)")
