"""``mtmcal-bayes report``: sample the posterior and write the report directory (SPEC §8).

The directory receives ``index.html`` (self-contained), every figure as PNG,
every table as CSV and the posterior as NetCDF.  Everything is written into a
temporary directory first and moved into place at the end, so a failure leaves
nothing half-written.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import time
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .. import units
from ..analysis import analysis_of
from ..conventions import reads_as_thesis
from ..figure_style import save_png
from ..html_page import Page
from ..inference import reading_choice
from ..inference.budget import sigma_prior_sentence
from ..inference.gum import GUM_COLUMNS, certificate_sentence
from ..inference.identifiability import DETERMINED, campaign_identifiability
from ..inference.sampling import SamplerSettings
from ..io.machine_reader import description_of
from ..io.netcdf import write_netcdf_atomic
from ..machines.plugins import provided
from ..models import models_of
from ..parameters import SCALE_LABEL, data_instruments
from ..planning import figures as plan_figures
from ..planning.plan import PlanResult, plan
from ..posterior.comparison import comparison, references
from ..posterior.conflict import ConflictAnalysis, explain_conflict
from ..posterior.conformity import (
    CONFORMITY_COLUMNS,
    conformity_table,
    row_tolerance_text,
)
from ..posterior.consistency import (
    DATA_WORDS,
    InstrumentComparison,
    compare_instruments,
)
from ..posterior.instrument_check import InstrumentCheck, blame, check_instruments, disputed_deviations
from ..posterior.least_squares import LeastSquares
from ..posterior.loo import LooResult, loo_check
from ..posterior.output import format_posterior, posterior_json
from ..posterior.sample import PosteriorResult, sample_posterior
from ..progress import Progress, ProgressEvent, emit
from ..version import __version__
from . import (
    budget_plot,
    compare,
    corner_plot,
    forest,
    loo_plot,
    mcmc_plots,
    polar,
    ppc,
    widths,
)
from . import machine_sections, rtest_sections
from .decisions import SUGGESTION_COLUMNS, add_suggestions, suggestion_text
from .drawing import Drawing
from .missing import missing_data
from .start import Begun, begin, check_output_dir

SUMMARY_COLUMNS = ["iso", "unit", "mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail",
                   "prior_sd", "sd_ratio", "identified", "identification", "combination", "identified_through",
                   "prior_sensitivity", "prior_growth", "nuisance_growth",
                   *GUM_COLUMNS]
REFERENCE_COLUMNS = ["ballbar", "ballbar_in_hdi", "ballbar_z", "probe_reported", "probe_reported_in_hdi",
                     "probe_reported_z", "probe_recomputed", "probe_recomputed_in_hdi", "probe_recomputed_z"]


@dataclass
class Report:
    """What :func:`build_report` wrote: the directory, file names, the summary table and console text."""

    directory: Path
    files: list[str]
    summary: pd.DataFrame
    console: str
    wall_time: float
    posterior: PosteriorResult
    missing: list[str]

    def to_json(self) -> dict:
        """What ``report --json`` prints: the posterior's JSON and what was written."""
        return {**posterior_json(self.posterior), "directory": str(self.directory), "files": self.files,
                "missing": self.missing, "wall_time_s": self.wall_time}

    def to_text(self) -> str:
        """What ``report`` prints."""
        return self.console


@dataclass
class ReportContent:
    """Everything the HTML page shows, computed before it is written."""

    campaign: object
    model: str
    posterior: PosteriorResult
    compared: dict[str, PosteriorResult] | None  # all models, when they are compared
    ident: object | None  # the deterministic identification (an IdentificationResult), where the machine's plug-ins give one
    missing: list[str]
    summary: pd.DataFrame
    ppc: pd.DataFrame | None  # None: no posterior saw the ball bar
    diagnostics: pd.DataFrame
    thesis_effect: pd.DataFrame | None
    off_scale: list[str]
    sigma_um: float
    fix_dx_BT: bool
    planned: PlanResult | None
    instruments: InstrumentComparison | None = None  # ball bar, probe, fused: when the campaign has probe readings
    loo: LooResult | None = None  # leave-one-out consistency of the main posterior's observations
    disputed: dict | None = None  # deviations the instruments disagree on, with the verdicts behind each
    conflict: ConflictAnalysis | None = None  # candidate explanations, when they disagree or a run is read otherwise
    shown: Shown | None = None  # the quantities listed and drawn, with their deterministic values
    machine_tables: dict = field(default_factory=dict)  # identifiability, least squares, truth (machine_sections)
    rtest: tuple | None = None  # the R-test's readings and nuisance terms (rtest_sections), where the posterior saw it
    pairs: InstrumentCheck | None = None  # every pair of the instruments, where the R-test is one of two or three


def summary_table(rep: PosteriorResult) -> pd.DataFrame:
    """summary.csv: one row per quantity with the posterior and the deterministic values beside it (and, where the
    campaign's reading of some ball-bar runs was a choice, the estimate under the alternative reading)."""
    s = rep.summary[SUMMARY_COLUMNS].copy()
    c = rep.comparison.reindex(s.index)
    for col in REFERENCE_COLUMNS:
        s[col] = c[col] if col in c else None
    if rep.conformity is not None:
        conf = rep.conformity.reindex(s.index)
        for col in CONFORMITY_COLUMNS + SUGGESTION_COLUMNS:
            s[col] = conf[col] if col in conf else None
    for col in reading_choice.COLUMNS if reading_choice.has_choice(rep.summary) else []:
        s[col] = rep.summary[col]
    s.index.name = "quantity"
    return s


def priors_table(post) -> pd.DataFrame:
    return pd.DataFrame([{"parameter": p.name, "prior": p.describe(), "reason": p.reason}
                         for p in post.priors.priors]).set_index("parameter")


def _side_posterior(analysis, settings: SamplerSettings, say, progress, *, ppc_here: bool):
    """How the report gets the posterior of other data than its main one, for the instruments' comparison: for the
    linear model (normal priors) exact draws of its closed-form σ-marginal posterior, which is what sampling would
    converge to; for a kinematic model the sampler.  The report shows their intervals; the ball-bar one, when the
    main posterior did not see the ball bar (not ``ppc_here``), also supplies the eccentricity plots (its
    predictions)."""
    def side(data: str) -> PosteriorResult:
        other = analysis.variant(data=data)
        exact = other.model == "linear" and other.approximation.exact
        how = "exact draws" if exact else "sampling"
        say(f"{how} of the posterior ({other.model}, {DATA_WORDS[data]}) to compare the instruments")
        s = dataclasses.replace(settings, sampler="exact") if exact else settings
        return sample_posterior(other, settings=s, progress=progress, statement=False,
                                lean=data != "ballbar" or ppc_here)
    return side


