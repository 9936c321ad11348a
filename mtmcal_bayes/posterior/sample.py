"""One call from a campaign to its posterior: draws, summary, diagnostics, and the thesis values beside them."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..analysis import analysis_of
from ..inference.identifiability import campaign_identifiability
from ..inference import reading_choice
from ..inference.log_posterior import LogPosterior
from ..inference.results import (
    combination_summaries,
    diagnostics_warnings,
    not_identified,
    prior_sensitivity_notes,
    summarize,
    to_inference_data,
)
from ..inference.sampling import SamplerSettings, SamplingResult, run_ensembles
from ..io.netcdf import write_netcdf_atomic
from ..progress import Progress
from .checks import (
    ReferenceCheck,
    linear_model_check,
    reference_check,
    reference_warnings,
)
from .comparison import comparison, references
from .conformity import conformity_table


@dataclass(frozen=True)
class SamplerDiagnostics:
    """How the sampler run went: convergence, sizes, autocorrelation, ESS and R-hat, and what to heed.

    ``min_ess_bulk``, ``min_ess_tail`` and ``ess_bulk_per_second`` are over the reported quantities (those whose
    ESS stops the sampler, the discrepancy scales apart);
    ``max_r_hat`` over every summarised quantity; ``independence_acceptance`` how often the independence
    proposal from the linearised posterior was accepted; ``checks`` the stopping checks (steps, burn-in,
    R-hat, smallest ESS over its target); ``reference`` the comparison with the exact or linearised posterior.
    """

    converged: bool
    n_ensembles: int
    n_walkers: int
    n_steps: int
    burn_in: int
    tau_max_steps: float
    kept_draws: int
    acceptance: list[float]
    wall_time_s: float
    min_ess_bulk: float
    ess_bulk_per_second: float
    max_r_hat: float
    warnings: list[str]
    not_identified: list[str]
    messages: list[str]
    sampler: str
    target_ess: float
    min_ess_tail: float
    independence_acceptance: float
    checks: list[dict]
    reference: dict | None
    prior_sensitivity: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        return asdict(self)


@dataclass
class PosteriorResult:
    """The posterior of a campaign under one forward model.

    Attributes
    ----------
    idata : arviz.InferenceData
        posterior (display units: ″, µm), prior, posterior predictive, observed data, sample stats.
    summary : pandas.DataFrame
        one row per quantity: mean, sd, median, 95 % HDI, R-hat, bulk/tail ESS, unit, prior sd,
        identified (:func:`~mtmcal_bayes.inference.results.summarize`); where the campaign's reading of some
        ball-bar runs was a choice, the estimate under the alternative reading and whether the quantity rests on the
        choice (:data:`~mtmcal_bayes.inference.reading_choice.COLUMNS`).
    comparison : pandas.DataFrame
        each quantity's posterior beside the published deterministic values of its machine's plug-in (the thesis':
        ball bar and touch probe; :func:`~mtmcal_bayes.posterior.comparison.comparison`), empty where it has none.
    sampling : SamplingResult
        the chains of every ensemble in internal units, and the sampler's own facts.
    warnings, not_identified : sentences to heed; ``not_identified`` what the campaign's Jacobian leaves
        undetermined or determines only in combination.
    prior_notes : the prior-sensitivity diagnostic's sentences (the nuisance priors an interval rests on); they
        never decide what is identified.
    conformity : pandas.DataFrame or None
        with tolerances: per toleranced quantity its limits, probability of nonconformance and verdict
        (:func:`~mtmcal_bayes.posterior.conformity.conformity_table`).
    """

    idata: object
    summary: pd.DataFrame
    comparison: pd.DataFrame
    sampling: SamplingResult
    warnings: list[str] = field(default_factory=list)
    not_identified: list[str] = field(default_factory=list)
    reference: ReferenceCheck | None = None
    output: str | None = None  # where :meth:`save` wrote the NetCDF
    conformity: pd.DataFrame | None = None  # one row per toleranced quantity (posterior.conformity)
    identifiability: object | None = None  # what its campaign determines (Identifiability)
    combinations: list[dict] = field(default_factory=list)  # its named combinations with their posteriors
    prior_notes: list[str] = field(default_factory=list)  # the prior-sensitivity diagnostic's sentences
    reference_at: int | None = None  # where the reference check's warnings go in ``warnings``, while it is to come

    def check_reference(self) -> None:
        """Make the check against the approximation the sampler started from, left to come by
        :func:`sample_posterior` (``reference=False``): :attr:`reference` and its warnings, in their place."""
        if self.reference_at is None:
            return
        self.reference = reference_check(self.sampling, self.summary)
        at, self.reference_at = self.reference_at, None
        self.warnings[at:at] = reference_warnings(self.reference, self.summary)

    @property
    def log_posterior(self) -> LogPosterior:
        return self.sampling.posterior

    @property
    def model(self) -> str:
        return self.log_posterior.model_name

    @property
    def sigma_model_um(self) -> float:
        """The first discrepancy scale (the ball bar's ``sigma_model``, else the probe's), µm: its fixed value, or the
        posterior median where it was sampled."""
        return self.scales_um[self.log_posterior.scales[0]]

    @property
    def scales_um(self) -> dict[str, float]:
        """Each discrepancy scale, µm: its fixed value, or its posterior median where it was sampled."""
        post = self.log_posterior
        if post.fixed_sigma is not None:
            return {n: units.from_internal(post.fixed_sigma, "um") for n in post.scales}
        return {n: float(self.summary.loc[n, "median"]) for n in post.scales}

    @property
    def reading_choice_note(self) -> str:
        """One line saying what the mark of a quantity that rests on the campaign's choice of reading means
        (:mod:`~mtmcal_bayes.inference.reading_choice`); "" when the summary marks nothing of the kind."""
        return reading_choice.note(self.log_posterior.campaign) if reading_choice.has_choice(self.summary) else ""

    @property
    def data(self) -> str:
        """Which measurements the likelihood used: ``"ballbar"``, ``"probe"`` or ``"both"``."""
        return self.log_posterior.data

    @property
    def ess_quantities(self) -> list[str]:
        """The quantities the diagnostics' smallest ESS is over: every reported quantity (the set whose ESS stops
        the sampler), the discrepancy scales aside."""
        return [n for n in self.summary.index if n not in self.log_posterior.scales]

    @property
    def diagnostics(self) -> SamplerDiagnostics:
        r = self.sampling
        reported = self.summary.loc[self.ess_quantities]
        ess = reported["ess_bulk"]
        return SamplerDiagnostics(
            converged=r.converged, n_ensembles=r.chains.shape[0], n_walkers=r.chains.shape[2], n_steps=r.n_steps,
            burn_in=r.burn, tau_max_steps=float(np.nanmax(r.tau)), kept_draws=r.n_draws,
            acceptance=r.acceptance.tolist(), wall_time_s=r.wall_time, min_ess_bulk=float(ess.min()),
            ess_bulk_per_second=float(ess.min() / r.wall_time), max_r_hat=float(self.summary["r_hat"].max()),
            warnings=self.warnings, not_identified=self.not_identified, messages=r.messages,
            sampler=r.settings.sampler, target_ess=r.settings.target_ess, min_ess_tail=float(reported["ess_tail"].min()),
            independence_acceptance=r.independence_acceptance,
            checks=[{"steps": c.steps, "burn_in": c.burn, "max_r_hat": c.max_rhat, "min_ess_over_target": c.min_ess_ratio}
                    for c in r.checks],
            reference=None if self.reference is None else self.reference.to_json(),
            prior_sensitivity=self.prior_notes)

    def save(self, path) -> None:
        """Write the InferenceData as NetCDF (atomically); ``compensate --posterior`` reads it."""
        write_netcdf_atomic(self.idata, path)
        self.output = str(path)

    def to_json(self) -> dict:
        """What ``sample --json`` prints: summary and comparison per quantity, diagnostics (SPEC §10)."""
        from .output import posterior_json

        return {**posterior_json(self), "output": self.output}

    def to_text(self) -> str:
        """What ``sample`` prints: the summary beside the thesis values, diagnostics, the dx_BT = 0 effect."""
        from .output import format_sample

        return format_sample(self)


def sample_posterior(campaign, *, model: str | None = None, fix_dx_BT: bool | None = None,
                     settings: SamplerSettings | None = None, checkpoint=None,
                     progress: Progress | None = None, data: str | None = None,
                     tolerances: dict | None = None, sigma_model: float | None | str = "same",
                     statement: bool = True, sigma_prior="same", lean: bool = False,
                     sampled=None, reference: bool = True) -> PosteriorResult:
    """Sample the posterior of ``campaign`` given its ``data`` (``"ballbar"``, ``"probe"`` or ``"both"``) and
    summarise it against the deterministic results; decide conformity with ``tolerances`` (``{name:
    Tolerance}``; default the campaign's own).  ``sigma_model`` (mm) fixes the model-discrepancy scale instead of
    sampling it (None: sampled); ``sigma_prior`` (a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`) is the
    prior of the sampled scales learnt elsewhere (None: the assumed default).  ``campaign`` may be a
    :class:`~mtmcal_bayes.analysis.CampaignAnalysis`: what it has built (the log posterior, the linearised
    posterior, the identification) is used, not built again, and ``model``, ``data``, ``fix_dx_BT``,
    ``sigma_model`` and ``sigma_prior``, where given, change its own choices (else a campaign gets linear, ball
    bar, dx_BT and σ_model sampled, σ_model under its assumed prior).  ``statement=False``: a summary without the
    GUM statement and the uncertainty budget (a posterior shown beside another).  ``lean=True`` with exact draws
    (``settings.sampler == "exact"``), for a posterior whose intervals alone are shown: an InferenceData of the
    posterior alone (no prior, predictions or log-likelihood), no chain diagnostics, no check against the
    exact posterior (the draws are independent draws of it) and no check of the linear model's first order (its
    warnings are the main posterior's to give); with sampled chains it changes nothing.
    ``sampled(result)`` is called with the :class:`~mtmcal_bayes.inference.sampling.SamplingResult` as soon as the
    chains exist (a report begins the figures that need them alone); ``reference=False`` leaves the check against
    the approximation the sampler started from to the caller (:meth:`PosteriorResult.check_reference`)."""
    analysis = analysis_of(campaign, model=model, fix_dx_BT=fix_dx_BT, data=data, sigma_model=sigma_model,
                           sigma_prior=sigma_prior)
    campaign, post = analysis.campaign, analysis.log_posterior
    result = run_ensembles(post, settings, checkpoint=checkpoint, progress=progress,
                           approximation=analysis.approximation)
    if sampled is not None:
        sampled(result)
    seed = settings.seed if settings else None
    beside = lean and result.settings.sampler == "exact"  # exact draws whose intervals alone are shown
    idata = to_inference_data(result, seed=seed, posterior_only=beside)
    ident = campaign_identifiability(post)
    summary = summarize(idata, post, statement=statement, diagnostics=not beside, identifiability=ident)
    choice = analysis.reading_choice(summary.index) if statement else None  # a reading chosen over another
    if choice is not None:
        summary = summary.join(choice)
    # the machine's published deterministic values (its plug-in's; the least squares, which wants the posterior's
    # σ_model, joins them in the report)
    comp = comparison(summary, references(analysis.identification))
    ref = None if beside or not reference else reference_check(result, summary)
    warn = result.messages + ([] if beside else linear_model_check(result) + diagnostics_warnings(summary))
    reference_at = len(warn)  # where the check's warnings go (made later: check_reference)
    warn += reference_warnings(ref, summary)
    warn += [campaign.lacking_data_note()] if campaign.ballbar.planned else []  # planned runs: not in the data
    tol = campaign.tolerances if tolerances is None else tolerances
    conf = conformity_table(idata, summary, tol) if tol and statement else None
    if conf is not None:  # a quantity of the machine that this campaign holds at zero has no posterior to decide on
        warn += [f"tolerance {t.key or n}: no verdict, the campaign does not estimate {n} (held at zero)"
                 for n, t in tol.items() if n not in summary.index]
    return PosteriorResult(idata, summary, comp, result, warn, not_identified(summary), ref, conformity=conf,
                           identifiability=ident, combinations=combination_summaries(ident, idata),
                           prior_notes=prior_sensitivity_notes(summary),
                           reference_at=None if beside or reference else reference_at)
