"""``next``'s rule: stop, keep the plan, drop from it, or design the rest again (docs/design.md, "Measure as you go").

A design promises each target met on :data:`~.design_problem.PROMISE` of the machines (their realised posterior
sd) and σ_model's contraction in expectation over them.  ``next`` asks of the measured data what the design asked
of its plan, no more:

* **stop** once the realised posterior sds meet the targets (each targeted quantity determined by the measured
  runs) and σ_model's contraction is reached — or the plan that promised the contraction in expectation (the
  campaign's ``[design]``) has been measured in full (:func:`contraction_delivered`);
* **keep** the remaining planned runs while their exact check from today's posterior meets each target on at least
  :data:`KEEP_SHARE` of the simulated machines (:func:`plan_holds`): the design's 90 % is a share over machines
  before any data; the data move this machine's own chance up or down, and a plan they leave likelier to meet each
  target than to miss it is measured on as designed (should it still miss one at the end, the rest is designed
  then);
* **drop** a planned run when the rest without it still promise every target at once on ``PROMISE`` of the
  simulated machines and σ_model's contraction in expectation (:func:`without_unneeded`);
* **design the rest again** (:func:`.design_make.make_design`) only when the plan falls short — a target met on
  fewer than ``KEEP_SHARE`` — or is measured in full with a target unmet, or there is no plan; the planned runs the
  re-plan keeps are measured before the runs it adds wherever that costs no minute (:func:`planned_first`): the
  plan may yet be enough on this machine, and the runs added after it are then dropped.

Keeping a plan costs one exact check and a closed-form screen of its runs, not the search.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .design_instruments import taught
from .design_make import Design, design_of_plan
from .design_other_runs import planned_other
from .design_problem import PROMISE, DesignProblem

#: a plan is kept while the data leave each target met on at least this share of the machines simulated from today
KEEP_SHARE = 0.5


def contraction_delivered(campaign, c_now: float, contraction: float | None) -> bool:
    """Whether σ_model's contraction is asked no more: none asked, reached now (``c_now``), or promised in
    expectation by the campaign's designed plan, now measured in full."""
    return (contraction is None or c_now >= contraction
            or (campaign.design is not None and not campaign.ballbar.planned and not planned_other(campaign)))


def plan_holds(design: Design) -> bool:
    """Whether the plan's exact check from today's posterior meets each target on at least :data:`KEEP_SHARE` of
    its simulated machines (and its runs determine every targeted quantity)."""
    tg = design.goal.targets
    has = np.isfinite(tg)
    if design.determined is not None and np.any(has & ~np.asarray(design.determined)):
        return False
    return bool(np.all(design.check.share_met(tg)[has] >= KEEP_SHARE))


def _promises(design: Design, c_now: float) -> bool:
    """Every target met at once on :data:`PROMISE` of the simulated machines, and the contraction reached now or in
    expectation."""
    c = design.goal.contraction
    return (design.probability_targets_met() >= PROMISE
            and (c is None or c_now >= c or float(design.check.contraction.mean()) >= c))


def without_unneeded(design: Design, counts: np.ndarray, c_now: float, **settings) -> Design:
    """``design`` (the remaining plan, ``counts`` (K,) over its candidates) without the planned runs the data made
    unnecessary: greedily the one whose dropping saves most minutes, while the rest still promises (:func:`_promises`)
    — screened by the closed form at σ_model's :data:`PROMISE` quantile first (only a plan the closed form still
    finds meeting every target is checked exactly).  ``settings`` those of :func:`.design_make.design_of_plan`."""
    planner = settings.pop("planner")
    problem = DesignProblem(planner, taught=taught(design.instruments))
    tg = design.goal.targets
    has = np.isfinite(tg)
    while counts.sum() > 1:
        fewer = np.array([counts - np.eye(len(counts), dtype=counts.dtype)[k] for k in np.flatnonzero(counts)])
        v = problem.value(fewer)
        ok = np.all(v.sd_promised[:, has] <= tg[has], axis=1)
        if design.goal.contraction is not None and c_now < design.goal.contraction:
            ok &= v.contraction >= design.goal.contraction
        saved = [design.total_minutes - design.timing.total_of_counts(design.candidates, f, design.start)
                 for f in fewer]
        for j in sorted((j for j in np.flatnonzero(ok) if saved[j] > 0), key=lambda j: -saved[j]):
            shorter = design_of_plan(design.campaign, design.candidates, fewer[j], planner=planner, **settings)
            if _promises(shorter, c_now):
                design, counts = shorter, fewer[j]
                break
        else:
            return design
    return design


def planned_first(design: Design, planned: set) -> Design:
    """``design`` (a re-plan) with the runs the plan held (their labels ``planned``) measured before the runs it adds
    wherever that costs nothing: a planned run moved ahead of an added one next to it while the order stays the
    measuring order (:meth:`.design_timing.Timing.order`: the same instrument, set-up and placement, or probe
    station) and the minutes do not grow.  The runs' whys are their own, moved with them."""
    runs, timing, start = design.runs, design.timing, design.start
    order, total = list(range(len(runs))), sum(design.minutes)
    moved = True
    while moved:  # each move takes a planned run ahead of an added one: at most (planned × added) moves
        moved = False
        for j in range(1, len(order)):
            a, b = order[j - 1], order[j]
            if runs[b].label not in planned or runs[a].label in planned:
                continue
            trial = order[:j - 1] + [b, a] + order[j + 1:]
            ordered = [runs[i] for i in trial]
            if (timing.order(ordered, start) == list(range(len(ordered)))
                    and sum(timing.per_run(ordered, start)) <= total + 1e-9):
                order, moved = trial, True
    if order == list(range(len(runs))):
        return design
    ordered = [runs[i] for i in order]
    return dataclasses.replace(design, runs=ordered, minutes=timing.per_run(ordered, start),
                               why=[design.why[i] for i in order])


__all__ = ["KEEP_SHARE", "contraction_delivered", "plan_holds", "planned_first", "without_unneeded"]
