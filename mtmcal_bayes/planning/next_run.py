"""``next``: on a partly measured designed campaign, the next run to measure or "stop: every target reached".

The posterior so far is the exact σ-marginal posterior of every measured run of the design's instruments — the ball
bar's, the touch probe's, the R-test's, each with its own discrepancy scale learnt from what is measured
(:mod:`.design_now`).  When every target sd is met by it and σ_model's contraction reached (or promised in
expectation by the designed plan, now measured in full), the answer is *stop*, with the probability that the
targets are met: the posterior probability of the scales' values at which the σ-conditional sds all meet them (the
sds themselves are known, the scales are not).  Otherwise the remaining planned runs are kept while their exact
check from today's posterior still leaves each target likelier met than missed (runs the data made unnecessary
dropped), and the rest is designed again from the machine's current state (the ball bar mounted at the last
measured run's set-up and placement, or the probe or the R-test after a run of theirs: :func:`machine_state`; the
remaining planned runs among the candidates, measured first where that costs nothing) only where the plan falls
short: :mod:`.next_plan`.  A designed probe or R-test run is planned while its table (``[design] to_fill_in``,
:mod:`.design_other_runs`) is not among the campaign's runs: the plan kept holds it as the ball bar's planned runs
(:func:`planned_other_candidates`); a re-plan chooses among the catalogues' probe and R-test runs again, which hold
it.  The first run of the plan is the next
one; the probability is the share of simulated machines in which the plan meets every target
(:mod:`.design_check`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..errors import ParameterError
from ..machine_time import TimeModel
from .candidates import Candidate
from .chain_candidates import arc_spec
from .design import Planner
from .design_instruments import chosen_instruments, other_candidates, taught
from .design_make import (
    CONTRACTION,
    Design,
    design_candidates,
    design_of_plan,
    make_design,
    parse_targets,
    reporting_planner,
)
from .design_now import now_of, taught_prior
from .design_other_runs import planned_other
from .determined import Determination
from .next_plan import contraction_delivered, plan_holds, planned_first, without_unneeded
from .scale_priors import learnt_summary

#: re-plans with the targets tightened when the closed form finds nothing left to measure but the exact posterior
#: has not met them yet
RETRIES = 4


@dataclass
class NextStep:
    """The answer of ``next``: ``status`` "measure" or "stop"; the re-plan (``design``) when measuring."""

    status: str
    targets: list[str]
    target_units: list[str]
    target_sd: np.ndarray  # (t,) NaN where none
    sd_now: np.ndarray  # (t,) exact posterior sd today, display units
    contraction_now: float
    contraction_target: float | None
    probability_targets_met: float
    design: Design | None = None
    measured: int = 0
    planned_left: list[str] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)
    added: list[str] = field(default_factory=list)
    #: the σ_model prior learnt elsewhere (:func:`.scale_priors.learnt_summary`; empty: assumed)
    learnt: dict = field(default_factory=dict)
    #: (t,) whether the measured runs determine each quantity (:mod:`.determined`; a target is reached only then)
    determined_now: np.ndarray | None = None

    @property
    def minutes_left(self) -> float:
        return 0.0 if self.design is None else self.design.total_minutes


def planned_candidates(campaign) -> list[Candidate]:
    """The campaign's planned runs as candidates of the re-plan."""
    bb = campaign.ballbar
    out = []
    for p in bb.planned:
        s, m = bb.setups[p.setup], bb.mounts[p.mount]
        out.append(Candidate(f"{p.label} (planned)", "planned", p.pattern, s, m, bb.length, p.repeats,
                             extension=s.R_B - campaign.primary_setup().R_B, arc_deg=arc_spec(p.arc_deg),
                             hold_deg=tuple((p.hold_deg or {}).items())))
    return out


def planned_other_candidates(campaign, instruments) -> list:
    """The designed probe and R-test runs the campaign plans (:func:`.design_other_runs.planned_other`) as candidates
    of the kept plan, each the catalogue's candidate of its name as that run (``<name> #k``: its k-th run, its terms'
    owners its own, :meth:`.candidates.WithoutBar.again`) named as the run, so the plan names it as the design did.
    A planned run whose candidate the catalogue of ``instruments`` no longer holds is left to the re-plan."""
    names = planned_other(campaign).values()
    if not names:
        return []
    catalogue = {c.name: c for c in other_candidates(campaign, [i for i in instruments if i != "ballbar"])}
    out = []
    for label in names:
        base, _, k = label.rpartition(" #")
        name, instance = (base, int(k)) if base and k.isdigit() else (label, 1)
        if name in catalogue:
            out.append(dataclasses.replace(catalogue[name].again(instance), name=label))
    return out


