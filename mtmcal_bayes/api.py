"""The Python API: one function per command of ``mtmcal-bayes``, each returning an object.

Every function takes the campaign first — a :class:`~mtmcal_bayes.campaign.Campaign`,
the path of a campaign TOML file, or ``None`` for the built-in thesis campaign —
and everything else by keyword.  Nothing is printed: each result has
``to_text()`` (what the command prints) and ``to_json()`` (what ``--json``
prints), so every command's output can be had from Python.  Long work takes
``progress=``, any callable receiving a :class:`~mtmcal_bayes.progress.ProgressEvent`
(``print`` will do).  Where the command writes files, ``output=`` does the same:
its directory is checked before any work, and nothing is written half-way.

Features are imported when first called, so ``import mtmcal_bayes`` stays quick.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from .analysis import CampaignAnalysis
from .campaign import Campaign
from .io.campaign_reader import load_campaign
from .io.machine_reader import demo_campaign, rtest_demo_campaign  # noqa: F401  (the CLI's --machine TYPE [--demo])
from .io.textfiles import check_writable
from .progress import Progress

if TYPE_CHECKING:  # the result types, for the signatures only
    from .compensation import CompensationResult
    from .fleets import FleetResult
    from .histories import HistoryResult
    from .identification import ProbeFit
    from .planning import PlanResult
    from .planning.design_output import DesignResult, NextResult
    from .posterior import ClosedFormResult, PosteriorResult
    from .posterior.instrument_check import InstrumentCheck
    from .reporting import Report
    from .simulation import SensitivityTable, Simulation
    from .simulation.history import SimulatedHistory
    from .validation import SBCResult

CampaignLike = Campaign | CampaignAnalysis | str | os.PathLike | None

#: default step budget of each emcee ensemble
MAX_STEPS = 20_000
#: default bulk and tail ESS of each of the eight quantities at which sampling stops
TARGET_ESS = 1000.0


def campaign_of(campaign: CampaignLike, *, measured: bool = False) -> Campaign:
    """A :class:`Campaign` from a campaign, a :class:`~mtmcal_bayes.analysis.CampaignAnalysis` (its campaign), a path
    to a campaign TOML, or None (the built-in thesis campaign).

    ``measured``: the command needs data, so a campaign without measured runs of either instrument (only planned
    ones, or none) is an :class:`~mtmcal_bayes.errors.InputError` naming its file and ``ballbar.runs``."""
    if isinstance(campaign, CampaignAnalysis):
        campaign = campaign.campaign
    c = campaign if isinstance(campaign, Campaign) else load_campaign(campaign)
    if measured:
        c.require_measured_runs()
    return c


def kinematic_model_of(model: str | None, c: Campaign) -> str:
    """The model asked for (checked against the machine's: ``chain`` and ``linear``, and its plug-ins'), else the
    machine's kinematic model (its plug-in's: ``htm-thesis`` on the thesis machine; else ``chain``)."""
    from .models import check_model, default_kinematic_model, models_of

    return default_kinematic_model(c.machine) if model is None else check_model(model, models_of(c.machine))


def data_of(data: str | None, c: Campaign) -> str:
    """The data of a likelihood: as given, else what the machine's plug-in states (the thesis machine: the ball bar)
    where the campaign has those instruments, else every instrument the campaign has."""
    from .models import default_data

    return default_data(c) if data is None else data


def tolerances_of(tolerances, campaign: Campaign | None = None) -> dict | None:
    """``{name: Tolerance}`` from a ``[tolerances]`` TOML path, a dict of them, or None (the campaign's own); with
    ``campaign``, keyed by its machine's quantity names (a name it does not have: an ``InputError`` naming the file
    and the key, :func:`~mtmcal_bayes.io.tolerances.resolve_tolerances`)."""
    from .io.tolerances import load_tolerances, resolve_tolerances

    if tolerances is not None and not isinstance(tolerances, dict):
        tolerances = load_tolerances(tolerances)
    if campaign is None:
        return tolerances
    return resolve_tolerances(tolerances, campaign.machine)[0]


def sigma_model_of(sigma_model_um: float | None) -> float | None:
    """sigma_model in mm from µm (None: sampled); a negative or non-finite value is a ``ParameterError``."""
    import math

    from .errors import ParameterError
    from .units import to_internal

    if sigma_model_um is None:
        return None
    if not (isinstance(sigma_model_um, (int, float)) and math.isfinite(sigma_model_um) and 0 <= sigma_model_um <= 1000):
        raise ParameterError("sigma_model_um", f"{sigma_model_um} is not a sigma_model in µm (0 to 1000)")
    return to_internal(float(sigma_model_um), "um")


def sigma_model_prior_of(sigma_model_prior, campaign: Campaign, sigma_model_um: float | None = None):
    """The :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` of a σ_model prior file's path or of a SigmaModelPrior
    (None: the assumed default).  A bad file is an :class:`~mtmcal_bayes.errors.InputError` naming it and the key;
    a prior together with a fixed ``sigma_model_um``, or for a scale the campaign's ``[priors]`` already sets, is a
    ``ParameterError``."""
    from .errors import ParameterError
    from .sigma_prior import SigmaModelPrior

    if sigma_model_prior is None:
        return None
    if sigma_model_um is not None:
        raise ParameterError("sigma_model_prior", f"a prior of σ_model needs σ_model sampled, and here it is fixed "
                             f"(at {sigma_model_um} µm): give one or the other")
    if isinstance(sigma_model_prior, SigmaModelPrior):
        prior = sigma_model_prior
    else:
        from .io.sigma_prior_file import read_sigma_model_prior

        prior = read_sigma_model_prior(sigma_model_prior)
    both = [n for n in prior.scales if n in campaign.priors]
    if both:
        raise ParameterError("sigma_model_prior", f"{' and '.join(both)} already has a prior in the campaign's "
                             f"[priors] ({campaign.source}): give it in one place")
    return prior


def analysis_or_campaign(given: CampaignLike, campaign: Campaign):
    """What a feature is handed: the analysis the caller gave (its cache then serves this command too), else the
    campaign."""
    return given if isinstance(given, CampaignAnalysis) else campaign


def _writable(path, what: str) -> None:
    if path is not None:
        check_writable(path, what)


def identify(campaign: CampaignLike = None):
    """The deterministic identification, on every machine the linearised least-squares identification of what its
    campaign determines, from the machine's default data (:func:`data_of`), and where the machine's plug-in has a
    method of its own, that beside it: on the thesis machine its Eqs 4.10–4.18 (ball bar) and 5.1–5.19 (touch
    probe), each value beside the published one (:class:`~mtmcal_bayes.posterior.least_squares.Identification`; its
    ``ballbar``, ``probe``, ``table()`` are the plug-in result's).  A campaign without ball-bar runs gets the least
    squares of its touch-probe readings (and R-test readings, where it has them) whatever the machine's default
    data."""
    from .posterior.least_squares import identify as identify_campaign

    c = campaign_of(campaign, measured=True)
    return identify_campaign(c, data_of(None, c) if c.ballbar.runs else "all" if c.has_rtest_readings() else "probe")


def probe_fit(path, *, stylus_radius_mm: float | None = None) -> ProbeFit:
    """Least-squares sphere through the probed points of a DPRNT file (thesis Fig 5.13)."""
    from .identification import probe_fit as fit

    return fit(path, stylus_radius_mm=stylus_radius_mm)


def simulate(campaign: CampaignLike = None, *, truth, model: str | None = None, noise: bool = False,
             seed: int | None = None, output=None) -> Simulation:
    """Predicted eccentricities of every run for a known ``truth`` (a TRUTH.toml path or a
    :class:`~mtmcal_bayes.campaign.Truth`); with ``output``, also write a synthetic campaign there,
    scattered like a real measurement when ``noise``."""
    from .campaign import Truth
    from .io.campaign_reader import load_truth
    from .simulation import simulate_truth

    from .errors import ParameterError

    c = campaign_of(campaign)
    model = kinematic_model_of(model, c)
    if truth is None:
        raise ParameterError("truth", "required: a TRUTH.toml with [deviations] (or [truth.deviations]) to simulate "
                             "(a simulated history without one takes the campaign's own truth or posterior mean)")
    _writable(output, "synthetic campaign")
    source = "<truth>" if isinstance(truth, Truth) else str(truth)
    t = truth if isinstance(truth, Truth) else load_truth(truth, c)
    sim = simulate_truth(c, t, model=model, noise=noise, seed=seed, source=source)
    if output is not None:
        sim.save(output)
    return sim


def sensitivity(campaign: CampaignLike = None, *, model: str | None = None) -> SensitivityTable:
    """Eccentricity of every pattern of the machine per ″ / µm of every deviation it names and every mounting offset
    (thesis Tables 2.4–2.6, generalised: :func:`mtmcal_bayes.simulation.sensitivity.sensitivity_table`), under
    ``model`` (default the machine's kinematic model)."""
    from .simulation import sensitivity as table

    c = campaign_of(campaign)
    return table(c, model=kinematic_model_of(model, c))


def sample(campaign: CampaignLike = None, *, model: str = "linear", seed: int | None = None, fix_dx_BT: bool = False,
           target_ess: float = TARGET_ESS, sampler: str = "emcee", max_steps: int = MAX_STEPS, checkpoint=None,
           output=None, progress: Progress | None = None, data: str | None = None, tolerances=None,
           sigma_model_um: float | None = None, sigma_model_prior=None) -> PosteriorResult:
    """The posterior of the deviations and nuisance offsets, summarised beside the ball-bar and touch-probe values.

    emcee ensembles run until the bulk and tail ESS of the eight quantities reach ``target_ess`` and R-hat
    ≤ 1.01 (``sampler="exact"``: independent draws of the exact posterior, linear model only).  ``seed``
    makes the draws reproducible; ``checkpoint`` (HDF5) is written as the run goes and resumed if it
    exists; ``output`` receives the InferenceData as NetCDF.  ``data``: the likelihood's measurements,
    ``"ballbar"``, ``"probe"`` (touch-probe readings) or ``"both"`` (fused); default (None) the ball bar, and on a
    described machine every instrument its campaign has (:func:`data_of`).  ``tolerances``: a
    TOML file with ``[tolerances]`` or ``{name: Tolerance}`` (default the campaign's own ``[tolerances]``):
    each toleranced quantity gets its probability of nonconformance, a verdict and, when undecided, the
    planner's next measurement for it.  ``sigma_model_um`` fixes the model-discrepancy scale (µm) instead of
    sampling it.  ``sigma_model_prior``: a σ_model prior learnt elsewhere (a fleet of machines of the type), the path
    of its file or a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`: the sampled scales it names get its
    log-normal instead of the assumed half-normal, and the budget names its source (docs/inference.md).
    """
    from .inference.sampling import SamplerSettings
    from .models import check_data, check_model
    from .posterior import sample_posterior
    from .reporting.decisions import add_suggestions

    c = campaign_of(campaign, measured=True)
    check_model(model)
    data = check_data(data_of(data, c), c)
    _writable(output, "posterior")
    _writable(checkpoint, "checkpoint")
    tol = tolerances_of(tolerances, c)
    learnt = sigma_model_prior_of(sigma_model_prior, c, sigma_model_um)
    settings = SamplerSettings(seed=seed, max_steps=max_steps, target_ess=target_ess, sampler=sampler)
    result = sample_posterior(analysis_or_campaign(campaign, c), model=model, fix_dx_BT=fix_dx_BT, settings=settings,
                              checkpoint=checkpoint, progress=progress, data=data, tolerances=tol,
                              sigma_model=sigma_model_of(sigma_model_um), sigma_prior=learnt)
    add_suggestions(result, c)
    if output is not None:
        result.save(output)
    return result


def closed_form(campaign: CampaignLike = None, *, sigma_model_um: float = 0.0, fix_dx_BT: bool = False,
                model: str = "linear", sigma_model_prior=None) -> ClosedFormResult:
    """The instant Gaussian posterior of the quantities the campaign determines (the thesis machine: the eight of
    Table 4.5), from every instrument it has (the thesis machine: the ball bar): linear model, sigma_model fixed
    (µm).  It has no σ_model prior: ``sigma_model_prior`` given is a ``ParameterError`` (the sampled posterior takes one)."""
    from .posterior import closed_form as gaussian

    if sigma_model_prior is not None:
        from .errors import ParameterError

        raise ParameterError("sigma_model_prior", f"the closed form fixes σ_model (at {sigma_model_um} µm) and has "
                             "no prior of it; a learnt prior is for the sampled posterior")

    c = campaign_of(campaign, measured=True)
    return gaussian(c, sigma_model_um=sigma_model_um, fix_dx_BT=fix_dx_BT, model=model, data=data_of(None, c))


def report(campaign: CampaignLike = None, *, output="report", model: str = "linear", seed: int | None = 1,
           fix_dx_BT: bool = False, compare_models: bool = False, target_ess: float = TARGET_ESS,
           sampler: str = "emcee", max_steps: int = MAX_STEPS, posterior: PosteriorResult | None = None,
           progress: Progress | None = None, command: str = "", data: str | None = None, tolerances=None,
           sigma_model_um: float | None = None, sigma_model_prior=None) -> Report:
    """Sample the posterior and write the HTML report with its figures, tables and NetCDF into ``output``.

    One report for every machine: each section appears where the campaign and its machine have what it needs
    (docs/report.md).  ``posterior`` reuses a posterior already sampled from this campaign (:func:`sample`);
    ``compare_models`` adds the same campaign under every forward model its machine offers (the thesis machine's
    four, a described machine's ``linear`` and ``chain``).  ``data`` as for :func:`sample`; a campaign with ball-bar
    runs and touch-probe readings also gets its ball-bar-only, probe-only and fused posteriors side by side and the
    instruments' consistency check; a posterior of R-test readings its R-test sections, and a campaign with the
    R-test beside another instrument every pair's check (docs/rtest.md, "The report").  ``tolerances``,
    ``sigma_model_um`` and ``sigma_model_prior`` as for :func:`sample` (the learnt prior for every posterior of
    the report; with ``posterior``, it must be the one that posterior was sampled with).
    """
    from .errors import ParameterError
    from .models import check_data, check_model
    from .reporting.start import begin

    c = campaign_of(campaign, measured=True)
    check_model(model)
    data = check_data(data_of(data, c), c)
    learnt = sigma_model_prior_of(sigma_model_prior, c, sigma_model_um)
    if posterior is not None and learnt is not None and learnt != posterior.log_posterior.sigma_prior:
        raise ParameterError("sigma_model_prior", "is not the prior the given posterior was sampled with")
    tol, sigma = tolerances_of(tolerances, c), sigma_model_of(sigma_model_um)
    # the machine's figures begun before the report's computation is imported (reporting.start)
    with begin(c, output) as begun:
        from .inference.sampling import SamplerSettings
        from .reporting.build import build_report

        settings = SamplerSettings(seed=seed, max_steps=max_steps, target_ess=target_ess, sampler=sampler)
        return build_report(analysis_or_campaign(campaign, c), output, model=model, settings=settings,
                            fix_dx_BT=fix_dx_BT, compare_models=compare_models, posterior=posterior,
                            progress=progress, command=command, data=data, tolerances=tol, sigma_model=sigma,
                            sigma_prior=learnt, begun=begun)


def plan(campaign: CampaignLike = None, *, targets=None, model: str = "linear", candidates=None,
         sigma_model_um: float | None = None, sweep_pattern: str | None = None, output=None,
         data: str | None = None, sigma_model_prior=None, times=None) -> PlanResult:
    """Rank candidate extra measurements — ball-bar runs, touch-probe runs and, with an ``[rtest]``, R-test runs —
    by how much they would reduce the uncertainty of ``targets`` (default the eight identified quantities), given the
    campaign's ``data`` (a value of :data:`~mtmcal_bayes.models.DATA`; default every instrument it has).  ``times``:
    a TOML file (or dict) overriding the machine-time model, as for :func:`design` (an R-test candidate's minutes).

    ``candidates``: a TOML file of your own ``[[candidate]]`` tables, or a list of
    :class:`~mtmcal_bayes.planning.Candidate`, ranked with the catalogue.  ``sigma_model_prior``: a σ_model prior
    learnt elsewhere (its file's path or a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`): the closed form's
    σ_model is then the rms of the learnt prior (unless ``sigma_model_um`` fixes it), and the σ_model information and
    the Monte-Carlo check use it (docs/planning.md).
    """
    import math

    from .errors import ParameterError
    from .models import check_data
    from .planning import plan as rank

    c = campaign_of(campaign, measured=True)
    _check_planning_model(model, c)
    data = check_data(data_of(data, c), c)
    _writable(output, "plan")
    if sigma_model_um is not None and not (math.isfinite(sigma_model_um) and sigma_model_um >= 0):
        raise ParameterError("sigma_model_um", f"{sigma_model_um} is not a non-negative number")
    learnt = sigma_model_prior_of(sigma_model_prior, c)  # the closed form's fixed σ_model does not exclude a prior
    from .machine_time import TimeModel

    clock = TimeModel(**_time_items(c, times))
    extra = _user_candidates(candidates, c)
    result = rank(c, targets, extra=extra, sigma_model_um=sigma_model_um, sweep_pattern=sweep_pattern, model=model,
                  data=data, sigma_prior=learnt, times=clock)
    if output is not None:
        result.write(output)
    return result


def ncgen(pattern: str | None = None, *, campaign: CampaignLike = None, R_B_mm: float | None = None, start=None,
          step_deg: float | None = None, feed: float | None = None, n: int | None = None, setup: str | None = None,
          mount: str | None = None, run: int | None = None, probe: str | None = None, rtest: str | None = None,
          arc_deg=None, hold_deg: dict | None = None, dwell_ms: int | None = None, output=None) -> str:
    """The measuring NC program of ``pattern`` at ``setup`` and ``mount``, of the campaign's ``run``-th ball-bar run
    (1-based, measured then planned), of its probe run ``probe`` or of its R-test run ``rtest`` (id or number; a
    dwell of ``dwell_ms`` at each position, default 2000 ms), as text; ``output`` receives it.

    One path on every machine (:func:`~mtmcal_bayes.io.chain_programs.campaign_program`): the pattern over
    ``arc_deg`` = (start, end) degrees by ``step_deg`` with the other rotary axes at ``hold_deg`` {letter: degrees},
    its commands through the machine's chain, written in the machine's program format.  ``R_B_mm``, ``start`` and
    ``n`` are options of a format that takes them (the thesis machine's, Fig 4.30(a): the tool length, the first
    block's NC position (x0, y0, z0) mm, the number of blocks; default step 2.5°; without a campaign, with
    ``R_B_mm`` and ``start``, a program from these alone); elsewhere they are refused by name.
    """
    from .io.chain_programs import campaign_program, program_format
    from .io.textfiles import write_text_atomic

    options = {"R_B_mm": R_B_mm, "start": start, "n": n}
    c = campaign_of(campaign)
    if campaign is None:  # the built-in campaign, or one its program format makes of its own options
        c = program_format(c.machine).alone(c, {k: v for k, v in options.items() if v is not None})
    _writable(output, "program")
    text = campaign_program(c, pattern=pattern, run=run, probe=probe, rtest=rtest, setup=setup, mount=mount,
                            arc_deg=arc_deg, step_deg=step_deg, hold_deg=hold_deg, feed=feed, dwell_ms=dwell_ms,
                            options=options)
    if output is not None:
        write_text_atomic(output, text)
    return text


def instruments(campaign: CampaignLike = None, *, explain: bool = True) -> InstrumentCheck:
    """Do the instruments of a campaign agree?  The consistency check of every pair of them (the ball bar, the
    touch probe, the R-test: each against the other's posterior) on the exact linear posteriors, each instrument's
    discrepancy scale in the fused posterior, the deviations they disagree on (which ``compensate`` refuses), and
    with ``explain`` the candidate explanations of each disagreeing pair's conflict weighed by the marginal likelihood
    (readings of the B patterns, the stylus length, the R-test's frame, sign, zero, nests and placements, a
    difference between the sessions)."""
    from .posterior.instrument_check import check_instruments

    c = campaign_of(campaign, measured=True)
    return check_instruments(analysis_or_campaign(campaign, c), explain=explain)


def axis_lines(campaign: CampaignLike = None, *, data: str | None = None, seed: int | None = 1, csv=None):
    """The identified axis lines of any machine (its description's, the thesis machine's included): direction and
    point of each rotary axis and of the spindle at the home pose, and the pivot distances, each from the draws of
    the exact posterior of ``data`` (default: every instrument a described machine's campaign has; the ball bar on
    the thesis machine), with a flag where the data do not determine it (:mod:`~mtmcal_bayes.posterior.axis_lines`);
    ``csv`` receives the table."""
    from .io.textfiles import write_text_atomic
    from .models import check_data
    from .posterior.axis_lines import axis_lines as lines

    c = campaign_of(campaign, measured=True)
    data = check_data(data_of(data, c), c)
    _writable(csv, "axis lines")
    result = lines(sample(c, sampler="exact", seed=seed, data=data))
    if csv is not None:
        write_text_atomic(csv, result.to_csv())
    return result


def isg_csv(campaign: CampaignLike = None, *, data: str | None = None, seed: int | None = 1, output=None) -> str:
    """The identified position errors in the ISG CSV format (ISG kernel / Beckhoff TF5280 volumetric compensation,
    :mod:`~mtmcal_bayes.io.isg_csv`): the posterior means, mm and rad, of the deviations the data determine one by
    one; each one left out is named in a ``//`` comment with why.  ``output`` receives the text."""
    from .io.isg_csv import isg_csv as text_of
    from .io.textfiles import write_text_atomic
    from .models import check_data
    from .posterior.axis_lines import isg_position_errors

    c = campaign_of(campaign, measured=True)
    data = check_data(data_of(data, c), c)
    _writable(output, "ISG CSV file")
    text = text_of(*isg_position_errors(sample(c, sampler="exact", seed=seed, data=data)))
    if output is not None:
        write_text_atomic(output, text)
    return text


def compensate(program, *, campaign: CampaignLike = None, output=None, method: str = "exact",
               model: str | None = None, values: str = "posterior", posterior=None, point: str = "tcp",
               setup: str | None = None, mount: str | None = None, integer_unit: str | None = None,
               accept_disagreement: bool = False) -> CompensationResult:
    """Rewrite X/Y/Z of an NC program (a path) so the tool point reaches the programmed points, with the
    residual error from the posterior and the tool tilts X/Y/Z cannot correct; ``output`` receives the program.

    ``method``: ``"exact"`` inversion or ``"thesis"`` (Eqs 3.4–3.13 as printed); ``values``:
    ``"posterior"`` mean or ``"ballbar"``; ``posterior``: draws, as a NetCDF file, a :func:`sample` result or an InferenceData (default:
    the machine's, below); ``integer_unit``: how X/Y/Z/B/C words without a decimal point (``X100``) are read, ``"um"``
    (increments of 1 µm / 0.001°) or ``"mm"`` (mm / °); by default they are refused (zeros are accepted).

    A campaign with two or three instruments (the ball bar, the touch probe, the R-test) is checked first
    (:func:`instruments`, every pair): where they disagree on a deviation the
    compensation uses, it is refused (a ``ParameterError`` naming ``accept_disagreement``) unless
    ``accept_disagreement``, which compensates and warns; so is a campaign on which the check cannot run (a gap of
    its probe readings, :meth:`~mtmcal_bayes.campaign.Campaign.probe_gap`).

    One path on every machine (docs/compensation.md, :mod:`mtmcal_bayes.compensation.compensate`): Newton through
    the machine's kinematics (its chain, or a plug-in's model: the thesis machine's ``htm-thesis`` by default), the
    rotary axes by their letters, ``setup`` the ball-bar set-up whose tool length is the tool's; the values the
    posterior mean (default posterior: the exact posterior of the machine's default data, or a plug-in's own), a
    deviation the data do not determine left at zero where its posterior is its prior, else compensated with its
    mean, each named.  ``method="thesis"``, ``values="ballbar"`` and
    ``mount`` are what a plug-in offers (the thesis machine's).
    """
    from .compensation.compensate import check_options, compensate as rewrite, kinematics_of, read
    from .errors import ParameterError
    from .machines import selected
    from .machines.plugins import provided
    from .parameters import data_instruments

    c = campaign_of(campaign, measured=True)
    check_options(c, method=method, values=values, point=point)
    kinematics_of(c, model=model, point=point, setup=setup, mount=mount)  # its options, checked before any work
    parsed = read(c, program, integer_unit=integer_unit)
    _writable(output, "compensated program")
    refusal = None
    two = len(data_instruments("all", c)) >= 2  # any two instruments: every pair is checked (docs/rtest.md)
    if two and c.has_probe_readings() and (gap := c.probe_gap()) is not None:
        refusal = (f"whether the instruments of {c.source} agree on the deviations it uses cannot be checked: "
                   f"{gap.reason()}")
    elif two:
        refusal = instruments(c, explain=False).refusal([d.name for d in selected(c.machine.description)])
    if refusal and not accept_disagreement:
        raise ParameterError("accept_disagreement", f"not given, and {refusal}")
    label = None
    if posterior is None:
        own = provided(c.machine, "compensation_posterior")
        if own is not None:
            posterior = own(c)
        else:
            posterior = sample(c, sampler="exact", seed=1)
            label = f"exact posterior of the linear model ({posterior.log_posterior.data} data)"
    result = rewrite(c, parsed, posterior, method=method, model=model, values=values, point=point, setup=setup,
                     mount=mount, label=label)
    if refusal:
        result.warnings.append(f"compensated although {refusal} (accepted)")
    if output is not None:
        result.save(output)
    return result


def sbc(campaign: CampaignLike = None, *, n: int = 200, model: str = "linear", sampler: str = "emcee",
        n_ranked: int = 99, max_steps: int = MAX_STEPS, workers: int | None = None, seed: int = 1, output=None,
        progress: Progress | None = None, data: str | None = None, scheduler: str | None = None) -> SBCResult:
    """Simulation-based calibration (Talts et al. 2018) of the posterior on the design of the campaign:
    ``n`` truths from the prior, each ranked among ``n_ranked`` posterior draws, the replicates as Dask tasks
    on a local cluster of ``workers`` processes (default the CPU count) or, with ``scheduler`` (``tcp://host:8786``
    or a scheduler file), on a running cluster; the same result either way.  ``output`` receives the JSON, CSV
    files and figures; ``data`` the measurements simulated and fitted (``"ballbar"``, ``"probe"``, ``"both"``).
    On a described machine the ranked quantities are the deviations its campaign determines one by one and its
    identifiable combinations (undetermined deviations are not ranked: their posterior is their prior), then the
    discrepancy scales (``docs/validation.md``).
    The local workers are forked where the platform forks (Linux, macOS); on Windows, where they are spawned
    and import the calling script, call it under ``if __name__ == "__main__":``."""
    from .errors import ParameterError
    from .models import check_data
    from .validation import SBCSettings, run_sbc

    if workers is not None and scheduler is not None:
        raise ParameterError("workers", "sets the size of a local cluster; a scheduler's cluster has its own workers")
    c = campaign_of(campaign, measured=True)
    data = check_data(data_of(data, c), c)
    _writable(output, "SBC")
    settings = SBCSettings(n=n, model=model, sampler=sampler, n_ranked=n_ranked, max_steps=max_steps,
                           workers=(os.cpu_count() or 1) if workers is None else workers, seed=seed, data=data,
                           scheduler=scheduler)
    result = run_sbc(c, settings, progress)
    if output is not None:
        result.write(output)
    return result


def history_campaigns(paths) -> list[Campaign]:
    """The campaigns of a history: a directory (its ``*.toml``, sorted) or a list of files (or Campaigns)."""
    from pathlib import Path

    from .errors import ParameterError

    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    files = []
    for item in items:
        if isinstance(item, Campaign):
            files.append(item)
        elif Path(item).is_dir():
            found = sorted(Path(item).glob("*.toml"))
            if not found:
                raise ParameterError("campaigns", f"{item}: no campaign files (*.toml) in this directory")
            files += found
        else:
            files.append(item)
    return [campaign_of(f, measured=True) for f in files]


def history(campaigns, *, model: str = "linear", seed: int = 1, tolerances=None, output=None,
            trend: str = "auto", data: str | None = None) -> HistoryResult:
    """One machine's history: every quantity at every date jointly (deviations as random walks in time, with a
    drift rate where the data want one, referred to 20 °C when the campaigns' temperatures are given), the
    changes that are real, and the date by which each toleranced quantity should be recalibrated.

    ``campaigns``: a directory of campaign files, a list of files, or Campaigns (each with its ``date``, one
    ``[machine] serial``); ``tolerances`` as for :func:`sample` (default: the latest campaign's); ``output``
    receives history.json, CSV files, trend.png and index.html.  ``model``: ``linear``, or a kinematic model
    linearised per campaign at the history's estimate (the linearisation checked and stated; ``chain`` on a described
    machine, whose history tracks its own deviations that the campaigns determine, docs/history.md); ``trend``:
    ``"auto"`` (chosen per deviation by Bayes factor) or ``"off"`` (random walks only); ``data``: what every
    campaign's likelihood uses (default: every instrument it has, as :func:`sample`; each instrument its own
    discrepancy scale, shared by the campaigns).
    """
    from .histories import fit_history
    from .models import check_data

    _writable(output, "history")
    found = history_campaigns(campaigns)
    if found:
        kinematic_model_of(model, found[-1])  # checked: a described machine has linear and chain
    tol = tolerances_of(tolerances, found[-1] if found else None)  # the latest campaign's machine names them
    for c in found if data is not None else ():
        check_data(data, c)
    result = fit_history(found, model=model, seed=seed, tolerances=tol, trend=trend, data=data)
    if output is not None:
        result.write(output)
    return result


def simulate_history(campaign: CampaignLike = None, *, truth=None, n: int = 5, every_days: float = 91.0, start=None,
                     steps=(), ramps=(), serial: str = "SIM-001", model: str = "linear", seed: int = 0,
                     output=None, temperatures=None, thermal=(), machine_type: str | None = None) -> SimulatedHistory:
    """A synthetic history of one machine: ``n`` campaigns ``every_days`` apart from ``start`` (a date, default
    2026-01-05), each simulated from ``truth`` plus the drifts at its date, with fresh set-up offsets and noise.

    ``truth``: a TRUTH.toml (``[deviations]`` or ``[truth.deviations]``, docs/campaign-format.md) or a Truth;
    default the campaign's own ``[truth]``, else its posterior mean (the result's ``truth_source`` says which).
    ``steps`` / ``ramps``: ``"NAME=SIZE@K"`` strings (or :class:`~mtmcal_bayes.simulation.history.Drift`):
    ``beta_CZ=40@4`` adds 40″ from the 4th campaign on; ``alpha_XB=8@1`` adds 8″ per year from the 1st on
    (display units: ″ or µm).  ``output`` (a directory, created with its parents) receives
    ``<serial>_<date>.toml`` files.  ``temperatures``: each campaign's workshop temperature (°C; one value for
    all, or one per campaign); ``thermal``: ``"NAME=K"`` strings, a thermal sensitivity in ″ or µm per °C (needs
    ``temperatures``).  ``machine_type``: the ``[machine] type`` written into every campaign.
    """
    from pathlib import Path

    from .errors import ParameterError
    from .simulation.history import (SimulatedHistory, deviation_names, history_dates, parse_drift, parse_thermal,
                                     synthetic_history)

    if not (isinstance(n, int) and 1 <= n <= 200):
        raise ParameterError("n", f"{n}: a series of 1 to 200 campaigns")
    dates = history_dates(n, every_days, start)
    c = campaign_of(campaign)
    names = deviation_names(c)
    drifts = [parse_drift(x, "step", dates, names) for x in steps] + [parse_drift(x, "ramp", dates, names) for x in ramps]
    model = kinematic_model_of(model, c)
    _writable_folder(output, "history")
    t, source = _history_truth(c, truth)
    series = synthetic_history(c, t, dates, drifts=drifts, serial=serial, model=model, seed=seed,
                               temperatures=_temperatures(temperatures, n), thermal=[parse_thermal(x, names) for x in thermal])
    if machine_type is not None:
        for x in series:
            x.machine.type = machine_type
    if output is not None:
        _save_series(series, Path(output), serial)
    return SimulatedHistory(series, truth_source=source)


def _history_truth(c: Campaign, truth):
    """The truth of a simulated history and where it came from: ``truth`` (a file or a Truth), else the campaign's
    own ``[truth]``, else the posterior mean of its deviations (the linear model's exact σ-marginal posterior)."""
    import numpy as np

    from .campaign import Truth
    from .io.campaign_reader import load_truth

    if isinstance(truth, Truth):
        return truth, "the truth given"
    if truth is not None:
        return load_truth(truth, c), f"the truth in {truth}"
    if c.truth is not None:
        return c.truth, f"the [truth] of {c.source}"
    analysis = CampaignAnalysis(c)  # linear, ball bar: its σ-marginal posterior is exact, its mean without draws
    post = analysis.log_posterior
    names = [q.name for q in post.space.parameters]
    devs = [q.name for q in post.space.parameters if q.group == "deviation"]  # the machine's own names
    T = np.eye(post.p)[[names.index(n) for n in devs]]
    mean, _ = analysis.marginal.target_moments(post.likelihood.y[None], T)
    return Truth(dict(zip(devs, mean[0].tolist()))), (f"the posterior mean of {c.source} (no --truth, and no [truth] "
                                                      "in the campaign)")


def _temperatures(temperatures, n: int) -> list[float] | None:
    """One workshop temperature per campaign (°C) from one value for all or one per campaign."""
    from .errors import ParameterError

    if temperatures is None:
        return None
    temps = [float(x) for x in (temperatures if isinstance(temperatures, (list, tuple)) else [temperatures])]
    temps = temps * n if len(temps) == 1 else temps
    if len(temps) != n or not all(-50.0 <= x <= 100.0 for x in temps):
        raise ParameterError("temperatures", f"{temperatures}: one workshop temperature (−50 to 100 °C) for all "
                             f"campaigns, or one for each of the {n}")
    return temps


def _save_series(series, out, serial: str) -> None:
    """Each campaign of ``series`` into ``out`` (created with its parents) as ``<serial>_<date>.toml``."""
    from .io.campaign_writer import save_campaign

    from pathlib import Path

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for x in series:
        path = out / f"{serial}_{x.date.date().isoformat()}.toml"
        save_campaign(x, path, header=f"Synthetic campaign {x.date.date()} of machine {serial}, simulated by "
                      "mtmcal-bayes (a history with drift).")
        x.source = str(path)


def _writable_folder(path, what: str) -> None:
    """A folder to be created (with its parents): it must not be a file."""
    from pathlib import Path

    from .errors import MtmcalError

    if path is not None and Path(path).exists() and not Path(path).is_dir():
        raise MtmcalError(f"{path}: cannot write the {what}: it is a file, not a folder")


def fleet(directory, *, scheduler: str | None = None, workers: int | None = None, seed: int = 1, model: str = "linear",
          output=None, cache=None, progress: Progress | None = None, sampler: str = "emcee",
          target_ess: float = TARGET_ESS, max_steps: int = MAX_STEPS, tolerances=None) -> FleetResult:
    """Every machine's calibrations below ``directory`` (each ``*.toml``, recursively), in parallel on Dask: each
    campaign's posterior and each machine's history (two or more dated campaigns of one ``[machine] serial``),
    in one overview of machines × quantities with conformity, drift flags and recalibrate-by dates.

    ``scheduler``: the address (``tcp://host:8786``) or scheduler file of a running Dask cluster; else a local
    cluster of ``workers`` processes (default one per core).  A campaign that fails is reported in ``errors``
    and the rest completes (``exit_status`` 3).  Each finished unit is cached (``cache``: a folder; default
    ``<output>/.cache``, else the user's cache folder; ``False``: none), so a re-run computes only what is
    missing.  Each campaign is seeded from its content and ``seed``: the results do not depend on the
    cluster.  ``output`` receives index.html, fleet.json, fleet_summary.csv and a page per machine;
    ``model``, ``sampler``, ``target_ess``, ``max_steps`` as for :func:`sample`.  ``tolerances``: a plant-wide
    ``[tolerances]`` file or ``{name: Tolerance}`` used for every machine instead of each campaign's own (each
    campaign's conformity, each history's forecast and change thresholds, the overview's verdicts).
    """
    from .fleets import FleetSettings, run_fleet
    from .models import check_model

    check_model(model)
    _writable(output, "fleet overview")
    settings = FleetSettings(model=model, seed=seed, sampler=sampler, target_ess=target_ess, max_steps=max_steps,
                             tolerances=tolerances_of(tolerances))
    result = run_fleet(directory, settings, scheduler=scheduler, workers=workers, output=output, cache=cache,
                       progress=progress)
    if output is not None:
        result.write(output)
    return result


def _time_items(c: Campaign, times) -> dict:
    """The time model's items: the campaign's ``[design.times]``, then ``times`` (a ``--times`` file, a dict or a
    TimeModel) over them, each checked."""
    from dataclasses import asdict

    from .io.times_reader import checked_times, read_times_table
    from .machine_time import TimeModel

    items = checked_times(dict(c.design.times), c.source, "design.times") if c.design and c.design.times else {}
    if isinstance(times, TimeModel):
        return {**items, **{k: v for k, v in asdict(times).items() if v is not None}}
    if isinstance(times, dict):
        return {**items, **checked_times(times, "times", "")}
    if times is not None:
        return {**items, **read_times_table(times)}
    return items


def _program(campaign, planned) -> str:
    """The measuring program of a planned run of ``campaign`` (a designed one), in its machine's program format,
    with the campaign's feed."""
    from .io.chain_programs import ballbar_program

    return ballbar_program(campaign, planned, feed=campaign.ballbar.feed_mm_per_min)


def _other_program(campaign, candidate) -> str:
    """The program of a designed touch-probe or R-test run of ``campaign`` (``candidate``: its catalogue candidate),
    as ``ncgen --probe`` / ``ncgen --rtest`` writes it."""
    from .io.chain_programs import probe_program
    from .io.rtest_program import rtest_program

    one = candidate.alone(campaign)
    if candidate.instrument == "probe":
        return probe_program(one, one.probe.runs[0])
    return rtest_program(one, one.rtest.runs[0])


def _check_planning_model(model: str, c: Campaign) -> None:
    """The model checked for ``c``'s machine."""
    from .models import check_model, models_of

    check_model(model, models_of(c.machine))


def _user_candidates(candidates, c: Campaign) -> list:
    """The user's candidates: a TOML file read in the machine's format (its planning kit), or a list."""
    from .planning.machine_kit import kit_of

    return kit_of(c).read_candidates(candidates, c) if isinstance(candidates, (str, os.PathLike)) else \
        list(candidates or [])


def design(campaign: CampaignLike = None, *, targets: dict | None = None, tolerances=None,
           budget_min: float | None = None, contraction: float | None = 0.5, candidates=None, times=None,
           seed: int = 0, model: str = "linear", output=None, sigma_model_prior=None,
           instruments=None) -> DesignResult:
    """Design the whole campaign: the runs (ball bar, touch probe, R-test: every instrument the campaign has a set-up
    for, or those of ``instruments``), in measuring order, that reach ``targets`` in the fewest machine minutes, or
    that improve most within ``budget_min`` (docs/design.md).

    The campaign may hold measured runs (the design extends it) or none (a new machine: its set-ups and mounts).
    ``targets`` {quantity: sd in ″ or µm}; ``tolerances`` a ``[tolerances]`` file or dict (targets at which the
    ISO 14253-1 decision is expected, where ``targets`` gives none); ``contraction`` σ_model's (None: none);
    ``candidates`` a TOML file of your own ``[[candidate]]`` tables, added to the catalogue; ``times`` a TOML
    file (or dict) overriding the machine-time model.  ``output`` receives design.json, campaign.toml (the
    designed runs as planned runs, ready to fill in), programs/NN_<pattern>.nc and design.html.
    ``sigma_model_prior``: a σ_model prior learnt elsewhere (file path or
    :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`): σ_model is integrated out over it, and the contraction is
    measured against the wider of the assumed and the learnt prior, so a narrow learnt prior may meet it before any run
    (docs/design.md).  ``instruments``: the ones to choose among (``"ballbar,probe,rtest"`` or a list; default every
    one the campaign has a set-up for).
    """
    from .machine_time import TimeModel
    from .planning.design_make import make_design
    from .planning.design_output import DesignResult, write_design
    from .planning.next_run import planned_candidates

    c = campaign_of(campaign)
    _check_planning_model(model, c)
    _writable(output, "design")
    learnt = sigma_model_prior_of(sigma_model_prior, c)
    items = _time_items(c, times)
    extra = planned_candidates(c) + _user_candidates(candidates, c)
    d = make_design(c, targets=targets, tolerances=tolerances_of(tolerances, c), contraction=contraction,
                    budget_min=budget_min, candidates=extra, time_model=TimeModel(**items), model=model, seed=seed,
                    candidates_source=str(candidates) if isinstance(candidates, (str, os.PathLike)) else "candidates",
                    sigma_prior=learnt, instruments=instruments)
    if output is None:
        return DesignResult(d)
    files, path = write_design(d, output, program=_program, times=items, other_program=_other_program)
    return DesignResult(d, str(output), files, path)


def next_run(campaign: CampaignLike = None, *, targets: dict | None = None, contraction: float | None = None,
             budget_min: float | None = None, candidates=None, times=None, seed: int = 0, model: str = "linear",
             output=None, sigma_model_prior=None, instruments=None) -> NextResult:
    """On a partly measured designed campaign: the next run to measure (the rest re-planned from what is measured)
    or "stop: every target reached" (docs/design.md).  Targets, contraction, budget and times default to the
    campaign's ``[design]``; ``output`` receives the re-planned campaign and programs; ``sigma_model_prior`` as for
    :func:`design` (the campaign does not record it: give the one it was designed under)."""
    from .machine_time import TimeModel
    from .planning.design_output import NextResult, write_next
    from .planning.next_run import next_step

    c = campaign_of(campaign)
    _check_planning_model(model, c)
    _writable(output, "next")
    learnt = sigma_model_prior_of(sigma_model_prior, c)
    items = _time_items(c, times)
    step = next_step(c, targets=targets, contraction=contraction, budget_min=budget_min,
                     time_model=TimeModel(**items), candidates=_user_candidates(candidates, c), model=model, seed=seed,
                     sigma_prior=learnt, instruments=instruments)
    if output is None:
        return NextResult(step)
    files, program = write_next(step, output, program=_program, times=items, other_program=_other_program)
    return NextResult(step, str(output), files, program)


__all__ = ["campaign_of", "identify", "probe_fit", "simulate", "sensitivity", "sample", "closed_form", "report",
           "plan", "ncgen", "instruments", "compensate", "sbc", "history", "simulate_history", "fleet", "design",
           "next_run"]
