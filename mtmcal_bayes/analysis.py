"""One campaign's analysis, built once and passed down: what every feature derives from a campaign.

A :class:`CampaignAnalysis` holds, for one campaign under one forward model, one choice of data
(``"ballbar"``, ``"probe"``, ``"both"``), the dx_BT assumption and the discrepancy scales (sampled under their
assumed prior or a prior learnt elsewhere, or fixed):

* the log posterior (:class:`~.inference.log_posterior.LogPosterior`): the observations, the parameter
  space, the forward model, the priors and the likelihood;
* the linearisation and the exact σ-marginal posterior of the linear model
  (:class:`~.inference.approximation.PosteriorApproximation`);
* the deterministic identification the machine's plug-in gives (the thesis': Eqs 4.10–4.18, 5.1–5.19).

Each is built when first asked for and kept.  The other analyses of the same campaign — another data set, the
linear model beside a kinematic one, dx_BT = 0, a fixed σ_model — come from :meth:`CampaignAnalysis.variant`
and share one cache, so the report, which needs the ball-bar-only, probe-only and fused posteriors, their
linear forms for the instruments' consistency check and the closed form at dx_BT = 0, builds each of them once.
The σ_model prior is part of what tells them apart: two analyses with different priors are never confused.

The campaign is not copied: an analysis assumes it is not changed afterwards.
"""

from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # imported where first used: ``import mtmcal_bayes`` loads no SciPy or ArviZ
    from .inference.approximation import PosteriorApproximation
    from .inference.log_posterior import LogPosterior
    from .sigma_prior import SigmaModelPrior


