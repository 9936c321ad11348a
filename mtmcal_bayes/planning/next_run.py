"""``next``: on a partly measured designed campaign, the next run to measure or "stop: every target reached".

The posterior so far is the exact σ-marginal posterior of the measured runs (σ_model learnt from what
is measured).  When every target sd is met by it and σ_model's contraction reached (or promised in
expectation by the designed plan, now measured in full), the answer is *stop*, with the probability that
the targets are met: the posterior probability of σ_model's values at which the σ-conditional sds all
meet them (the sds themselves are known, σ_model is not).  Otherwise the remaining planned runs are kept
while their exact check from today's posterior still leaves each target likelier met than missed (runs
the data made unnecessary dropped), and the rest is designed again from the machine's current state
(the ball bar mounted at the last measured run's set-up and placement, the remaining planned runs among
the candidates) only where the plan falls short: :mod:`.next_plan`.  The first run of the plan is the
next one; the probability is the share of simulated machines in which the plan meets every target
(:mod:`.design_check`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..errors import ParameterError
from ..machine_time import TimeModel
from .candidates import Candidate
from .chain_candidates import arc_spec
from .design import Planner
from .design_instruments import chosen_instruments
from .design_make import (
    CONTRACTION,
    Design,
    design_candidates,
    design_of_plan,
    make_design,
    parse_targets,
    reporting_planner,
)
from .design_problem import current_posterior
from .determined import Determination
from .next_plan import contraction_delivered, plan_holds, without_unneeded
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


def _conditional_met(planner: Planner, targets: np.ndarray) -> float:
    """Posterior probability of the σ_model values at which every σ-conditional target sd meets its target."""
    now = current_posterior(planner)
    w = now.weights(planner.observations.mean[None])[:, 0]
    var = np.einsum("tp,gpq,tq->gt", planner.T, now.cov, planner.T)
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    sd = np.sqrt(np.maximum(var, 0.0)) * scale
    ok = np.all(sd <= np.where(np.isfinite(targets), targets, np.inf), axis=1)
    return float(w @ ok)


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
    # the plan and the user's candidates only: the catalogue is read when the rest is designed again
    plan = design_candidates(campaign, planned_candidates(campaign) + list(candidates or []), instruments=instruments,
                             catalogue=False)
    planner = reporting_planner(campaign, plan, want, model=model, sigma_prior=sigma_prior)
    tg = np.array([want.get(t, np.nan) for t in planner.targets])
    sd_now, c_now = _now(planner, bool(bb.runs))
    # a target counts as reached only where the measured runs determine its quantity (not its prior alone)
    determined_now = Determination(planner, []).determined()
    targets_met = (bool(np.all(sd_now <= np.where(np.isfinite(tg), tg, np.inf)))
                   and bool(np.all(determined_now | ~np.isfinite(tg))))
    base = dict(targets=list(planner.targets), target_units=list(planner.target_units), target_sd=tg, sd_now=sd_now,
                contraction_now=c_now, contraction_target=contraction, measured=len(bb.runs),
                planned_left=[p.label for p in bb.planned], learnt=learnt_summary(campaign, sigma_prior),
                determined_now=determined_now)
    if targets_met and contraction_delivered(campaign, c_now, contraction):
        return NextStep("stop", probability_targets_met=_conditional_met(planner, tg), **base)
    settings = {"targets": want, "contraction": contraction, "budget_min": budget_min, "time_model": time_model,
                "model": model, "seed": seed, "n_sim": n_sim, "sigma_prior": sigma_prior, "instruments": instruments}
    start = (True, bb.runs[-1].setup, bb.runs[-1].mount) if bb.runs else (False, None, None)
    design = None
    if bb.planned:
        counts = np.array([int(c.kind == "planned") for c in plan])
        design = design_of_plan(campaign, plan, counts, start=start, planner=planner, **settings)
        if plan_holds(design):
            design = without_unneeded(design, counts, c_now, start=start, planner=planner, **settings)
        else:
            design = None
    if design is None:
        if campaign.design is not None and not bb.planned:
            settings["contraction"] = None  # the designed plan, measured in full, delivered it: the targets are left
        design = _designed_again(campaign, plan, planner, sd_now=sd_now, c_now=c_now, start=start, settings=settings)
    planned = {p.label for p in bb.planned}
    chosen = {r.label for r in design.runs}
    return NextStep("measure", probability_targets_met=design.probability_targets_met(), design=design,
                    dropped=sorted(planned - chosen), added=sorted(chosen - planned), **base)


def _now(planner: Planner, measured: bool) -> tuple[np.ndarray, float]:
    """The exact posterior sds of the planner's targets today (display units) and σ_model's contraction."""
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    if measured:
        now = current_posterior(planner)
        _, sd = now.target_moments(planner.observations.mean[None], planner.T)
        w = now.weights(planner.observations.mean[None])[:, 0]
        s = now.sigma[:, 0]
        prior_var = planner.contraction_reference() or float(planner.sigma_prior().var())
        return sd[0] * scale, float(1.0 - (w @ s**2 - (w @ s) ** 2) / prior_var)
    # nothing measured yet: the priors (a learnt σ_model prior measured against the wider one's variance)
    ref = planner.contraction_reference()
    return (np.sqrt((planner.T**2) @ planner.prior_var) * scale,
            0.0 if ref is None else float(1.0 - planner.sigma_prior().var() / ref))


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


__all__ = ["NextStep", "next_step", "planned_candidates"]
