"""The log posterior of a campaign under a forward model, vectorised over batches.

Sampled parameters (SPEC §5): the deviations alpha_CZ, beta_CZ, alpha_XB,
beta_XB, gamma_XB, alpha_BT, dy_CZ, dx_CZ and dx_BT (separately; their
difference is reported), dz_BT; per tool setup xT, yT, zT, dRB; per W-ball
mount xW, yW, zW; and sigma_model.  The linear-axis squareness deviations are
held at zero (the thesis relations leave them out).  Sampling happens in
coordinates scaled by the prior widths: ``z = (θ − centre) / width``, except
sigma_model, sampled as ``log(sigma_model / prior scale)``: the other
parameters' spread shrinks as sigma_model → 0 (a funnel), and the log
coordinate lets the sampler reach that end (τ of sigma_model ≈ 3× shorter).
"""

from __future__ import annotations

import copy

import numpy as np

from ..models import check_data, make_model
from ..parameters import ParameterSpace
from .likelihood import GaussianMeanLikelihood
from .priors import PriorSet, make_prior

#: deviations sampled by default (Table 2.1 minus the linear-axis squareness)
SAMPLED_DEVIATIONS = ("dx_BT", "dz_BT", "alpha_BT", "alpha_XB", "beta_XB", "gamma_XB",
                      "dx_CZ", "dy_CZ", "alpha_CZ", "beta_CZ")


class LogPosterior:
    """Log posterior of ``campaign`` under forward model ``model``.

    Parameters
    ----------
    campaign : Campaign
    model : ``"linear"``, ``"htm-literal"`` or ``"htm-thesis"``
    fix_dx_BT : impose the thesis assumption dx_BT = 0 (Eq 4.2)
    sigma_model : fix the model-discrepancy scale (mm) instead of sampling it
    data : ``"ballbar"`` (eccentricities), ``"probe"`` (touch-probe readings) or ``"both"``; one
        sigma_model for all (SPEC §12)

    Attributes
    ----------
    names : sampled parameter names, length q (forward-model parameters, then ``sigma_model`` if sampled)
    priors : PriorSet over ``names``
    forward : the forward model, over the first ``p`` names
    """

    def __init__(self, campaign, model: str = "linear", fix_dx_BT: bool = False, sigma_model: float | None = None, *,
                 data: str = "ballbar"):
        self.campaign = campaign
        self.model_name = model
        self.fix_dx_BT = fix_dx_BT
        self.data = check_data(data, campaign)
        devs = [d for d in SAMPLED_DEVIATIONS if not (fix_dx_BT and d == "dx_BT")]
        self.space = ParameterSpace.for_campaign(campaign, devs, data=data)
        self.forward = make_model(model, campaign, self.space, data)
        self.likelihood = GaussianMeanLikelihood(self.forward.observations, campaign.ballbar.accuracy)
        priors = [make_prior(p.name, p.base, p.kind, campaign.priors) for p in self.space.parameters]
        self.fixed_sigma = sigma_model
        if sigma_model is None:
            priors.append(make_prior("sigma_model", "sigma_model", "length", campaign.priors))
        self.priors = PriorSet(priors)
        self._sigma_scale = priors[-1].scale if sigma_model is None else None
        self.names = self.priors.names
        self.p = len(self.space)

    def with_means(self, y: np.ndarray) -> LogPosterior:
        """The posterior of the same campaign structure given other repeat means ``y`` (m,), mm.

        Only the likelihood's data change (repeat sds, counts, priors and model
        stay): what simulation-based calibration needs.  ``campaign`` and
        ``forward.observations`` still describe the original measurement.
        """
        out = copy.copy(self)
        out.likelihood = self.likelihood.with_means(y)
        return out

    def __len__(self) -> int:
        return len(self.names)

    # ------------------------------------------------------------ coordinates
    def to_theta(self, z: np.ndarray) -> np.ndarray:
        """Sampling coordinates ``(n, q)`` to parameters (internal units)."""
        theta = self.priors.centre + self.priors.width * np.asarray(z, dtype=float)
        if self.fixed_sigma is None:
            theta[..., self.p] = self._sigma_scale * np.exp(np.asarray(z)[..., self.p])
        return theta

    def to_z(self, theta: np.ndarray) -> np.ndarray:
        z = (np.asarray(theta, dtype=float) - self.priors.centre) / self.priors.width
        if self.fixed_sigma is None:
            with np.errstate(divide="ignore"):
                z[..., self.p] = np.log(np.asarray(theta)[..., self.p] / self._sigma_scale)
        return z

    def sigma(self, theta: np.ndarray) -> np.ndarray:
        """sigma_model of each row ``(n,)``, mm."""
        theta = np.atleast_2d(theta)
        if self.fixed_sigma is not None:
            return np.full(theta.shape[0], self.fixed_sigma)
        return theta[:, self.p]

    # ------------------------------------------------------------ densities
    def log_prob_theta(self, theta: np.ndarray) -> np.ndarray:
        """Log posterior (unnormalised) ``(n,)`` of parameters ``(n, q)`` in internal units."""
        theta = np.atleast_2d(theta)
        lp = self.priors.logpdf(theta)
        ok = np.isfinite(lp)
        out = np.full(theta.shape[0], -np.inf)
        if ok.any():
            pred = self.forward.predict(theta[ok, : self.p])
            out[ok] = lp[ok] + self.likelihood.loglike(pred, self.sigma(theta[ok]))
        return out

    def __call__(self, z: np.ndarray) -> np.ndarray:
        """Log posterior density of sampling coordinates ``(n, q)`` -> ``(n,)``: what emcee calls (vectorize=True).

        Includes the Jacobian of the log coordinate of sigma_model; that of the
        affine scaling is constant and omitted.
        """
        z = np.atleast_2d(z)
        lp = self.log_prob_theta(self.to_theta(z))
        if self.fixed_sigma is None:
            lp = lp + z[:, self.p]
        return lp