class CampaignAnalysis:
    """What a campaign becomes for one model, data set and scale assumption (module docstring).

    Parameters
    ----------
    campaign : Campaign
    model : ``"linear"``, ``"htm-literal"`` or ``"htm-thesis"``
    data : ``"ballbar"``, ``"probe"`` or ``"both"``
    fix_dx_BT : the thesis assumption dx_BT = 0 (Eq 4.2)
    sigma_model : the discrepancy scales fixed at this value (mm), or None (sampled)
    sigma_prior : the :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` of the sampled scales learnt elsewhere, or
        None (the assumed default); dropped when the scales are fixed (a fixed scale has no prior)
    """

    def __init__(self, campaign, *, model: str = "linear", data: str = "ballbar", fix_dx_BT: bool = False,
                 sigma_model: float | None = None, sigma_prior: SigmaModelPrior | None = None,
                 _family: dict | None = None):
        self.campaign = campaign
        self.model = model
        self.data = data
        self.fix_dx_BT = fix_dx_BT
        self.sigma_model = sigma_model
        self.sigma_prior = None if sigma_model is not None else sigma_prior
        self._family = {} if _family is None else _family
        self._family.setdefault(self.key, self)

    @property
    def key(self) -> tuple:
        """``(model, data, fix_dx_BT, sigma_model, sigma_prior)``: what tells the analyses of one campaign apart."""
        return self.model, self.data, self.fix_dx_BT, self.sigma_model, self.sigma_prior

    def variant(self, *, model: str | None = None, data: str | None = None, fix_dx_BT: bool | None = None,
                sigma_model: float | None | str = "same",
                sigma_prior: SigmaModelPrior | None | str = "same") -> CampaignAnalysis:
        """The analysis of the same campaign with the given choices changed (the others kept), from the shared
        cache: built once however often it is asked for.  ``sigma_model="same"`` keeps this one's; None samples.
        ``sigma_prior`` not given keeps this one's; None is the assumed default prior."""
        sigma = self.sigma_model if sigma_model == "same" else sigma_model
        learnt = self.sigma_prior if sigma_prior == "same" else sigma_prior
        key = (self.model if model is None else model, self.data if data is None else data,
               self.fix_dx_BT if fix_dx_BT is None else fix_dx_BT, sigma, None if sigma is not None else learnt)
        if key not in self._family:
            CampaignAnalysis(self.campaign, model=key[0], data=key[1], fix_dx_BT=key[2], sigma_model=key[3],
                             sigma_prior=key[4], _family=self._family)
        return self._family[key]

    def linear(self) -> CampaignAnalysis:
        """The linear model's analysis of the same data (exact closed forms; the instruments' consistency)."""
        return self.variant(model="linear")

    @cached_property
    def log_posterior(self) -> LogPosterior:
        """The log posterior: parameter space, forward model, priors, likelihood (built on first use)."""
        from .inference.log_posterior import LogPosterior

        return LogPosterior(self.campaign, self.model, fix_dx_BT=self.fix_dx_BT, sigma_model=self.sigma_model,
                            data=self.data, sigma_prior=self.sigma_prior, space=self.space,
                            observations=self.ballbar_observations,
                            probe_layout=self.probe_layout if self.data != "ballbar" else None)

    def _shared(self, key, make):
        """What ``make()`` derives from the campaign, made once for every variant of the family (kept under
        ``key``)."""
        if key not in self._family:
            self._family[key] = make()
        return self._family[key]

    @property
    def ballbar_observations(self):
        """The campaign's ball-bar observations (repeat means of every run), made once for every variant."""
        from .observations import Observations

        return self._shared("observations", lambda: Observations.from_campaign(self.campaign))

    @property
    def probe_layout(self):
        """The campaign's touch-probe readings and where they were taken, laid out for its probe models
        (:class:`~mtmcal_bayes.models.probe.ProbeLayout`, as the machine lays them out: ``probe_layout``), made once
        for every variant; None without probe readings."""
        from .models.probe import probe_layout

        if not self.campaign.has_probe_readings():
            return None
        return self._shared("probe_layout", lambda: probe_layout(self.campaign))

    @property
    def observations(self):
        """The observations of the data in the likelihood (ball-bar means, probe readings or both)."""
        return self.log_posterior.forward.observations

    @property
    def space(self):
        """The parameter space of this data and dx_BT assumption, made once for every variant that shares them (the
        forward models and the σ choices do not change it)."""
        from .inference.log_posterior import parameter_space

        return self._shared(("space", self.fix_dx_BT, self.data),
                            lambda: parameter_space(self.campaign, self.fix_dx_BT, self.data))

    @property
    def forward(self):
        return self.log_posterior.forward

    @cached_property
    def approximation(self) -> PosteriorApproximation:
        """The σ-marginal posterior of the model linearised at its mode: for ``linear`` with normal priors, the
        exact posterior."""
        from .inference.approximation import PosteriorApproximation

        return PosteriorApproximation(self.log_posterior)

    @property
    def marginal(self):
        """The exact σ-marginal posterior of the (linearised) model, a :class:`~.inference.marginal.MarginalPosterior`."""
        return self.approximation.marginal

    def alternative_reading(self) -> CampaignAnalysis | None:
        """This analysis (same model, data, dx_BT assumption and scales) of the campaign read the other way where its
        reading was a choice (:meth:`~mtmcal_bayes.campaign.Campaign.alternative_reading`); None when it records no
        choice.  The alternative campaign's analyses form one family, built once for every variant of this one."""
        root = self._shared("alternative reading", lambda: _alternative_root(self.campaign))
        if root is None:
            return None
        return root.variant(model=self.model, data=self.data, fix_dx_BT=self.fix_dx_BT, sigma_model=self.sigma_model,
                            sigma_prior=self.sigma_prior)

    def reading_choice(self, names):
        """Where the campaign's reading of some ball-bar runs was a choice: per quantity of ``names`` its estimate under
        the alternative reading, the shift in sd and whether it rests on the choice
        (:func:`~mtmcal_bayes.inference.reading_choice.choice_columns`: the exact σ-marginal posteriors of this
        analysis and of :meth:`alternative_reading`), a DataFrame indexed by quantity; None without a choice or when
        the data are the touch probe's alone (the ball-bar reading plays no part)."""
        if self.data == "probe":
            return None
        other = self.alternative_reading()
        if other is None:
            return None
        from .inference.reading_choice import choice_columns

        names = list(names)
        return choice_columns(self.approximation.moments(names), other.approximation.moments(names))

    @property
    def identification(self):
        """The deterministic identification the campaign's machine gives (its plug-in's ``identify``: the thesis',
        Eqs 4.10–4.18 and 5.1–5.19 beside the published values), shared by every variant; ``None`` where its
        plug-ins give none."""
        from .machines.plugins import provided

        identify = provided(self.campaign.machine, "identify")
        return None if identify is None else self._shared("identification", lambda: identify(self.campaign))

    def __repr__(self) -> str:
        sigma = "sampled" if self.sigma_model is None else f"{self.sigma_model:g} mm"
        learnt = "" if self.sigma_prior is None else f", sigma_prior=learnt ({self.sigma_prior.source})"
        return (f"CampaignAnalysis({self.campaign.source}, model={self.model}, data={self.data}, "
                f"fix_dx_BT={self.fix_dx_BT}, sigma_model={sigma}{learnt})")


def analysis_of(campaign, *, model: str | None = None, data: str | None = None, fix_dx_BT: bool | None = None,
                sigma_model: float | None | str = "same",
                sigma_prior: SigmaModelPrior | None | str = "same") -> CampaignAnalysis:
    """The analysis of ``campaign`` for these choices: a Campaign's new analysis (a choice not given takes its
    default: linear, ball bar, dx_BT sampled, σ_model sampled under its assumed prior), or, for a
    :class:`CampaignAnalysis`, its variant with the given choices changed (the others kept; the cache shared).
    ``sigma_prior``: a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`, or None for the assumed default."""
    if isinstance(campaign, CampaignAnalysis):
        return campaign.variant(model=model, data=data, fix_dx_BT=fix_dx_BT, sigma_model=sigma_model,
                                sigma_prior=sigma_prior)
    return CampaignAnalysis(campaign, model=model or "linear", data=data or "ballbar", fix_dx_BT=bool(fix_dx_BT),
                            sigma_model=None if sigma_model == "same" else sigma_model,
                            sigma_prior=None if sigma_prior == "same" else sigma_prior)


def _alternative_root(campaign) -> CampaignAnalysis | None:
    """The default analysis of ``campaign``'s alternative reading (its family's root), or None without a choice."""
    other = campaign.alternative_reading()
    return None if other is None else CampaignAnalysis(other)