def build_report(campaign, out_dir, *, model: str = "linear", settings: SamplerSettings | None = None,
                 fix_dx_BT: bool = False, compare_models: bool = False, posterior: PosteriorResult | None = None,
                 progress: Progress | None = None, command: str = "", data: str = "ballbar",
                 tolerances: dict | None = None, sigma_model: float | None = None, sigma_prior=None,
                 begun: Begun | None = None) -> Report:
    """Sample, draw, tabulate and write the report of ``campaign`` (any machine's) into ``out_dir``.

    ``posterior``: a posterior of this campaign already sampled (its model, data, dx_BT assumption and σ_model
    prior then hold); else one is sampled with ``settings``.
    ``progress`` receives the sampler's events and one ``"report"`` event per stage.  ``data``: the
    measurements of the main posterior (``"ballbar"``, ``"probe"``, ``"both"``); a campaign with ball-bar runs and
    touch-probe readings also gets the three posteriors side by side and the instruments' consistency.
    ``tolerances`` (``{name: Tolerance}`` by the machine's names, default the campaign's own) adds the conformity
    decisions; ``sigma_model`` (mm) fixes the model-discrepancy scale of every posterior instead of sampling it;
    ``sigma_prior`` (a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`) is the prior of the sampled scales of every
    posterior, learnt elsewhere (None: the assumed default).  Each section appears where the campaign and its
    machine have what it needs (docs/report.md).  ``begun``: the report already begun into ``out_dir``
    (:func:`~.start.begin`, whose ``with`` block then holds this call), else it is begun here.
    """
    t0 = time.perf_counter()
    out_dir = Path(out_dir)
    if begun is None:
        check_output_dir(out_dir)
    settings = settings or SamplerSettings()

    def say(text: str) -> None:
        emit(progress, ProgressEvent("report", text))

    if posterior is not None:
        model, fix_dx_BT, data = posterior.model, posterior.log_posterior.fix_dx_BT, posterior.data
        sigma_model, sigma_prior = posterior.log_posterior.fixed_sigma, posterior.log_posterior.sigma_prior
    analysis = analysis_of(campaign, model=model, data=data, fix_dx_BT=fix_dx_BT, sigma_model=sigma_model,
                           sigma_prior=sigma_prior)
    campaign = analysis.campaign
    # the plug-in's own deterministic identification where it gives one (the thesis': its tables and section); the
    # least squares beside it on every machine come after the sampling (at its σ_model: Shown.of)
    ident = analysis.identification
    with contextlib.nullcontext(begun) if begun is not None else begin(campaign, out_dir) as started:
        tmp, drawing = started.directory, started.drawing
        try:
            ahead, planned_for = _ahead(analysis, drawing, say)
            tol = campaign.tolerances if tolerances is None else tolerances
            if posterior is not None:
                rep = posterior
                if tol:
                    rep.conformity = conformity_table(rep.idata, rep.summary, tol)
            else:
                say(f"sampling the posterior ({model}, {DATA_WORDS[data]})")
                # the figures that need the chains alone are drawn while they are summarised (the second core is
                # free then), the check against the exact posterior is made once the other figures are begun
                rep = sample_posterior(analysis, settings=settings, progress=progress, tolerances=tol,
                                       sampled=lambda result: _draw_chains(drawing, result, campaign, data=data, say=say),
                                       reference=False)
            if rep.conformity is not None and not rep.conformity.empty:
                say("asking the planner how to decide the undecided tolerances")
                add_suggestions(rep, campaign)
            shown = Shown.of(rep, ident)
            # the leave-one-out check in its figure's process (a posterior read from a file without the pointwise
            # log-likelihood is refused here, as before anything is drawn)
            loo = loo_check(rep.idata) if "log_likelihood" not in rep.idata.groups() else None
            # the main posterior's figures and its NetCDF while the instruments are weighed and the plan is made
            first = _main_figures(rep, model, loo, shown)
            first.insert(1, ("posterior.nc", lambda: write_netcdf_atomic(rep.idata, tmp / "posterior.nc")))
            # the eccentricity plots show the main posterior where it saw the ball bar, else the ball-bar one
            ppc_here = _saw_ballbar(data, campaign)
            ppc_df = None
            if ppc_here:
                ppc_df = ppc.ppc_table(rep.idata, campaign, analysis.ballbar_observations)
                first[2:2] = [job for job in _eccentricity_figures(rep, ppc_df, campaign)
                              if job[0] not in drawing.names]  # polar.png: begun with the chains
            rtest = None
            if rtest_sections.has_readings(rep):
                rtest = (rtest_sections.readings_table(rep), rtest_sections.terms_table(rep))
                first.insert(2, ("rtest.png", lambda: rtest_sections.readings_figure(rtest[0])))

            def draw(jobs):  # a batch of figures, drawn while the report goes on; a figure already failed stops it
                drawing.check()
                if jobs:
                    say("drawing " + ", ".join(name for name, _ in jobs))
                    drawing.start(jobs)

            draw(first)
            rep.check_reference()
            content = _rest_of_report(rep, analysis, campaign, settings=settings, say=say, progress=progress,
                                      compare_models=compare_models, draw=draw, ahead=ahead, drawing=drawing,
                                      ident=ident, shown=shown, ppc_here=ppc_here, planned_for=planned_for)
            if not ppc_here:
                ppc_df = content.ppc
            extras = drawing.finish()
            off_scale, content.conflict = extras["corner.png"], extras.get(CONFLICT_JOB)
            loo = extras["loo.png"] if loo is None else loo
            files = _write_tables(tmp, rep, content, ident=ident, ppc_df=ppc_df, loo=loo, shown=shown, rtest=rtest)
        finally:
            drawing.stop()
        files = [n for n in FIGURE_ORDER if (tmp / n).exists()] + files + ["posterior.nc"]
        page_content = ReportContent(campaign, model, rep, content.reports if compare_models else None,
                                     ident, content.missing, content.summary, ppc_df,
                                     content.diagnostics, content.effect, off_scale, rep.sigma_model_um,
                                     analysis.fix_dx_BT, content.planned, content.instruments, loo=loo,
                                     disputed=content.disputed, conflict=content.conflict, shown=shown,
                                     machine_tables=content.machine_tables, rtest=rtest, pairs=content.pairs)
        page = _page(page_content, tmp)
        elapsed = time.perf_counter() - t0
        files.insert(0, "index.html")
        seed = rep.sampling.settings.seed
        page.write(tmp / "index.html", _meta(campaign, model, seed, command=command, elapsed=elapsed))
    console = _console(rep, content.missing, out_dir=out_dir, files=files, elapsed=elapsed)
    return Report(out_dir, files, content.summary, console, elapsed, rep, content.missing)


@dataclass
class Shown:
    """Which quantities the report lists and draws: ``listed`` one by one (results, forest, widths, the plan's
    targets), ``joint`` in the corner, trace and rank plots, with every deterministic value of the machine beside
    them (``reference``: :func:`~mtmcal_bayes.posterior.comparison.comparison` of the posterior with the least
    squares and the plug-in's own values); ``least_squares`` the least-squares identification."""

    listed: list[str]
    joint: list[str]
    reference: pd.DataFrame
    least_squares: LeastSquares

    @classmethod
    def of(cls, rep: PosteriorResult, ident) -> Shown:
        """The quantities the machine's plug-in reports (the thesis': its eight, Table 4.5 order), listed and drawn
        together, else every deviation of the machine, those its campaign determines drawn together; beside the
        least squares at the posterior's σ_model and the values of the plug-in's own identification (``ident``)
        where it gives one."""
        post = rep.log_posterior
        own = provided(post.campaign.machine, "reported_quantities")
        if own is not None:
            listed = joint = [n for n in own if n in rep.summary.index]
        else:
            listed = [p.name for p in post.space.parameters if p.group == "deviation"]
            joint = machine_sections.shown_together(rep)
        ls = machine_sections.least_squares_of(rep)
        return cls(listed, joint, comparison(rep.summary, references(ident, ls)), ls)


