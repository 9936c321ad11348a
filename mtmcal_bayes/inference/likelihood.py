"""Likelihood of the observed eccentricities (SPEC §5).

For each eccentricity component the mean of its n repeats is Normal around the
prediction with variance ``s²/n + u_inst² + sigma_model²``: ``s`` the sample
standard deviation of the repeats (their scatter), ``u_inst`` the instrument
accuracy (an error shared by the repeats of a run, so it does not average
out), ``sigma_model`` what the model leaves out (dynamics, thermal drift, pitch
error).  A component measured once has no ``s`` of its own; it takes the pooled
repeat sd of the campaign's other components, or 0.25 µm (thesis Table 4.4)
when no component was repeated.

The class is small on purpose: a different likelihood (Student-t, correlated
components) only has to provide ``loglike(pred, sigma_model)``.
"""

from __future__ import annotations

import copy
import math

import numpy as np


class GaussianMeanLikelihood:
    """Normal likelihood of the repeat means.

    Parameters
    ----------
    observations : Observations, ProbeObservations or JointObservations (m entries): anything with
        ``mean`` (m,) and ``noise_variance(accuracy)`` (m,)
    accuracy : ball-bar instrument accuracy u_inst, mm (the probe's readings carry their own noise)
    """

    def __init__(self, observations, accuracy: float):
        self.observations = observations
        self.y = observations.mean  # (m,) mm
        self.base_var = observations.noise_variance(accuracy)  # (m,) mm²
        self.noise = observations.noise_components(accuracy)  # {source: (m,) mm²}, summing to base_var

    def with_means(self, y: np.ndarray) -> GaussianMeanLikelihood:
        """The same likelihood (same repeat sds, counts and accuracy) for other means ``y`` (m,), mm."""
        out = copy.copy(self)
        out.y = np.asarray(y, dtype=float)
        return out

    def variance(self, sigma_model: np.ndarray | float) -> np.ndarray:
        """Variance of each mean, ``(n, m)`` for ``sigma_model`` of shape ``(n,)``."""
        return self.base_var + np.square(np.atleast_1d(sigma_model))[:, None]

    def loglike(self, pred: np.ndarray, sigma_model: np.ndarray | float) -> np.ndarray:
        """Log-likelihood ``(n,)`` of predictions ``(n, m)`` (mm): ``Σ −½((y − f)²/v + log 2πv)``, plain numpy."""
        var = self.variance(sigma_model)
        r = self.y - pred
        return -0.5 * (np.sum(r * r / var, axis=1) + np.sum(np.log(var), axis=1) + r.shape[1] * math.log(2 * math.pi))

    def replicate(self, pred: np.ndarray, sigma_model: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Posterior-predictive replicate of the means, ``(n, m)`` mm."""
        return pred + rng.normal(size=pred.shape) * np.sqrt(self.variance(sigma_model))
