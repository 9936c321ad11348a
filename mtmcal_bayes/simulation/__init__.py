"""Forward-model features: what a known truth would measure, and how every pattern responds to every deviation.

* :func:`simulate_truth` — predicted eccentricities of a truth, and synthetic
  campaigns with realistic scatter (:class:`Simulation`).
* :func:`sensitivity` — the Jacobian of a model at zero for every pattern of any machine
  (thesis Tables 2.4–2.6 as numbers, generalised).
"""

from .result import Simulation, simulate_truth
from .sensitivity import SensitivityTable, sensitivity, sensitivity_table
from .simulate import predict_truth, synthetic_campaign, truth_from_vector, truth_vector

__all__ = ["Simulation", "simulate_truth", "SensitivityTable", "sensitivity", "sensitivity_table", "predict_truth",
           "synthetic_campaign", "truth_from_vector", "truth_vector"]