#: the job that weighs the explanations of the instruments' conflict beside the figures (no file of its own)
CONFLICT_JOB = "explanations"
#: the job that makes the plan of the next measurement beside the sampling, and draws its figures
PLAN_JOB = "plan"
#: the plan's figures: file name, drawing function of a PlanResult
PLAN_FIGURES = (("plan_sweep.png", plan_figures.sweep_figure), ("plan_ranking.png", plan_figures.ranking_figure))


def _expected_unidentified(analysis) -> list[str]:
    """The quantities the report will list (:class:`Shown`) that the campaign's Jacobian leaves undetermined or
    determines only in combination: known before the posterior exists (it does not depend on σ_model), so the plan
    begun beside the sampling is the one the report shows."""
    listed = provided(analysis.campaign.machine, "reported_quantities",
                      [p.name for p in analysis.space.parameters if p.group == "deviation"])
    determined = campaign_identifiability(analysis.log_posterior)
    return [n for n in listed if determined.of(n)[0] not in (None, DETERMINED)]


def _saw_ballbar(data: str, campaign) -> bool:
    """Whether a posterior of ``data`` saw the campaign's ball-bar runs."""
    return "ballbar" in data_instruments(data, campaign) and bool(campaign.ballbar.runs)


def _plans(campaign) -> bool:
    """Whether the planner can rank measurements for this campaign: its catalogue starts from a ball-bar set-up."""
    return bool(campaign.ballbar.setups)


def _plan_and_figures(campaign, directory: Path, *, targets=None, sigma_prior=None, data: str = "ballbar"):
    """A drawing job: the plan (:func:`~mtmcal_bayes.planning.plan.plan`, given the report's ``data``, under the
    posterior's learnt σ_model prior ``sigma_prior`` if any) and its figures written into ``directory``; returns
    ``(None, plan)``."""
    planned = plan(campaign, targets, sigma_prior=sigma_prior, data=data)
    for name, make in PLAN_FIGURES:
        save_png(make(planned), directory / name)
    return None, planned


def _compares_instruments(campaign) -> bool:
    """Whether the campaign has two instruments to set side by side: ball-bar runs and touch-probe readings the
    likelihood can take (else :func:`~.missing.missing_data` says why not)."""
    return bool(campaign.ballbar.runs) and campaign.has_probe_readings() and campaign.probe_gap() is None


def _ahead(analysis, drawing: Drawing, say) -> tuple[dict[str, int], list[str]]:
    """Begin, before the posterior is sampled, what needs the campaign alone, each in a process of its own (the
    sampler leaves the second core idle): the plan for the listed quantities the campaign's Jacobian does not
    determine one by one (:func:`_expected_unidentified`; none: the planner's default targets) and its figures and,
    for a campaign with both instruments some of whose
    B runs read otherwise than in the thesis, the weighing of the explanations of a conflict between them, which
    that reading always wants (elsewhere it is begun only when the comparison finds a conflict,
    :func:`_rest_of_report`).  Returns their batches by job name
    and the targets the plan was begun for.  (The figures of the machine's description were begun before, with
    the report: :func:`~.start.begin`.)"""
    campaign = analysis.campaign
    ahead = {}
    targets = _expected_unidentified(analysis)
    if _plans(campaign):
        say("planning the next measurement (beside the sampling)")
        ahead[PLAN_JOB] = drawing.start([(PLAN_JOB, lambda: _plan_and_figures(
            campaign, drawing.directory, targets=targets or None, sigma_prior=analysis.sigma_prior,
            data=analysis.data))])
    if _compares_instruments(campaign) and not reads_as_thesis(campaign.ballbar):  # wanted whatever the comparison
        say("weighing the explanations of a conflict between the instruments and the readings of the B runs "
            "(beside the sampling)")
        ahead[CONFLICT_JOB] = drawing.start([_conflict_job(analysis)])
    return ahead, targets


def _conflict_job(analysis) -> tuple:
    """The drawing job that weighs the explanations of a conflict between the instruments (no file of its own; the
    report shows its own consistency check, so none for the candidates)."""
    return CONFLICT_JOB, lambda: (None, explain_conflict(analysis, consistency_of=0))


#: the figures in the order the report's file list names them
FIGURE_ORDER = ("machine.png", "deviations.png", "corner.png", "forest.png", "ppc.png", "polar.png", "widths.png",
                "rank.png", "trace.png", "loo.png", "compare_forest.png", "compare_ppc.png", "instruments_forest.png",
                "budget.png", "sigma_model.png", "plan_ranking.png", "plan_sweep.png", "rtest.png")


def _draw_chains(drawing: Drawing, result, campaign, *, data: str, say) -> None:
    """Begin the main posterior's figures that need its chains alone (the polar trajectories, where it saw the ball
    bar) in one process, while the report summarises them."""
    if _saw_ballbar(data, campaign):
        say("drawing polar.png")
        drawing.start([("polar.png", lambda: polar.polar_figure(result, campaign))], workers=1)


def _loo_job(rep: PosteriorResult, loo: LooResult | None):
    """The leave-one-out figure and, when ``loo`` is None, the check itself (PSIS-LOO of every observation), made in
    the figure's process: ``(figure, check)``."""
    loo = loo_check(rep.idata) if loo is None else loo
    return loo_plot.loo_figure(loo), loo


def _main_figures(rep: PosteriorResult, model: str, loo: LooResult | None, shown: Shown) -> list:
    """The figures that show the main posterior alone: drawn as soon as it exists (the longest first, so that the
    two drawing processes end together); the leave-one-out check with its figure where ``loo`` is None."""
    return [("corner.png", lambda: corner_plot.corner_figure(rep.idata, shown.reference, names=shown.joint)),
            ("sigma_model.png", lambda: budget_plot.sigma_figure(rep, names=shown.joint)),
            ("trace.png", lambda: mcmc_plots.trace_figure(rep.sampling, names=shown.joint)),
            ("forest.png", lambda: forest.forest_figure({model: rep.summary}, shown.reference, names=shown.listed)),
            ("rank.png", lambda: mcmc_plots.rank_figure(rep.idata, names=shown.joint)),
            ("budget.png", lambda: budget_plot.budget_figure(rep.summary)),
            ("widths.png", lambda: widths.widths_figure(rep.summary, names=shown.listed)),
            ("loo.png", lambda: _loo_job(rep, loo))]


