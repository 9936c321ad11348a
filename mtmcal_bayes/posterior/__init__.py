"""The posterior of a campaign: sampled, summarised, and set beside the thesis' deterministic values.

* :func:`sample_posterior` — emcee ensembles (:mod:`mtmcal_bayes.inference`) to a
  :class:`PosteriorResult`: InferenceData, summary, diagnostics, the comparison
  with the ball-bar and touch-probe values, warnings.
* :func:`closed_form` — the instant Gaussian answer of the linear model at a fixed sigma_model.
* :func:`loo_check` — PSIS leave-one-out consistency of each observation (ArviZ LOO, Pareto k).
"""

from .closed_form import ClosedFormResult, closed_form
from .comparison import REFERENCES, comparison
from .loo import LooResult, loo_check
from .sample import PosteriorResult, SamplerDiagnostics, sample_posterior

__all__ = ["ClosedFormResult", "closed_form", "REFERENCES", "comparison", "LooResult", "loo_check", "PosteriorResult",
           "SamplerDiagnostics", "sample_posterior"]
