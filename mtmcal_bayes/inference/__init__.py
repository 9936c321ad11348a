"""Bayesian inference: priors, likelihood, log posterior, emcee ensembles, closed form, results."""

from .analytic import GaussianPosterior, gaussian_posterior
from .posterior import SAMPLED_DEVIATIONS, Posterior
from .priors import Prior, PriorSet
from .results import comparison, diagnostics_warnings, not_identified, summarize, to_inference_data
from .sampling import SamplerSettings, SamplingResult, run_ensembles

__all__ = ["GaussianPosterior", "gaussian_posterior", "SAMPLED_DEVIATIONS", "Posterior", "Prior", "PriorSet",
           "comparison", "diagnostics_warnings", "not_identified", "summarize", "to_inference_data",
           "SamplerSettings", "SamplingResult", "run_ensembles"]