def _eccentricity_figures(bb_rep: PosteriorResult, ppc_df: pd.DataFrame, campaign) -> list:
    """The posterior predictive check and the polar trajectories of a posterior that saw the ball bar."""
    return [("ppc.png", lambda: ppc.ppc_figure({bb_rep.model: ppc_df}, campaign)),
            ("polar.png", lambda: polar.polar_figure(bb_rep.sampling, campaign))]


@dataclass
class _Rest:
    """What the report computes beside the main posterior, and the figures that show it."""

    instruments: InstrumentComparison | None
    disputed: dict | None
    conflict: ConflictAnalysis | None
    reports: dict
    missing: list[str]
    summary: pd.DataFrame
    diagnostics: pd.DataFrame
    effect: pd.DataFrame | None
    planned: PlanResult | None  # None: the planner has no catalogue for this campaign (no ball-bar set-up)
    ppc: pd.DataFrame | None  # the ball-bar posterior's predictive check, when it is a side posterior
    machine_tables: dict  # identifiability, combinations, least squares, truth: where the posterior has them
    pairs: InstrumentCheck | None = None  # every pair of the instruments, where the R-test is one of two or three


def _rest_of_report(rep, analysis, campaign, *, settings, say, progress, compare_models, draw, ahead, drawing,
                    ident, shown: Shown, ppc_here: bool, planned_for: list[str]) -> _Rest:
    """The instruments' comparison, the model comparison, the tables, the dx_BT = 0 effect and the plan; the figures
    of the comparison are handed to ``draw`` as soon as it exists, those of the model comparison (and of a plan made
    here) once the plan exists.  The plan with its figures and the weighing of the instruments' conflict (only a
    table shows it) were begun before the sampling (``ahead``, :func:`_ahead`): the weighing is dropped here when
    the comparison does not want it, else its result comes back with the figures (``_Rest.conflict`` is filled in
    then)."""
    model, data = analysis.model, analysis.data
    instruments = disputed = ppc_df = pairs = None
    if campaign.has_rtest_readings() and len(data_instruments("all", campaign)) >= 2:
        say("checking every pair of the instruments (the R-test's included)")
        pairs = check_instruments(analysis, explain=False)
        disputed = pairs.disputed
    if _compares_instruments(campaign):
        instruments = compare_instruments({data: rep}, _side_posterior(analysis, settings, say, progress, ppc_here=ppc_here),
                                          data_instruments("all", campaign))
        if pairs is None:  # else every pair's verdicts, the ball bar / probe pair's among them
            disputed = disputed_deviations(instruments.consistency, instruments.posteriors["ballbar"].log_posterior,
                                           instruments.posteriors["probe"].log_posterior)
        if instruments.consistency.disagreeing and CONFLICT_JOB not in ahead:  # a conflict to explain after all
            say("weighing the explanations of the conflict between the instruments")
            ahead[CONFLICT_JOB] = drawing.start([_conflict_job(analysis)])
        figures = [("instruments_forest.png", lambda: forest.forest_figure(
            {instruments.labels[d]: r.summary for d, r in instruments.posteriors.items()}, shown.reference,
            names=shown.listed))]
        if not ppc_here:  # the eccentricity plots show the ball-bar posterior, a side one here
            ppc_df = ppc.ppc_table(instruments.posteriors["ballbar"].idata, campaign, analysis.ballbar_observations)
            figures += _eccentricity_figures(instruments.posteriors["ballbar"], ppc_df, campaign)
        draw(figures)
    reports = {model: rep}
    compared = models_of(campaign.machine)
    if compare_models:
        for other in compared:
            if other != model:
                variant = analysis.variant(model=other)
                # exact draws where this model's posterior has them, else the sampler
                s = (settings if settings.sampler != "exact" or variant.approximation.exact
                     else dataclasses.replace(settings, sampler="emcee"))
                say(f"sampling the posterior ({other}) for the model comparison")
                reports[other] = sample_posterior(variant, settings=s, progress=progress)
        reports = {m: reports[m] for m in compared}
    draw([])  # a figure of an earlier batch already failed: stop before planning
    planned, drawn = None, True
    if PLAN_JOB in ahead:
        planned, drawn = _planning(campaign, rep, drawing, batch=ahead[PLAN_JOB], say=say, listed=shown.listed,
                                   planned_for=planned_for)
    figures = [] if drawn else [(name, lambda make=make: make(planned)) for name, make in PLAN_FIGURES]
    if compare_models:
        figures[:0] = [("compare_forest.png", lambda: forest.forest_figure(
                            {m: r.summary for m, r in reports.items()}, shown.reference, names=shown.listed))]
        if _saw_ballbar(data, campaign):
            figures.append(("compare_ppc.png", lambda: ppc.ppc_figure(
                {m: ppc.ppc_table(r.idata, campaign, analysis.ballbar_observations) for m, r in reports.items()},
                campaign)))
    draw(figures)
    missing = missing_data(campaign, ident)
    assumption = provided(campaign.machine, "assumption_effect")  # a plug-in's assumption (the thesis': dx_BT = 0)
    effect = (assumption(analysis, sigma_model_um=rep.sigma_model_um)
              if assumption is not None and not analysis.fix_dx_BT else None)
    # the Jacobian's statement and the least squares on every machine; the stated truth of a simulated campaign
    machine_tables = machine_sections.tables(rep, shown.least_squares, campaign.truth)
    return _Rest(instruments, disputed, None, reports, missing, summary_table(rep),
                 mcmc_plots.diagnostics_table(rep.summary, rep.sampling), effect, planned, ppc_df, machine_tables,
                 pairs)


def _write_tables(tmp: Path, rep: PosteriorResult, c: _Rest, *, ident,
                  ppc_df: pd.DataFrame | None, loo: LooResult, shown: Shown, rtest: tuple | None) -> list[str]:
    """Every CSV of the report into ``tmp``; returns their names in order."""
    files: list[str] = []

    def csv(name, df, index=True):
        df.to_csv(tmp / name, index=index, float_format="%.6g")
        files.append(name)

    csv("summary.csv", c.summary)
    if ppc_df is not None:
        csv("ppc.csv", ppc_df)
    if rtest is not None:
        csv("rtest.csv", rtest[0], index=False)
        csv("rtest_terms.csv", rtest[1], index=False)
    csv("loo.csv", loo.table)
    csv("diagnostics.csv", c.diagnostics)
    csv("priors.csv", priors_table(rep.log_posterior))
    own = provided(rep.log_posterior.campaign.machine, "report_tables")  # a plug-in's sections' (the thesis')
    if own is not None:
        for name, df, index in own(ident, c.effect):
            csv(name, df, index=index)
    for name, df in c.machine_tables.items():
        csv(name, df, index=False)
    if len(c.reports) > 1:
        csv("compare_models.csv", compare.model_comparison_table(c.reports, shown.listed), index=False)
        if ppc_df is not None and _saw_ballbar(rep.data, rep.log_posterior.campaign):  # each model's ball-bar fit
            csv("compare_fit.csv", compare.model_fit_table(c.reports, rep.log_posterior.campaign))
    if c.instruments is not None:
        csv("instruments.csv", c.instruments.intervals, index=False)
        csv("consistency.csv", c.instruments.consistency.groups, index=False)
        csv("consistency_readings.csv", c.instruments.consistency.readings, index=False)
        if c.conflict is not None:
            csv("explanations.csv", c.conflict.table(), index=False)
    if c.pairs is not None:
        csv("consistency_pairs.csv", c.pairs.consistency.groups, index=False)
    csv("budget.csv", budget_table(rep.summary))
    if c.planned is not None:
        csv("plan.csv", c.planned.table, index=False)
    return files


