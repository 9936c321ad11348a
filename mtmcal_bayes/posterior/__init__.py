"""The posterior of a campaign: sampled, summarised, and set beside the machine's deterministic values.

* :func:`sample_posterior` — emcee ensembles (:mod:`mtmcal_bayes.inference`) to a
  :class:`PosteriorResult`: InferenceData, summary, diagnostics, the comparison
  with the published deterministic values of its machine's plug-in (the thesis' ball bar and touch probe), warnings.
* :func:`comparison` — a posterior beside every deterministic value the machine has (:func:`references`: the least
  squares on every machine, the plug-in's own method's values where it has one).
* :func:`closed_form` — the instant Gaussian answer of the linear model at a fixed sigma_model.
* :func:`loo_check` — PSIS leave-one-out consistency of each observation (ArviZ LOO, Pareto k).
"""

from .closed_form import ClosedFormResult, closed_form
from .comparison import REFERENCES, comparison, references
from .loo import LooResult, loo_check
from .sample import PosteriorResult, SamplerDiagnostics, sample_posterior

__all__ = ["ClosedFormResult", "closed_form", "REFERENCES", "comparison", "references", "LooResult", "loo_check",
           "PosteriorResult", "SamplerDiagnostics", "sample_posterior"]