def _conditional_met(planner: Planner, targets: np.ndarray) -> float:
    """Posterior probability of the discrepancy scales' values at which every σ-conditional target sd meets its
    target (the grid cells of every measured instrument's scale, :class:`.design_now.Now`)."""
    w, var = now_of(planner).cell_target_var(planner.T)
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    sd = np.sqrt(np.maximum(var, 0.0)) * scale
    ok = np.all(sd <= np.where(np.isfinite(targets), targets, np.inf), axis=1)
    return float(w @ ok)


def measured_runs(campaign, instruments) -> int:
    """How many runs of ``instruments`` the campaign has measured (the ball bar's, the probe's, the R-test's)."""
    count = {"ballbar": len(campaign.ballbar.runs),
             "probe": len(campaign.probe.runs) if campaign.probe is not None else 0,
             "rtest": len(campaign.rtest.runs) if campaign.rtest is not None else 0}
    return sum(count[i] for i in instruments)


def machine_state(campaign) -> tuple:
    """The machine's state ``next`` continues from (``start`` of :class:`.design_timing.Timing`): the instrument of
    the last measured run on the machine at its set-up.  A session measures the ball bar's runs, then the probe's,
    then the R-test's (as a design orders them), so a designed probe or R-test run measured (its table named in the
    campaign's ``[design] to_fill_in``, which keeps the measured ones while the session goes on with those
    instruments: :func:`.design_output.designed_campaign`) is the last measured run — the latest of them in the
    design's order: the probe with that run's stylus and sphere, or the R-test —, else the ball bar's last run
    (mounted, its set-up and placement current); a new machine has nothing mounted."""
    goal = campaign.design
    probe = {r.id: r for r in campaign.probe.runs} if campaign.probe is not None else {}
    rtest = {r.id for r in campaign.rtest.runs} if campaign.rtest is not None else set()
    done = [k for k in (goal.to_fill_in if goal is not None else {}) if k in probe or k in rtest]
    if done and done[-1] in probe:
        run = probe[done[-1]]
        return (False, None, None, ("probe", campaign.probe.centre_length(run.stylus),
                                    tuple(float(x) for x in run.sphere)))
    if done:
        return (False, None, None, ("rtest",))
    bb = campaign.ballbar
    return (True, bb.runs[-1].setup, bb.runs[-1].mount) if bb.runs else (False, None, None)


def _contraction_now(planner: Planner, instrument: str) -> float:
    """``1 − var/var_prior`` of ``instrument``'s scale today (the ball bar's under a learnt prior against the wider
    prior's variance, :meth:`.design.Planner.contraction_reference`)."""
    now = now_of(planner)
    if instrument == "ballbar":
        prior_var = planner.contraction_reference() or float(planner.sigma_prior().var())
    else:
        prior_var = float(taught_prior(planner, instrument).var())
    return float(1.0 - now.variance(instrument) / prior_var)