def _meta(campaign, model, seed, *, command, elapsed) -> str:
    now = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    seed = "none (not reproducible)" if seed is None else seed
    return (f"Campaign {campaign.source} · model {model} · seed {seed} · mtmcal-bayes {__version__} · "
            f"generated {now} in {elapsed:.0f} s" + (f" · command: {command}" if command else ""))


def _console(rep, missing, *, out_dir, files, elapsed) -> str:
    lines = [format_posterior(rep)]
    if rep.warnings:
        lines += ["", "Warnings:"] + [f"  - {w}" for w in rep.warnings]
    if missing:
        lines += ["", "Missing from this campaign:"] + [f"  - {m}" for m in missing]
    lines += ["", f"report written to {out_dir}/ in {elapsed:.0f} s: " + ", ".join(files),
              f"open {out_dir / 'index.html'} in a browser"]
    return "\n".join(lines)


def _results_table(summary: pd.DataFrame, listed: list[str]) -> pd.DataFrame:
    """The results as the page shows them: the ``listed`` quantities first, then the others; the columns of
    deterministic values only where the campaign has any."""
    s = summary.loc[[n for n in listed if n in summary.index] + [n for n in summary.index if n not in listed]]
    unit = s["unit"].map({"arcsec": "″", "um": "µm"})
    out = pd.DataFrame({"ISO 230-7": s["iso"].fillna("—"), "unit": unit, "mean": s["mean"], "sd": s["sd"], "HDI 2.5 %": s["hdi_low"],
                        "HDI 97.5 %": s["hdi_high"], "ball bar": s["ballbar"], "in HDI": s["ballbar_in_hdi"],
                        "probe (thesis)": s["probe_reported"], "in HDI ": s["probe_reported_in_hdi"],
                        "probe (recomputed)": s["probe_recomputed"], "in HDI  ": s["probe_recomputed_in_hdi"],
                        "R-hat": s["r_hat"], "bulk ESS": s["ess_bulk"].round(0).astype(int),
                        "identified by": s["identification"], "prior sensitivity": s["prior_sensitivity"]})
    for value, inside in (("ball bar", "in HDI"), ("probe (thesis)", "in HDI "), ("probe (recomputed)", "in HDI  ")):
        if out[value].isna().all():  # no such deterministic value in this campaign
            out = out.drop(columns=[value, inside])
    if reading_choice.has_choice(s):  # the mark and the value under the best rejected reading
        out[reading_choice.HEAD] = [reading_choice.mark_cell(r) for _, r in s.iterrows()]
    return out


def sampler_paragraph(rep: PosteriorResult) -> str:
    """How the posterior was sampled and by what rule it stopped, in words."""
    d, s = rep.diagnostics, rep.sampling.settings
    if d.sampler == "exact":
        return (f"{d.kept_draws} independent draws of the exact σ-marginal posterior of the linear model in "
                f"{d.n_ensembles} chains, no MCMC ({d.wall_time_s:.1f} s).")
    ref = rep.sampling.approximation.kind if rep.sampling.approximation is not None else "prior"
    n = units.in_words(len(rep.ess_quantities))
    return (f"{d.n_ensembles} independent emcee ensembles × {d.n_walkers} walkers, started from draws of the {ref}; "
            f"moves: independence proposals from it (accepted {100 * d.independence_acceptance:.0f} %) and "
            f"differential evolution. {d.n_steps} steps each (burn-in {d.burn_in}, detected), largest integrated "
            f"autocorrelation time {d.tau_max_steps:.1f} steps, {'converged' if d.converged else 'NOT converged'} "
            f"by the rule: R-hat ≤ {s.max_rhat} across the ensembles and their halves in time, bulk and tail ESS ≥ "
            f"{s.target_ess:g} for each of the {n} quantities and ≥ {s.target_ess_sigma:g} for sigma_model; "
            f"max R-hat {d.max_r_hat:.3f}, min bulk / tail ESS of the {n} {d.min_ess_bulk:.0f} / "
            f"{d.min_ess_tail:.0f}, sampling {d.wall_time_s:.1f} s. R-hat is computed across the independent "
            "ensembles (the walkers of one ensemble are not independent chains).")


def reference_table(check) -> pd.DataFrame:
    """Per quantity: reference mean and sd, and the sampled posterior's differences from them."""
    return pd.DataFrame({"reference mean": check.reference_mean, "reference sd": check.reference_sd,
                         "mean difference [sd]": check.mean_diff_sd, "sd difference [%]": check.sd_diff_pct})


def _instruments_section(page: Page, c: ReportContent, tmp: Path) -> None:
    ins = c.instruments
    page.section("instruments", ("Ball bar, touch probe and R-test" if "rtest" in ins.labels else "Ball bar and touch probe")
                 + ": each alone and fused")
    cons = ins.consistency
    page.paragraph(
        "The touch-probe readings (sphere centres at indexed positions of the rotary axes) enter the likelihood through the same "
        "kinematic chain as the ball bar (docs/probe.md). Do the instruments agree? Each instrument's readings "
        "are predicted from the other's posterior (its own nuisance terms from their priors); per reading group "
        "a χ² of the standardised residuals gives the verdict (disagree: p < 0.01). "
        + " ".join(f"{g['group']} given the {g['given']}-only posterior: {g['verdict']} (χ² = {g['chi2']:.1f} on "
                   f"{g['dof']} dof, p = {g['p_value']:.2g}, largest |z| = {g['max_abs_z']:.1f} at {g['worst']})."
                   for _, g in cons.groups.iterrows()))
    fused = ins.fused
    post = fused.log_posterior
    if post.fixed_sigma is None:
        scales = {n: (float(fused.summary.loc[n, "mean"]), float(fused.summary.loc[n, "sd"])) for n in post.scales}
        priors = {p.name: p for p in post.priors.priors[post.p:]}
        page.paragraph(blame(scales, priors))
    if cons.disagreeing:
        page.paragraph("Where a group disagrees, the fused posterior combines measurements the model cannot "
                       "reconcile: its intervals are not to be trusted until the cause is found. "
                       + " ".join(ins.disagreements))
    if c.disputed:
        page.paragraph("The instruments disagree on " + ", ".join(c.disputed) + " (each moves the readings of a "
                       "disagreeing group beyond what its datum terms absorb); compensate refuses them unless the "
                       "disagreement is accepted (section 'Compensation').")
    page.figure(tmp / "instruments_forest.png", forest.CAPTION_DATA, "intervals by data")
    sd = ins.intervals.pivot(index="quantity", columns="data", values="sd")[list(ins.labels.values())]
    page.table(sd.rename(columns=lambda col: f"sd, {col}"), digits=2)
    if c.conflict is not None:
        page.paragraph(
            "Where a conflict could come from, each candidate weighed by the marginal likelihood of the fused linear "
            "model (both instruments, every parameter and both discrepancy scales integrated out; log Bayes factor "
            "against the campaign as given: above 2.3 strong, above 4.6 decisive): the readings of the B runs (where "
            "the samples at B = 0° and 90° were drawn, the BY bar's side; docs/conventions.md), the stylus length "
            "along its axis, a difference of each rotary axis' angles between the two sessions. Quantities are the "
            "fused posterior means under each candidate (″, µm). Full table: explanations.csv; the choice for the "
            "built-in campaign: docs/thesis-notes.md.")
        t = c.conflict.table().head(8)
        scales = [col for col in t.columns if col.endswith("_um")]
        show = ["candidate", "log_bayes_factor"] + scales + list(c.conflict.shown)
        page.table(t[show].rename(columns={"log_bayes_factor": "log BF", "alpha_XB+gamma_XB": "α_XB+γ_XB"}),
                   digits=2, index=False)


