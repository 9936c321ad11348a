"""Simulated machines for the design's validation (tests/test_design.py, bench/design.py).

A machine's truth — deviations, every set-up's and placement's nuisance offsets, σ_model — is drawn from the
campaign's priors, each offset when first needed (a run at a new set-up or placement); its parameters are the
posterior's (:func:`~mtmcal_bayes.inference.log_posterior.parameter_space`: the thesis plug-in's, a described
machine's selection).  A planned run is measured through ``simulate`` (by default through the machine's kinematic
model — the thesis plug-in's ``htm-thesis``, a described machine's chain —, ``model="linear"`` its first order; the
instrument error and the repeat scatter) plus a model discrepancy of sd σ_model on each component, shared by its
repeats.  A designed touch-probe or R-test run likewise (:meth:`SimulatedMachine.measure_other`): through the same
model, with its own nuisance terms (stylus, sphere, datum; nest, placement, zero) drawn from their priors, the
instrument's repeatability and its own discrepancy scale (σ_model_probe, σ_model_rtest) shared by the repeats.
"""

from __future__ import annotations

import copy

import numpy as np

from mtmcal_bayes import units
from mtmcal_bayes.inference.log_posterior import parameter_space
from mtmcal_bayes.inference.priors import make_prior
from mtmcal_bayes.models import default_kinematic_model
from mtmcal_bayes.planning.design import Planner
from mtmcal_bayes.planning.design_instruments import INSTRUMENTS
from mtmcal_bayes.planning.design_now import measured_data, now_of
from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector


class SimulatedMachine:
    def __init__(self, campaign, seed: int, model: str | None = None):
        """``model`` the one the runs are measured through (None: the machine's kinematic model)."""
        self.rng = np.random.default_rng(seed)
        self.values: dict[str, float] = {}
        self.priors = campaign.priors
        self.model = model or default_kinematic_model(campaign.machine)
        self.sigma = float(make_prior("sigma_model", "sigma_model", "length", campaign.priors).frozen().rvs(
            random_state=self.rng))
        #: the touch probe's and the R-test's discrepancy scales, drawn when first measured (:meth:`measure_other`)
        self.scales: dict[str, float] = {}

    def truth(self, campaign):
        space = parameter_space(campaign, False, "ballbar")
        for p in space.parameters:
            if p.name not in self.values:
                prior = make_prior(p.name, p.base, p.kind, self.priors)
                self.values[p.name] = float(prior.frozen().rvs(random_state=self.rng))
        return truth_from_vector(space, np.array([self.values[n] for n in space.names]))

    def measure(self, campaign, index: int = 0):
        """A copy of ``campaign`` with its planned run ``index`` measured on this machine (appended to its runs)."""
        bb = campaign.ballbar
        one = copy.deepcopy(campaign)
        one.ballbar.planned = [bb.planned[index]]
        one.probe = one.rtest = None  # their readings are measured apart (measure_other): not simulated again here
        filled = synthetic_campaign(one, self.truth(campaign), model=self.model, noise=True,
                                    seed=int(self.rng.integers(2**31)))
        run = filled.ballbar.runs[-1]
        for comp in run.repeats:  # the model discrepancy: one offset per component, shared by its repeats
            run.repeats[comp] = run.repeats[comp] + self.rng.normal(0.0, self.sigma)
        out = copy.deepcopy(campaign)
        out.ballbar.runs = list(out.ballbar.runs) + [run]
        out.ballbar.planned = [p for i, p in enumerate(bb.planned) if i != index]
        out.design = campaign.design
        return out

    def measure_other(self, campaign, run, order: int = 1, table_id: str | None = None):
        """A copy of ``campaign`` with the designed touch-probe or R-test ``run`` (a :class:`DesignedRun` that
        ``design`` or ``next`` names, ``order`` its place there) measured on this machine and added as the user adds
        it: its table as ``to_fill_in.toml`` gives it, read back with the readings this machine's model (the
        machine's kinematic model unless given: its chain) gives at its truth — the deviations and the run's own
        nuisance terms —, scattered by the instrument's repeatability, plus a discrepancy of its scale's sd on each
        reading, shared by the repeats; ``table_id`` the id its table has (default the one ``to_fill_in.toml``
        gives a run of that order)."""
        from mtmcal_bayes.inference.log_posterior import parameter_space
        from mtmcal_bayes.io import campaign_to_dict, parse_campaign
        from mtmcal_bayes.io.tomlio import dumps
        from mtmcal_bayes.planning.design_instruments import SCALE_OF
        from mtmcal_bayes.planning.design_other_runs import fill_in_tables
        from mtmcal_bayes.simulation.simulate import synthetic_campaign

        kind = run.instrument
        table = fill_in_tables(campaign, [(order, run)])[kind]["runs"][0]
        table["id"] = table_id or table["id"]
        k = len(next(iter(table["angles_deg"].values())))
        table["centres_mm" if kind == "probe" else "displacement_um"] = np.zeros((run.repeats, k, 3)).tolist()
        doc = campaign_to_dict(campaign)
        doc.setdefault(kind, {}).setdefault("runs", []).append(table)
        out = parse_campaign(dumps(doc), campaign.source)
        # the instrument's runs with the new one last (its terms named as the campaign names them: an R-test run
        # shares the placement of the runs before it at its sphere); only the new run's readings are taken
        one = copy.deepcopy(out)
        one.ballbar.runs, one.ballbar.planned = [], []
        setattr(one, "rtest" if kind == "probe" else "probe", None)
        space = parameter_space(one, False, kind)
        stated = one.rtest.prior_sds() if kind == "rtest" else None
        for p in space.parameters:
            if p.name not in self.values:
                prior = make_prior(p.name, p.base, p.kind, self.priors, stated=stated)
                self.values[p.name] = float(prior.frozen().rvs(random_state=self.rng))
        truth = truth_from_vector(space, np.array([self.values[n] for n in space.names]))
        filled = getattr(synthetic_campaign(one, truth, model=self.model, noise=True,
                                            seed=int(self.rng.integers(2**31))), kind).runs[-1]
        scale = SCALE_OF[kind]
        if scale not in self.scales:
            self.scales[scale] = float(make_prior(scale, scale, "length", self.priors).frozen().rvs(
                random_state=self.rng))
        readings = filled.centres if kind == "probe" else filled.displacements
        readings = readings + self.rng.normal(0.0, self.scales[scale], readings.shape[1:])  # shared by the repeats
        new = getattr(out, kind).runs[-1]
        if kind == "probe":
            new.replace_centres(readings)
        else:
            new.displacements = readings
        return out

    def measure_all(self, campaign, design=None):
        """``campaign`` with its planned ball-bar runs measured, then ``design``'s touch-probe and R-test runs (its
        ``[design] to_fill_in`` tables: ``campaign`` is ``designed_campaign(design)``), in the design's order."""
        out = campaign
        while out.ballbar.planned:
            out = self.measure(out, 0)
        for order, run in enumerate(design.runs if design is not None else [], start=1):
            if run.instrument != "ballbar":
                out = self.measure_other(out, run, order=order)
        return out


