"""The posterior of a campaign: sampled, summarised, and set beside the thesis' deterministic values.

* :func:`sample_posterior` — emcee ensembles (:mod:`mtmcal_bayes.inference`) to a
  :class:`PosteriorResult`: InferenceData, summary, diagnostics, the comparison
  with the ball-bar and touch-probe values, warnings.
* :func:`closed_form` — the instant Gaussian answer of the linear model at a fixed sigma_model.
"""

from .closed_form import ClosedFormResult, closed_form
from .comparison import REFERENCES, comparison
from .sample import PosteriorResult, SamplerDiagnostics, sample_posterior

__all__ = ["ClosedFormResult", "closed_form", "REFERENCES", "comparison", "PosteriorResult", "SamplerDiagnostics",
           "sample_posterior"]