def _pairs_section(page: Page, check: InstrumentCheck) -> None:
    """Every pair of the instruments, each against the other's posterior (``mtmcal-bayes instruments``), where the
    R-test is one of them."""
    g = check.consistency.groups
    page.section("pairs", "The instruments, pair by pair")
    page.paragraph(
        "Each instrument's readings predicted from the posterior of another's data alone (the exact linear "
        "posterior; its own nuisance terms from their priors, the broad ones profiled out), per reading group: each "
        "R-test run, each ball-bar run, each probe run; a χ² on the rank of the predictive covariance gives the "
        "verdict (disagree: p < 0.01; docs/rtest.md, 'Three instruments'). The fused posterior's discrepancy scales: "
        + ", ".join(f"{SCALE_LABEL[n]} {m:.2f} ± {sd:.2f} µm" for n, (m, sd) in check.scales.items())
        + ". consistency_pairs.csv.")
    if check.disputed:
        page.paragraph("The instruments disagree on " + ", ".join(check.disputed) + ": "
                       + "; ".join(dict.fromkeys(w for v in check.disputed.values() for w in v)) + ". Compensate "
                       "refuses them unless the "
                       "disagreement is accepted (section 'Compensation').")
    cols = [col for col in ("pair", "group", "given", "chi2", "dof", "p_value", "max_abs_z", "worst", "verdict")
            if col in g.columns]
    page.table(g[cols], digits={"chi2": 1, "p_value": 3, "max_abs_z": 2}, index=False)


def _compensation_section(page: Page, c: ReportContent) -> None:
    page.section("compensation", "Compensation")
    base = ("mtmcal-bayes compensate rewrites X/Y/Z of an NC program so the tool point reaches the programmed points "
            "(exact inversion of the kinematic model with the posterior mean; the residual error per block from the "
            "posterior, and the error no block of the program exceeds with 95 % probability; docs/compensation.md). ")
    if c.disputed:
        where = ("two of the instruments disagree on " if c.pairs is not None else
                 "the ball bar and the touch probe disagree on ")
        page.paragraph(base + "On this campaign it refuses: " + where + ", ".join(c.disputed)
                       + (" (section 'The instruments, pair by pair')" if c.pairs is not None else
                          " (section 'Ball bar and touch probe')") + ", and a deviation with the "
                       "wrong sign doubles the error it was meant to remove. Find the cause, or pass "
                       "--accept-disagreement to compensate anyway (with a warning).")
    elif c.pairs is not None:
        page.paragraph(base + "Every pair of the instruments agrees on every deviation both measure, so it "
                       "compensates without asking; deviations the data do not determine one by one, and those whose "
                       "values rest on nuisance priors, are named in its warnings.")
    elif c.instruments is not None:
        page.paragraph(base + "The two instruments agree on every deviation they both measure, so it compensates "
                       "without asking; deviations the data do not determine one by one, and those whose values rest "
                       "on nuisance priors, are named in its warnings.")
    else:
        page.paragraph(base + "This campaign has one instrument: nothing checks its deviations against a second one.")
    if reading_choice.marked(c.posterior.summary):
        page.paragraph(f"The deviations marked {reading_choice.MARK} in the results rest on the reading chosen for "
                       "some ball-bar runs: compensate marks each one it uses and names them in its summary, with "
                       "its value under the best rejected reading.")


def budget_table(summary: pd.DataFrame) -> pd.DataFrame:
    """budget.csv: per quantity the share of its posterior variance from each source (columns), summing to 1."""
    cols = [c for c in summary.columns if c.startswith("budget:")]
    out = summary.loc[summary[cols].notna().any(axis=1), cols]
    return out.rename(columns=lambda c: c.split(":", 1)[1]).rename_axis("quantity")


def _budget_section(page: Page, rep: PosteriorResult, tmp: Path, *, sigma_names) -> None:
    """The uncertainty budget's section; ``sigma_names``: the quantities ``sigma_model.png`` was drawn for."""
    post = rep.log_posterior
    page.section("budget", "Uncertainty budget")
    how = (f"σ_model fixed at {rep.sigma_model_um:g} µm" if post.fixed_sigma is not None else
           "averaged over σ_model's posterior, with the extra variance of not knowing σ_model (law of total variance)")
    page.paragraph(f"Where each quantity's posterior variance comes from ({how}"
                   + ("" if post.model_name == "linear" else f"; the {post.model_name} model linearised at the "
                      "posterior mean") + "). A share dominated by σ_model or by a prior says the interval is "
                   "mostly a property of that assumption, not of the machine; docs/metrology.md, budget.csv. "
                   + sigma_prior_sentence(post))
    page.figure(tmp / "budget.png", budget_plot.BUDGET_CAPTION, "uncertainty budget")
    page.table((100 * budget_table(rep.summary)).round(1), digits=1)
    page.figure(tmp / "sigma_model.png", budget_plot.sigma_caption(sigma_names), "posterior sd against sigma_model")