def realised_sd(campaign, targets) -> np.ndarray:
    """The exact posterior sd of ``targets`` given the campaign's measured runs of every instrument (display units)."""
    pl = Planner(campaign, [], targets, data=measured_data(campaign, INSTRUMENTS))
    _, sd = now_of(pl).target_moments(pl.T)
    return sd * np.array([units.from_internal(1.0, u) for u in pl.target_units])


def measure_sequentially(machine: SimulatedMachine, campaign, *, max_runs: int = 30, n_sim: int = 200,
                         trail: list | None = None, instruments=None):
    """``next`` after every run on ``machine`` (choosing among ``instruments``, default every one the campaign has):
    measure the run it names until it says stop.  Where ``next`` changed the plan (a run dropped or added) the
    campaign carries its re-plan from then on, as ``next -o`` writes it.  Returns the measured campaign, the minutes
    used and the last answer; ``trail`` receives per run measured ``(label, minutes, why, added, dropped,
    instrument)``: the runs ``next`` added to and dropped from the plan at that step."""
    from mtmcal_bayes.planning.design_other_runs import planned_other
    from mtmcal_bayes.planning.design_output import designed_campaign
    from mtmcal_bayes.planning.next_run import next_step

    c, minutes = campaign, 0.0
    for _ in range(max_runs):
        step = next_step(c, n_sim=n_sim, instruments=instruments)
        if step.status == "stop":
            break
        if step.added or step.dropped:
            c = designed_campaign(step.design, c.design)
        run = step.design.runs[0]
        minutes += step.design.minutes[0]
        if trail is not None:
            trail.append((run.label, step.design.minutes[0], step.design.why[0], step.added, step.dropped,
                          run.instrument))
        if run.instrument != "ballbar":  # a probe or R-test run: its table filled in and added, under its planned id
            planned = planned_other(c)
            c = machine.measure_other(c, run, table_id=next((k for k, v in planned.items() if v == run.label), None))
            continue
        c = machine.measure(c, next(j for j, p in enumerate(c.ballbar.planned) if p.label == run.label))
    return c, minutes, step


def small_problem(campaign, rng, k: int = 6):
    """A random design problem of ``k`` catalogue candidates and targets it can meet, for comparisons with
    exhaustive search: ``(problem, minutes(counts), targets (t,))``, or None when no target is worth setting.
    Up to three quantities that all candidates together would narrow to below half; each target between the sd
    today and the best reachable."""
    from mtmcal_bayes.machine_time import TimeModel
    from mtmcal_bayes.planning.design_make import design_candidates
    from mtmcal_bayes.planning.design_problem import MAX_INSTANCES, DesignProblem
    from mtmcal_bayes.planning.design_runs import designed_runs
    from mtmcal_bayes.planning.design_timing import Timing

    allc = design_candidates(campaign)
    cands = [allc[i] for i in rng.choice(len(allc), k, replace=False)]
    dp = DesignProblem(Planner(campaign, cands))
    timing = Timing(campaign, TimeModel())
    now = dp.value_now().sd_promised[0]
    most = dp.value(np.full(k, MAX_INSTANCES)).sd_promised[0]
    useful = np.flatnonzero(most < 0.5 * now)
    if not len(useful):
        return None
    pick = rng.choice(useful, min(3, len(useful)), replace=False)
    tg = np.full(len(now), np.nan)
    tg[pick] = np.maximum(np.sqrt(now[pick] * most[pick]) * rng.uniform(0.5, 1.0, len(pick)), 1.05 * most[pick])
    return dp, (lambda counts: timing.total(designed_runs(cands, counts), (False, None, None))), tg


def new_machine_runs(kind: str, n: int):
    """A new machine of built-in type ``kind`` (its demo's set-ups and mounts, no run of any instrument), its
    planner over the catalogue's candidates and the designed runs of the first ``n`` candidates once each."""
    from mtmcal_bayes import api
    from mtmcal_bayes.planning.design_make import design_candidates, reporting_planner
    from mtmcal_bayes.planning.design_runs import designed_runs

    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    c.ballbar.runs, c.probe, c.rtest, c.truth = [], None, None, None
    cands = design_candidates(c)
    planner = reporting_planner(c, cands, {})
    counts = np.zeros(len(cands), dtype=int)
    counts[:n] = 1
    return planner, designed_runs(cands, counts)
