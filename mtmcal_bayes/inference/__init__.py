"""Bayesian inference: priors, likelihood, log posterior, emcee ensembles, closed forms, results.

The engine only: it knows the campaign's data, the forward model and the
priors, nothing of the thesis' deterministic method (the posterior feature,
:mod:`mtmcal_bayes.posterior`, sets the two side by side).
"""

from ..lazy_names import lazy_names

#: each public name and the module it comes from, imported on first use (PEP 562): a command that needs the exact
#: posterior or the closed form (``design``, ``plan``) does not load ArviZ, pandas and matplotlib with the sampler's
#: results
_HOME = {
    **dict.fromkeys(("GaussianPosterior", "gaussian_posterior", "prior_sensitivity"), "analytic"),
    **dict.fromkeys(("IndependenceMove", "PosteriorApproximation"), "approximation"),
    **dict.fromkeys(("Combination", "Identifiability", "identifiability"), "identifiability"),
    **dict.fromkeys(("SAMPLED_DEVIATIONS", "LogPosterior"), "log_posterior"),
    "MarginalPosterior": "marginal",
    **dict.fromkeys(("Prior", "PriorSet", "make_prior"), "priors"),
    **dict.fromkeys(("diagnostics_warnings", "display_draws", "not_identified", "summarize", "to_inference_data"),
                    "results"),
    **dict.fromkeys(("SAMPLERS", "SamplerSettings", "SamplingResult", "check_step_budget", "run_ensembles",
                     "run_exact"), "sampling"),
}


__getattr__, __dir__ = lazy_names(__name__, _HOME, globals())


__all__ = list(_HOME)
