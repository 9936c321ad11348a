"""Likelihood of the observed eccentricities (SPEC §5).

For each eccentricity component the mean of its n repeats is Normal around the
prediction with variance ``s²/n + u_inst² + sigma_model²``: ``s`` the sample
standard deviation of the repeats (their scatter), ``u_inst`` the instrument
accuracy (an error shared by the repeats of a run, so it does not average
out), ``sigma_model`` what the model leaves out (dynamics, thermal drift, pitch
error).  A component measured once has no ``s`` of its own; it takes the pooled
repeat sd of the campaign's other components, or 0.25 µm (thesis Table 4.4)
when no component was repeated.  Touch-probe readings carry their own noise and their own
discrepancy scale ``sigma_model_probe`` (SPEC §17): each observation belongs to one scale (``groups``),
so a conflict between the instruments widens the one whose data the model cannot fit.

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
    groups : (m,) the discrepancy scale of each observation, an index into the columns of ``sigma``
        (default: one scale for all)
    """

    def __init__(self, observations, accuracy: float, groups: np.ndarray | None = None):
        self.observations = observations
        self.y = observations.mean  # (m,) mm
        self.base_var = observations.noise_variance(accuracy)  # (m,) mm²
        self.noise = observations.noise_components(accuracy)  # {source: (m,) mm²}, summing to base_var
        self.groups = np.zeros(len(self.y), dtype=int) if groups is None else np.asarray(groups, dtype=int)

    def with_means(self, y: np.ndarray) -> GaussianMeanLikelihood:
        """The same likelihood (same repeat sds, counts and accuracy) for other means ``y`` (m,), mm."""
        out = copy.copy(self)
        out.y = np.asarray(y, dtype=float)
        return out

    def variance(self, sigma_model: np.ndarray | float) -> np.ndarray:
        """Variance of each mean, ``(n, m)``, for scales ``sigma_model`` of shape ``(n, s)`` (``(n,)``: one scale)."""
        sig = np.atleast_1d(np.asarray(sigma_model, dtype=float))
        if sig.ndim == 1:
            sig = sig[:, None]
        return self.base_var + np.square(sig[:, self.groups] if sig.shape[1] > 1 else sig)

    def variance_at(self, sigma_model) -> np.ndarray:
        """Variance of each mean ``(m,)`` at one point: ``sigma_model`` one value for every scale or one per
        scale ``(s,)``, mm."""
        sig = np.atleast_1d(np.asarray(sigma_model, dtype=float))
        return self.base_var + (sig[self.groups] if sig.size > 1 else sig) ** 2

    def loglike(self, pred: np.ndarray, sigma_model: np.ndarray | float) -> np.ndarray:
        """Log-likelihood ``(n,)`` of predictions ``(n, m)`` (mm): ``Σ −½((y − f)²/v + log 2πv)``, plain numpy."""
        var = self.variance(sigma_model)
        r = self.y - pred
        return -0.5 * (np.sum(r * r / var, axis=1) + np.sum(np.log(var), axis=1) + r.shape[1] * math.log(2 * math.pi))

    def replicate(self, pred: np.ndarray, sigma_model: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Posterior-predictive replicate of the means, ``(n, m)`` mm."""
        return pred + rng.normal(size=pred.shape) * np.sqrt(self.variance(sigma_model))
