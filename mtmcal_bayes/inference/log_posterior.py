"""The log posterior of a campaign under a forward model, vectorised over batches.

Sampled parameters (SPEC §5): the deviations alpha_CZ, beta_CZ, alpha_XB,
beta_XB, gamma_XB, alpha_BT, dy_CZ, dx_CZ and dx_BT (separately; their
difference is reported), dz_BT; per tool setup xT, yT, zT, dRB; per W-ball
mount xW, yW, zW; the touch probe's terms with probe data; and one
model-discrepancy scale per instrument whose data the likelihood uses:
``sigma_model`` for the ball bar, ``sigma_model_probe`` for the touch probe
(SPEC §17: a conflict between the instruments widens the one whose data the
model cannot fit, not everything).  The linear-axis squareness deviations are
held at zero (the thesis relations leave them out).  Sampling happens in
coordinates scaled by the prior widths: ``z = (θ − centre) / width``, except
the scales, sampled as ``log(σ / prior scale)``: the other parameters' spread
shrinks as σ → 0 (a funnel), and the log coordinate lets the sampler reach
that end (τ of sigma_model ≈ 3× shorter).
"""

from __future__ import annotations

import copy

import numpy as np

from .. import units
from ..errors import ParameterError
from ..machines.plugins import provided
from ..machines.space import described_space
from ..models import JointModel, check_data, make_model
from ..observations import observation_instruments
from ..parameters import DISCREPANCY_SCALES, ParameterSpace
from .likelihood import GaussianMeanLikelihood
from .priors import PriorSet, learnt_prior, make_prior

#: deviations sampled by default (Table 2.1 minus the linear-axis squareness)
SAMPLED_DEVIATIONS = ("dx_BT", "dz_BT", "alpha_BT", "alpha_XB", "beta_XB", "gamma_XB",
                      "dx_CZ", "dy_CZ", "alpha_CZ", "beta_CZ")


def parameter_space(campaign, fix_dx_BT: bool, data: str) -> ParameterSpace:
    """The parameter space of a posterior of ``campaign``'s ``data``: the machine's sampled deviations and the
    campaign's nuisance terms, as its plug-in lays them out where it has one (the thesis': without dx_BT under the
    thesis assumption ``fix_dx_BT``)."""
    space_of = provided(campaign.machine, "parameter_space")
    if space_of is not None:
        return space_of(campaign, fix_dx_BT, data)
    if fix_dx_BT:
        raise ParameterError("fix_dx_BT", "the thesis assumption dx_BT = 0 belongs to the thesis machine; a "
                             "described machine selects its deviations with [machine] deviations = [...]")
    return described_space(campaign, data=data)