def _statement_section(page: Page, rep: PosteriorResult) -> None:
    """The GUM statement of each quantity as a calibration certificate gives it, and the tolerance decisions."""
    s = rep.summary
    page.section("statement", "Uncertainty statement")
    page.paragraph(
        "In the form of a calibration certificate (GUM, JCGM 100; GUM Supplement 1, JCGM 101: the posterior draws "
        "are the Monte-Carlo sample). The expanded uncertainty U = k·u is stated only where the posterior is close "
        "to Gaussian (y ± U within the numerical tolerance of the probabilistically symmetric interval, GUM-S1 §8); "
        "elsewhere the coverage intervals are the statement. ISO 230-7 symbols as in docs/metrology.md.")
    page.box("statement", "Results", [certificate_sentence(n, r, r["iso"] if isinstance(r["iso"], str) else None)
                                      for n, r in s.iterrows() if n != "sigma_model"])
    gum = s.rename_axis("quantity")[["iso", "mean", "u", "ci95_shortest_low", "ci95_shortest_high", "ci95_symmetric_low", "ci95_symmetric_high",
             "U", "k", "endpoint_tolerance", "significant_digits"]]
    if reading_choice.has_choice(s):
        page.paragraph(reading_choice.short_note() + ".")
        gum = gum.assign(**{reading_choice.HEAD: [reading_choice.mark_cell(r) for _, r in s.iterrows()]})
    page.table(gum.rename(columns={"iso": "ISO 230-7", "mean": "estimate", "ci95_shortest_low": "shortest low",
                                   "ci95_shortest_high": "shortest high", "ci95_symmetric_low": "symmetric low",
                                   "ci95_symmetric_high": "symmetric high", "endpoint_tolerance": "endpoints ±",
                                   "significant_digits": "digits"}), digits=3)
    if rep.conformity is None or rep.conformity.empty:
        return
    page.section("conformity", "Conformity with the tolerances")
    page.paragraph(
        "ISO 14253-1 decision rule with guard bands equal to the uncertainty: conforms when the shortest 95 % "
        "coverage interval lies inside the tolerance, does not conform when it lies wholly outside, undecided when "
        "it straddles a limit; no verdict ('not determined by the data') where the campaign's data do not determine "
        "the quantity one by one, whose interval is then its prior's. P(nonconformance) is the posterior probability "
        "of lying outside the tolerance. For an undecided quantity the planner names the next measurement that would "
        "make it most certain.")
    rows = []
    for n, r in rep.conformity.iterrows():
        unit = s.loc[n, "unit"]
        nxt = r.get("next_measurement")
        rows.append({"quantity": n, "ISO 230-7": s.loc[n, "iso"] or "—", "tolerance": row_tolerance_text(r, unit),
                     "P(nonconformance)": r["p_nonconformance"], "verdict": r["conformity"],
                     "next measurement": suggestion_text(n, r, units.SYMBOL[unit]) if isinstance(nxt, str) else ""})
    page.table(pd.DataFrame(rows), digits={"P(nonconformance)": 3}, index=False)


def _planning(campaign, rep, drawing: Drawing, *, batch: int, say, listed: list[str],
              planned_for: list[str]) -> tuple[PlanResult, bool]:
    """The plan for the ``listed`` quantities the data do not determine one by one (the Jacobian's statement: not at
    all, or only in combination), else for the planner's default targets (the one begun before the sampling for
    ``planned_for``, in ``batch``, is waited for here when it was begun for these), and whether its figures are
    drawn already (they are for that one)."""
    targets = [n for n in listed if n in rep.summary.index and rep.summary.loc[n, "identified"] is False]
    if targets == planned_for:
        return drawing.wait(batch)[PLAN_JOB], True
    drawing.cancel(batch)
    say("planning the next measurement for the quantities the data do not identify")
    return plan(campaign, targets, sigma_prior=rep.log_posterior.sigma_prior, data=rep.log_posterior.data), False


#: the page's title where the campaign names no machine description (the thesis' own campaign format)


def _page(c: ReportContent, tmp: Path) -> Page:
    campaign, model, rep, reports, ident = c.campaign, c.model, c.posterior, c.compared, c.ident
    summary, ppc_df, diag, effect, planned, sigma_um = c.summary, c.ppc, c.diagnostics, c.thesis_effect, c.planned, c.sigma_um
    shown, desc = c.shown, description_of(campaign.machine)
    page = Page(f"Bayesian calibration report — {desc.name or desc.configuration} ({desc.configuration})")
    page.paragraph("What the intervals rest on (share of each posterior variance by source; section 'Uncertainty "
                   "budget'): " + budget_plot.dominant_sentence(rep.summary, shown.listed, post=rep.log_posterior))
    page.box("missing", "Missing from this campaign", c.missing)
    page.box("warn", "Warnings", rep.warnings + rep.not_identified + rep.prior_notes)

    machine_sections.machine_section(page, desc, rep, tmp)
    machine_sections.determined_section(page, rep)
    page.section("results", "Results")
    if ident is not None:
        page.paragraph(
            f"Posterior of the eight quantities the thesis identifies (and the deviations sampled beside them) under "
            f"the {model} model{' with the thesis assumption dx_BT = 0' if c.fix_dx_BT else ''}: mean, sd and 95 % "
            "highest-density interval, beside the deterministic ball-bar values (thesis Eqs 4.10–4.18 recomputed "
            "from this campaign) and the touch-probe values (as printed in Table 5.3 and as recomputed from Table "
            "5.2). 'in HDI' says whether that value lies inside the 95 % HDI. Angles in arc seconds, lengths in "
            "micrometres. Full table: summary.csv. The least-squares values beside them: section 'Least-squares "
            "identification'.")
    else:
        page.paragraph(f"Posterior of the deviations under the {model} model ({DATA_WORDS[rep.data]}): mean, sd "
                       "and 95 % highest-density interval; angles in arc seconds, lengths in micrometres. The "
                       "least-squares values beside them: section 'Least-squares identification'. summary.csv.")
    page.table(_results_table(summary, shown.listed), digits={"R-hat": 3})
    if rep.reading_choice_note:
        page.paragraph(rep.reading_choice_note)
    machine_sections.least_squares_section(page, rep, shown.least_squares)
    if "truth.csv" in c.machine_tables:
        machine_sections.truth_section(page, c.machine_tables["truth.csv"])
    _statement_section(page, rep)

    _budget_section(page, rep, tmp, sigma_names=shown.joint)

    page.section("corner", "Joint posterior")
    page.figure(tmp / "corner.png", corner_plot.caption(shown.reference, shown.joint)
                + (" Off scale, not drawn: " + "; ".join(c.off_scale) + "." if c.off_scale else ""), "corner plot")
    page.section("forest", "Intervals against the deterministic methods")
    page.figure(tmp / "forest.png", forest.caption(shown.reference, shown.listed), "forest plot")

    if c.instruments is not None:
        _instruments_section(page, c, tmp)
    if c.pairs is not None:
        _pairs_section(page, c.pairs)
    _compensation_section(page, c)

    page.section("ppc", "Posterior predictive check")
    if ppc_df is not None:
        page.figure(tmp / "ppc.png", ppc.CAPTION, "posterior predictive check")
        n_out = int((~ppc_df["inside_95"]).sum())
        q = len(rep.log_posterior.names)
        example = " (wide or shifted intervals, e.g. beta_XB against dx_BT)" if ident is not None else ""
        page.paragraph(f"{n_out} of {len(ppc_df)} observed means fall outside their 95 % predictive interval. "
                       f"σ_model (what the model leaves out), posterior median {sigma_um:.2f} µm. Table: ppc.csv."
                       + (f" With {len(ppc_df)} observed means and {q} sampled parameters the model can match every "
                          "mean, so this check has little power here: tension between measurements shows in the "
                          f"parameters{example} rather than in the residuals." if q >= len(ppc_df) else ""))
        page.table(ppc_df[["observed_mean_um", "repeat_sd_um", "n_repeats", "predictive_mean_um",
                           "predictive_sd_um", "z", "inside_95"]], digits={"z": 2})
    if c.loo is not None:  # leave-one-out consistency, the second check
        page.paragraph(f"Leave-one-out consistency of the posterior ({DATA_WORDS[rep.data]}): does each observed "
                       "mean agree with what all the other measurements predict for it? " + c.loo.power_sentence()
                       + " Table: loo.csv.")
        page.box("warn", "Leave-one-out: measurements the others do not predict", c.loo.outlier_sentences())
        page.figure(tmp / "loo.png", loo_plot.caption(c.loo), "leave-one-out elpd and Pareto k per observation")
        page.table(c.loo.table[["variable", "elpd_loo", "elpd_drop", "pareto_k", "note"]],
                   digits={"elpd_loo": 2, "elpd_drop": 2, "pareto_k": 2})

    if c.rtest is not None:
        rtest_sections.rtest_section(page, rep, *c.rtest, tmp=tmp)

    if ppc_df is not None:
        page.section("polar", "Ball-bar trajectories")
        page.figure(tmp / "polar.png", polar.CAPTION, "polar trajectories")

    page.section("widths", "What the data taught")
    page.figure(tmp / "widths.png", widths.CAPTION, "prior and posterior widths")
    page.paragraph("Priors, each with its reason (priors.csv):")
    page.table(priors_table(rep.log_posterior))

    if planned is not None:
        _plan_section(page, planned, rep, shown=shown, tmp=tmp)

    page.section("diagnostics", "Sampler diagnostics")
    page.paragraph(sampler_paragraph(rep))
    if rep.reference is not None:
        page.paragraph(f"Accuracy {rep.reference.sentence()}. Per quantity, the difference of the sampled "
                       "mean (in reference sd) and sd (in %):" + ("" if rep.reference.exact else
                       " the kinematic posterior against its linearisation, i.e. what the nonlinearity of the "
                       "model changes, not sampler error."))
        page.table(reference_table(rep.reference), digits={"mean difference [sd]": 3, "sd difference [%]": 1})
    page.table(diag.assign(ess_bulk=diag["ess_bulk"].round().astype(int), ess_tail=diag["ess_tail"].round().astype(int)),
               digits={"r_hat": 3, "tau_steps": 0})
    page.figure(tmp / "rank.png", mcmc_plots.RANK_CAPTION, "rank plots")
    page.figure(tmp / "trace.png", mcmc_plots.TRACE_CAPTION, "trace plots")

    thesis_section = provided(campaign.machine, "report_section")  # a plug-in's own section (the thesis')
    if ident is not None and thesis_section is not None:
        thesis_section(page, ident, effect, sigma_um)
    if reports is not None:
        _models_section(page, reports, campaign, tmp, names=shown.listed,
                        with_fit=ppc_df is not None and _saw_ballbar(rep.data, campaign))
    return page


