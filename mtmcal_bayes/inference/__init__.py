"""Bayesian inference: priors, likelihood, log posterior, emcee ensembles, closed forms, results.

The engine only: it knows the campaign's data, the forward model and the
priors, nothing of the thesis' deterministic method (the posterior feature,
:mod:`mtmcal_bayes.posterior`, sets the two side by side).
"""

from .analytic import GaussianPosterior, gaussian_posterior, prior_sensitivity
from .approximation import IndependenceMove, PosteriorApproximation
from .identifiability import Combination, Identifiability, identifiability
from .log_posterior import SAMPLED_DEVIATIONS, LogPosterior
from .marginal import MarginalPosterior
from .priors import Prior, PriorSet, make_prior
from .results import (
           diagnostics_warnings,
           display_draws,
           not_identified,
           summarize,
           to_inference_data,
)
from .sampling import (
           SAMPLERS,
           SamplerSettings,
           SamplingResult,
           check_step_budget,
           run_ensembles,
           run_exact,
)

__all__ = ["GaussianPosterior", "gaussian_posterior", "prior_sensitivity", "IndependenceMove",
           "PosteriorApproximation", "Combination", "Identifiability", "identifiability",
           "SAMPLED_DEVIATIONS", "LogPosterior", "MarginalPosterior", "Prior", "PriorSet",
           "make_prior", "diagnostics_warnings", "display_draws", "not_identified", "summarize", "to_inference_data",
           "SAMPLERS", "SamplerSettings", "SamplingResult", "check_step_budget", "run_ensembles", "run_exact"]