class LogPosterior:
    """Log posterior of ``campaign`` under forward model ``model``.

    Parameters
    ----------
    campaign : Campaign
    model : ``"linear"``, ``"htm-literal"`` or ``"htm-thesis"``
    fix_dx_BT : impose the thesis assumption dx_BT = 0 (Eq 4.2)
    sigma_model : fix the model-discrepancy scales (mm; one value for every scale) instead of sampling them
    data : ``"ballbar"`` (eccentricities), ``"probe"`` (touch-probe readings), ``"both"`` (the two), ``"rtest"``
        (R-test readings), their combinations ``"ballbar+rtest"``, ``"probe+rtest"``, or ``"all"``
        (:data:`~mtmcal_bayes.parameters.DATA_INSTRUMENTS`)
    sigma_prior : a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` learnt elsewhere: the prior of each scale it
        names (log-normal) instead of the assumed default; None: the defaults (or the campaign's ``[priors]``)
    space, observations, probe_layout : the :func:`parameter_space` of these choices, the campaign's ball-bar
        :class:`~mtmcal_bayes.observations.Observations` and its probe readings
        (:class:`~mtmcal_bayes.plugins.thesis.probe_model.ProbeLayout`), when already made (an analysis shares them between its
        variants); None: made here

    Attributes
    ----------
    names : sampled parameter names, length q (forward-model parameters, then the scales if sampled)
    priors : PriorSet over ``names``
    forward : the forward model, over the first ``p`` names
    scales : names of the discrepancy scales, one per instrument in the data (``sigma_model``,
        ``sigma_model_probe``), sampled or fixed
    scale_of : (m,) index into ``scales`` of each observation
    ballbar_observations : the campaign's ball-bar observations (None for touch-probe data alone)
    """

    def __init__(self, campaign, model: str = "linear", fix_dx_BT: bool = False, sigma_model: float | None = None, *,
                 data: str = "ballbar", sigma_prior=None, space: ParameterSpace | None = None, observations=None,
                 probe_layout=None):
        if sigma_prior is not None and sigma_model is not None:
            raise ValueError("a fixed sigma_model has no prior: give sigma_model or sigma_prior, not both")
        self.campaign = campaign
        self.model_name = model
        self.fix_dx_BT = fix_dx_BT
        self.data = check_data(data, campaign)
        self.space = space or parameter_space(campaign, fix_dx_BT, data)
        self.forward = make_model(model, campaign, self.space, data, observations=observations,
                                  probe_layout=probe_layout)
        #: the campaign's ball-bar observations (None for probe data alone)
        parts = self.forward.parts if isinstance(self.forward, JointModel) else [self.forward]
        self.ballbar_observations = observations or next(
            (p.observations for p in parts if p.observations.instrument == "ballbar"), None)
        instruments = observation_instruments(self.forward.observations)
        self.scales = tuple(DISCREPANCY_SCALES[i].name for i in dict.fromkeys(instruments))
        self.scale_of = np.array([self.scales.index(DISCREPANCY_SCALES[i].name) for i in instruments], dtype=int)
        self.likelihood = GaussianMeanLikelihood(self.forward.observations, campaign.ballbar.accuracy, self.scale_of)
        stated = campaign.rtest.prior_sds() if campaign.rtest is not None else None
        priors = [make_prior(p.name, p.base, p.kind, campaign.priors, stated=stated) for p in self.space.parameters]
        self.fixed_sigma = sigma_model
        self.sigma_prior = sigma_prior
        self.p = len(self.space)
        if sigma_model is None:
            priors += [learnt_prior(n, sigma_prior) if sigma_prior is not None and n in sigma_prior.scales
                       else make_prior(n, n, "length", campaign.priors) for n in self.scales]
        self.priors = PriorSet(priors)
        self._sigma_scale = np.array([q.scale for q in priors[self.p:]]) if sigma_model is None else None
        self.names = self.priors.names

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

    #: points (in sampling coordinates) at which :meth:`fingerprint` evaluates the density, and its seed
    FINGERPRINT_POINTS, FINGERPRINT_SEED = 16, 20261126

    def fingerprint(self) -> str:
        """A sha256 (hex) of what defines this posterior: the parameter names, model, data, fixed quantities and
        σ_model prior, and the log density at :data:`FINGERPRINT_POINTS` fixed points (9 significant digits), through
        which the campaign's observations, geometry and priors enter.  Equal for the same campaign content under
        the same choices, whatever the file is called."""
        import hashlib
        import json

        z = np.random.default_rng(self.FINGERPRINT_SEED).normal(size=(self.FINGERPRINT_POINTS, len(self)))
        prior = (None if self.sigma_prior is None else
                 {"scales": sorted(self.sigma_prior.scales.items()), "source": self.sigma_prior.source})
        text = json.dumps({"names": list(self.names), "model": self.model_name, "data": self.data,
                           "fix_dx_BT": self.fix_dx_BT, "sigma_model": self.fixed_sigma, "sigma_prior": prior,
                           "log_density": [f"{v:.9e}" for v in self(z)]})
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def describe(self) -> str:
        """The posterior's choices in words: ``"campaign c.toml, linear model, ballbar data, dx_BT sampled, σ_model
        sampled under its assumed prior"``."""
        if self.fixed_sigma is not None:
            sigma = f"σ_model fixed at {units.from_internal(self.fixed_sigma, 'um'):g} µm"
        elif self.sigma_prior is not None:
            sigma = f"σ_model sampled under the prior learnt by {self.sigma_prior.source}"
        else:
            sigma = "σ_model sampled under its assumed prior"
        return (f"campaign {self.campaign.source}, {self.model_name} model, {self.data} data, "
                f"dx_BT {'fixed at 0' if self.fix_dx_BT else 'sampled'}, {sigma}")

    # ------------------------------------------------------------ coordinates
    @property
    def sampled_scales(self) -> tuple[str, ...]:
        """The scales sampled beside the parameters (none when they are fixed)."""
        return self.scales if self.fixed_sigma is None else ()

    def to_theta(self, z: np.ndarray) -> np.ndarray:
        """Sampling coordinates ``(n, q)`` to parameters (internal units)."""
        theta = self.priors.centre + self.priors.width * np.asarray(z, dtype=float)
        if self.fixed_sigma is None:
            theta[..., self.p:] = self._sigma_scale * np.exp(np.asarray(z)[..., self.p:])
        return theta

    def to_z(self, theta: np.ndarray) -> np.ndarray:
        z = (np.asarray(theta, dtype=float) - self.priors.centre) / self.priors.width
        if self.fixed_sigma is None:
            with np.errstate(divide="ignore"):
                z[..., self.p:] = np.log(np.asarray(theta)[..., self.p:] / self._sigma_scale)
        return z

    def sigma(self, theta: np.ndarray) -> np.ndarray:
        """The discrepancy scales of each row ``(n, s)``, mm (s = ``len(scales)``)."""
        theta = np.atleast_2d(theta)
        if self.fixed_sigma is not None:
            return np.full((theta.shape[0], len(self.scales)), float(self.fixed_sigma))
        return theta[:, self.p:]

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

        Includes the Jacobian of the log coordinates of the scales; that of the
        affine scaling is constant and omitted.
        """
        z = np.atleast_2d(z)
        lp = self.log_prob_theta(self.to_theta(z))
        if self.fixed_sigma is None:
            lp = lp + z[:, self.p:].sum(axis=1)
        return lp