def _plan_section(page: Page, planned: PlanResult, rep: PosteriorResult, *, shown: Shown, tmp: Path) -> None:
    """Which measurement next: the plan's targets, its best candidate, what would teach σ_model, its figures."""
    summary = rep.summary
    page.section("plan", "Which measurement next")
    unidentified = [n for n in shown.listed if summary.loc[n, "identified"] is False]
    best = planned.table.iloc[0]
    page.paragraph(
        f"Targets: {', '.join(planned.targets)}"
        + (" (the quantities this campaign does not determine one by one)"
           if unidentified and list(planned.targets) == unidentified else "")
        + f". Best candidate: {best['name']}, expected information gain {best['eig_bits']:.2f} bits"
        + (f", which identifies {best['newly_identified']}" if best["newly_identified"] else "")
        + ". Closed form for the linear model; the full ranking is in plan.csv, and mtmcal-bayes plan "
          "ranks for any targets (docs/planning.md).")
    info = planned.document()["sigma_model_information"]
    if "prior" in info:  # the ball bar's data alone (the planner's σ_model information is theirs: docs/planning.md)
        _sigma_paragraph(page, planned, rep, info)
    page.figure(tmp / "plan_ranking.png", plan_figures.RANKING_CAPTION, "ranked candidate measurements")
    _plan_tables(page, planned, tmp)


def _sigma_paragraph(page: Page, planned: PlanResult, rep: PosteriorResult, info: dict) -> None:
    """What would teach the ball bar's σ_model: the plan's closed-form contraction now and the best candidate's."""
    t = planned.table.sort_values("sigma_model_rank").iloc[0]
    page.paragraph(
        f"What would teach σ_model: today's design narrows its {info['prior']} prior by a contraction of "
        f"{info['contraction_now']:.3f} (closed form at {info['evaluated_at_um']:g} µm; the sampler's posterior: "
        f"{budget_plot.sigma_contraction(rep):.2f}), i.e. hardly at all: the parameters absorb the residuals of "
        f"{info['means']} means. Redundant runs teach it: {t['name']} alone would bring the contraction to "
        f"{t['sigma_model_contraction']:.2f}; plan.csv lists each candidate's contraction and how many runs reach "
        f"{info['target_contraction']:g} (docs/planning.md)."
        + (" The planner weighs the assumed prior of σ_model, not the one learnt elsewhere that the posterior above "
           "uses." if rep.log_posterior.sigma_prior is not None else ""))


def _plan_tables(page: Page, planned: PlanResult, tmp: Path) -> None:
    """The plan's ten best candidates, its sweep figure and its Monte-Carlo check."""
    ranked = planned.table.head(10)
    cols = ["name", "eig_bits", "verdict", "newly_identified"] + [f"{t} sd_after" for t in planned.targets[:4]]
    page.table(ranked[cols].rename(columns={"newly_identified": "identifies"}), digits=3, index=False)
    page.figure(tmp / "plan_sweep.png", plan_figures.SWEEP_CAPTION, "tool-length sweep")
    if len(planned.check):
        page.paragraph("Monte-Carlo check of the closed form (data simulated from the posterior predictive, "
                       "sigma_model learnt from them):")
        page.table(planned.check[["candidate", "target", "sd_after_closed_form", "sd_after_monte_carlo",
                                  "relative_difference"]], digits=3, index=False)


def _models_section(page: Page, reports: dict, campaign, tmp: Path, *, names: list[str], with_fit: bool) -> None:
    """The same campaign under every model of its machine: intervals and (where they saw the ball bar) their fit."""
    page.section("models", "Model comparison")
    page.figure(tmp / "compare_forest.png", compare.CAPTION_FOREST, f"intervals under {len(reports)} models")
    page.box("warn", "Where the models disagree", compare.disagreements(reports, names))
    if with_fit:
        fit = compare.model_fit_table(reports, campaign)
        page.table(fit, digits={"rms_z": 3, "max_abs_z": 3})
        worst = float(fit["max_abs_z"].max())
        if worst < 2:
            page.paragraph(f"Every model reproduces every measured mean (largest |z| {worst:.2f}), so the data "
                           "cannot tell the models apart: where their intervals differ, that difference is "
                           "model-form uncertainty the measurement does not resolve, and the choice of model "
                           "(which pivots the thesis relations assume, SPEC §3.2) decides the answer.")
        page.figure(tmp / "compare_ppc.png", compare.CAPTION_PPC, f"predictive fit under {len(reports)} models")
    page.paragraph("All numbers: compare_models.csv" + (", compare_fit.csv." if with_fit else "."))