def next_step(campaign, *, targets: dict | None = None, contraction: float | None = None,
              budget_min: float | None = None, time_model: TimeModel | None = None, candidates=None,
              model: str = "linear", seed: int | None = 0, n_sim: int | None = None, sigma_prior=None,
              instruments=None) -> NextStep:
    """The next run of a designed campaign, or stop (the rule: :mod:`.next_plan`).  Targets, contraction and budget
    default to the campaign's ``[design]``; ``sigma_prior`` a σ_model prior learnt elsewhere, as for
    :func:`.design_make.make_design` (a campaign does not record the prior it was designed under: give it again)."""
    goal = campaign.design
    want = parse_targets(targets if targets is not None else (goal.targets if goal else {}), campaign)
    if contraction is None:
        contraction = goal.contraction if goal and goal.contraction is not None else CONTRACTION
    if budget_min is None and goal is not None:
        budget_min = goal.budget_min
    bb = campaign.ballbar
    instruments = chosen_instruments(campaign, instruments)
    # the plan (the ball bar's planned runs, the designed probe and R-test runs not measured yet) and the user's
    # candidates only: the catalogue is read when the rest is designed again
    bar_plan = design_candidates(campaign, planned_candidates(campaign) + list(candidates or []),
                                 instruments=instruments, catalogue=False)
    other_plan = planned_other_candidates(campaign, instruments)
    plan = bar_plan + other_plan
    planner = reporting_planner(campaign, plan, want, model=model, sigma_prior=sigma_prior, instruments=instruments)
    tg = np.array([want.get(t, np.nan) for t in planner.targets])
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    # every measured reading of the instruments: the ball bar's, the probe's and the R-test's (:mod:`.design_now`)
    sd_now = now_of(planner).target_moments(planner.T)[1] * scale
    c_now = _contraction_now(planner, taught(instruments))
    others = planned_other(campaign)  # the designed probe and R-test runs not measured yet
    # a target counts as reached only where the measured runs determine its quantity (not its prior alone)
    determined_now = Determination(planner, []).determined()
    targets_met = (bool(np.all(sd_now <= np.where(np.isfinite(tg), tg, np.inf)))
                   and bool(np.all(determined_now | ~np.isfinite(tg))))
    base = dict(targets=list(planner.targets), target_units=list(planner.target_units), target_sd=tg, sd_now=sd_now,
                contraction_now=c_now, contraction_target=contraction, measured=measured_runs(campaign, instruments),
                planned_left=[p.label for p in bb.planned] + list(others.values()),
                learnt=learnt_summary(campaign, sigma_prior),
                determined_now=determined_now)
    if targets_met and contraction_delivered(campaign, c_now, contraction):
        return NextStep("stop", probability_targets_met=_conditional_met(planner, tg), **base)
    settings = {"targets": want, "contraction": contraction, "budget_min": budget_min, "time_model": time_model,
                "model": model, "seed": seed, "n_sim": n_sim, "sigma_prior": sigma_prior, "instruments": instruments}
    start = machine_state(campaign)
    design = None
    if bb.planned or other_plan:
        counts = np.array([int(c.kind == "planned") for c in bar_plan] + [1] * len(other_plan))
        design = design_of_plan(campaign, plan, counts, start=start, planner=planner, **settings)
        if plan_holds(design):
            design = without_unneeded(design, counts, c_now, start=start, planner=planner, **settings)
        else:
            design = None
    planned = {p.label for p in bb.planned} | set(others.values())
    if design is None:
        if campaign.design is not None and not bb.planned and not others:
            settings["contraction"] = None  # the designed plan, measured in full, delivered it: the targets are left
        design = _designed_again(campaign, plan, planner, sd_now=sd_now, c_now=c_now, start=start, settings=settings)
        design = planned_first(design, planned)
    chosen = {r.label for r in design.runs}
    return NextStep("measure", probability_targets_met=design.probability_targets_met(), design=design,
                    dropped=sorted(planned - chosen), added=sorted(chosen - planned), **base)


def _designed_again(campaign, plan, planner, *, sd_now, c_now, start, settings) -> Design:
    """The rest designed again from the machine's current state, the plan's runs among the catalogue's candidates;
    where the closed form finds nothing left to measure but the exact posterior has not met the targets yet, the
    targets tightened by the ratio (and σ_model's contraction goal raised), at most :data:`RETRIES` times."""
    want, contraction = dict(settings.pop("targets")), settings.pop("contraction")
    goal, contraction_goal = dict(want), contraction
    for _ in range(RETRIES):
        design = make_design(campaign, targets=goal, contraction=contraction, start=start,
                             candidates=[c for c in plan if c.kind in ("planned", "user")], **settings)
        if design.runs:
            return design
        # the closed form already promises what the exact posterior has not reached: ask it for the ratio more
        goal = {q: v * min(1.0, v / sd_now[planner.targets.index(q)]) ** 2 for q, v in goal.items()}
        if contraction_goal is not None and c_now < contraction_goal:  # and halve what σ_model's variance may keep
            contraction = 1.0 - 0.5 * (1.0 - contraction)
    short = [q for q in want if sd_now[planner.targets.index(q)] > want[q]]
    raise ParameterError("targets", f"{', '.join(short) or 'σ_model contraction'} not reached yet, and no candidate "
                         "run lowers it further in the closed form: relax the target or add candidates")


__all__ = ["NextStep", "next_step", "planned_candidates", "planned_other_candidates", "machine_state"]
