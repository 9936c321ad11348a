"""``design``: the whole campaign — which runs, in which order, how many machine minutes, what uncertainty.

1. Candidates: the catalogue's new ball-bar runs (patterns × tool lengths × placements × unmeasured
   set-ups, :func:`.catalogue.catalogue`) and the user's, feasible within the travels; a design may run a
   candidate up to :data:`.design_problem.MAX_INSTANCES` times, each further run on a new W-ball placement.
2. The search (:mod:`.design_search`) on the closed-form criterion at σ_model's quantiles
   (:mod:`.design_problem`) with the machine-time model (:mod:`mtmcal_bayes.machine_time`).
3. The exact preposterior check (:mod:`.design_check`); where it finds a target met in fewer than
   :data:`.design_problem.PROMISE` of the simulated machines, or the contraction short in expectation, the
   search runs again with that goal tightened by the shortfall, and where a target that shapes the design
   (:data:`BINDING`) is kept with more than :data:`LOOSEN_ABOVE` to spare, loosened by it (at most :data:`ROUNDS`
   rounds; a later round's search starts once from the last round's design; the rounds end when a moved goal's
   design is not kept — short of the promise, or longer than the one kept before, which stands).
4. The runs in measuring order (set-up changes grouped), each with its minutes and why it is there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..errors import InputError, ParameterError
from ..machine_time import TimeModel
from .candidates import Candidate
from .machine_kit import catalogue_of, feasibility_of
from .design import Planner, target_names
from .design_check import Preposterior, preposterior
from .design_instruments import SCALE_OF, chosen_instruments, other_candidates, taught
from .design_now import left_out, measured_data, now_of
from .design_problem import MAX_INSTANCES, PROMISE, DesignProblem
from .design_runs import DesignedRun, designed_runs
from .design_search import Goal, Search
from .design_refusal import beyond_note, refuse_undetermined
from .design_timing import Timing
from .determined import not_targeted
from .scale_priors import learnt_notes, learnt_summary

#: default σ_model contraction target: the data, not the prior, then set σ_model
CONTRACTION = 0.5
#: search rounds with the working goal moved by the exact check
ROUNDS = 4
#: the working targets are loosened while the exact check finds every target met with this much room (sd ratio)
LOOSEN_ABOVE = 1.1
#: a target shapes the design when its closed-form sd is at least this fraction of its working target; one met with
#: more room is not loosened further (the rounds end once every target that shapes the design is kept with
#: less than LOOSEN_ABOVE to spare)
BINDING = 0.7
#: a run "identifies" a quantity when dropping it would raise that quantity's sd by this fraction
WHY_SD = 0.05
#: ... or "teaches σ_model" when dropping it would lower the contraction by this much
WHY_CONTRACTION = 0.05
#: coverage factor of the ISO 14253-1 decision a tolerance's target sd is set for
K_DECISION = 1.96


@dataclass
class Design:
    """A designed campaign (see :mod:`.design_make`): its runs in measuring order and what they are expected to give."""

    campaign: object  # the starting Campaign
    runs: list[DesignedRun]  # measuring order
    minutes: list[float]  # per run: measuring plus the set-up changes it causes
    why: list[str]
    timing: Timing
    targets: list[str]
    target_units: list[str]
    goal: Goal
    check: Preposterior
    closed_form: dict  # sd_promised, sd_mean (t,), contraction: the search's criterion of the chosen design
    candidates: list[Candidate]
    model: str = "linear"
    notes: list[str] = field(default_factory=list)
    start: tuple = (False, None, None)
    rounds: int = 1
    #: the σ_model prior learnt elsewhere, as :func:`.scale_priors.learnt_summary` gives it (empty: assumed)
    learnt: dict = field(default_factory=dict)
    #: (t,) whether the campaign plus the designed runs determine each quantity (:mod:`.determined`)
    determined: np.ndarray | None = None
    #: {deviation: why} the deviations that are no reported quantity of their own (:func:`.determined.not_targeted`)
    not_targeted: dict = field(default_factory=dict)
    #: the instruments the design chose among (:mod:`.design_instruments`)
    instruments: list = field(default_factory=lambda: ["ballbar"])

    @property
    def total_minutes(self) -> float:
        return self.timing.total(self.runs, self.start)

    def probability_targets_met(self) -> float:
        """The share of simulated machines meeting every target; 0 while a target's quantity is not determined
        (met by its prior alone is not met)."""
        if self.determined is not None and np.any(np.isfinite(self.goal.targets) & ~np.asarray(self.determined)):
            return 0.0
        return self.check.share_all_met(self.goal.targets)


def parse_targets(targets: dict | None, campaign) -> dict[str, float]:
    """``{quantity: sd}`` (display units; ISO symbols allowed) checked: quantities of ``campaign``'s machine (its
    names, :func:`.design.target_names`), positive finite sds."""
    out = {}
    for name, sd in (targets or {}).items():
        q = target_names([str(name)], campaign)[0]
        try:
            v = float(sd)
        except (TypeError, ValueError):
            raise ParameterError("targets", f"{name}: expected a number, got {sd!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise ParameterError("targets", f"{name}: the target sd must be a positive number, got {sd!r}")
        out[q] = v
    return out


def targets_from_tolerances(planner: Planner, tolerances: dict, source: str = "tolerances") -> dict[str, float]:
    """Target sds at which the ISO 14253-1 decision is expected to be made: the 95 % half-interval
    (``K_DECISION`` sd) half the distance from today's estimate (the exact posterior mean; the prior mean on a
    new machine) to the nearest tolerance limit, so the decision holds while the estimate moves by the other
    half."""
    names = planner.targets
    mean, _ = now_of(planner).target_moments(planner.T)
    out = {}
    for i, q in enumerate(names):
        if q not in tolerances:
            continue
        tol = tolerances[q]
        lim = [v for v in (tol.low, tol.high) if v is not None and math.isfinite(v)]
        d = min(abs(mean[i] - v) for v in lim)
        unit = planner.target_units[i]
        if d <= 0.0:
            raise InputError(tol.source or source, tol.key or q,
                             "today's estimate lies on the tolerance limit: no uncertainty decides it")
        out[q] = units.from_internal(d / (2.0 * K_DECISION), unit)
    return out


def design_candidates(campaign, extra: list[Candidate] | None = None, source: str = "candidates",
                      instruments=("ballbar",), *, catalogue: bool = True) -> list[Candidate]:
    """``extra`` (the user's, or a designed campaign's planned runs; each checked: within the travels, at the
    campaign's bar length), the catalogue's new ball-bar runs within the travels (with the ball bar among
    ``instruments``), one candidate per pattern, set-up, mount and repeats (the first given), then the touch-probe
    and R-test runs of the catalogues within the travels (:func:`.design_instruments.other_candidates`); without
    ``catalogue`` ``extra`` alone, checked."""
    out = []
    fits = feasibility_of(campaign)
    for i, c in enumerate(extra or []):
        ok, why = fits(c)
        where = f"candidate[{i}]" if c.kind == "user" else f"planned run {c.name}"
        if not ok:
            raise InputError(source, where, f"{c.pattern} outside the machine's travels: {why}")
        if abs(c.length - campaign.ballbar.length) > 1e-9:
            raise InputError(source, f"{where}.length_mm", f"{c.length:g} mm: a campaign has one bar length "
                             f"({campaign.ballbar.length:g} mm); design another bar length as a campaign of its own")
        out.append(c)
    if not catalogue:
        return out
    for c in catalogue_of(campaign) if "ballbar" in instruments else []:
        if c.repeat_of is None and c.kind != "bar length" and fits(c)[0]:
            out.append(c)
    seen, unique = set(), []
    for c in out:
        key = (c.pattern, c.setup.id, c.mount.id, c.repeats, c.arc_deg, c.hold_deg)
        if key not in seen:
            seen.add(key)
            unique.append(c)
    return unique + other_candidates(campaign, list(instruments))


def reporting_planner(campaign, cands: list[Candidate], want: dict, *, tolerances=None, model: str = "linear",
                      sigma_prior=None, instruments=("ballbar",)) -> Planner:
    """The planner of a design: the measured readings of ``instruments`` (:func:`.design_now.measured_data`), the
    wanted quantities first, then the toleranced ones the machine reports, then every quantity reported by default
    (the thesis machine's eight identifiable ones; a described machine's deviations the campaign and the candidates
    determine one by one)."""
    tol = list(tolerances or {})
    planner = Planner(campaign, cands, None, model=model, sigma_prior=sigma_prior,
                      data=measured_data(campaign, instruments))
    known = set(planner.targets) | set(want)
    planner.retarget(list(dict.fromkeys(list(want) + [q for q in tol if q in known] + planner.targets)))
    return planner


def _goal_vector(planner: Planner, targets: dict[str, float]) -> np.ndarray:
    return np.array([targets.get(t, np.nan) for t in planner.targets], dtype=float)


def _check_reachable(problem: DesignProblem, search: Search, goal: Goal, units_of: list[str]) -> None:
    """Refuse targets no design of the candidates reaches (all at their most runs), naming the quantity and, where
    a run beyond the travels would lower it further, that run and the axis that keeps it out."""
    most = np.where(search.allowed, MAX_INSTANCES, 0)
    v = problem.value(most)
    sd = v.sd_promised[0]
    for i, t in enumerate(problem.planner.targets):
        if np.isfinite(goal.targets[i]) and sd[i] > goal.targets[i]:
            u = units.SYMBOL[units_of[i]]
            raise ParameterError("targets", f"{t} = {goal.targets[i]:g} {u} cannot be reached: every candidate "
                                 f"measured {MAX_INSTANCES} times gives {sd[i]:.3g} {u} (at σ_model's "
                                 f"{PROMISE:.0%} quantile); the best reachable is no smaller"
                                 + beyond_note(problem, t))
    if goal.contraction is not None and v.contraction[0] < goal.contraction:
        raise ParameterError("contraction", f"{goal.contraction:g} cannot be reached: every candidate measured "
                             f"{MAX_INSTANCES} times teaches σ_model {v.contraction[0]:.2f}")


def _check_budget(search: Search, goal: Goal) -> None:
    if goal.budget is None:
        return
    K = len(search.problem.candidates)
    shortest = min(search.minutes(np.eye(K, dtype=int)[k]) for k in np.flatnonzero(search.allowed))
    if goal.budget < shortest:
        raise ParameterError("budget_min", f"{goal.budget:g} min is shorter than the shortest run with its set-up "
                             f"({shortest:.0f} min)")


def _why(problem: DesignProblem, with_it, without, row: int, *, units_of: list[str],
         targets: np.ndarray | None = None) -> str:
    """What a run's last instance adds: the targeted quantities (``targets`` (t,), NaN: none) whose sd it lowers,
    then the others it lowers most, two at least where there are, and what it teaches σ_model; ``with_it`` the
    design's value, ``without`` the values of the design less one run of each candidate it runs
    (:meth:`.DesignProblem.value_minus_one`), ``row`` the run's candidate among them."""
    a, b = with_it.sd_promised[0], without.sd_promised[row]
    rel = b / a - 1.0
    served = np.zeros(len(rel), dtype=bool) if targets is None else np.isfinite(targets) & (rel > WHY_SD)
    first = [i for i in np.argsort(-rel) if served[i]]
    parts = []
    for i in first + [i for i in np.argsort(-rel) if not served[i]][:max(0, 2 - len(first))]:
        if rel[i] > WHY_SD:
            u = units.SYMBOL[units_of[i]]
            parts.append(f"{problem.planner.targets[i]} {b[i]:.3g} → {a[i]:.3g} {u}")
    teach = None
    dc = with_it.contraction[0] - without.contraction[row]
    if dc > WHY_CONTRACTION:
        teach = f"teaches σ_model (contraction {without.contraction[row]:.2f} → {with_it.contraction[0]:.2f})"
    if parts and teach:
        return f"identifies {', '.join(parts)}; {teach}"
    if parts:
        return f"identifies {', '.join(parts)}"
    return teach or "adds little on its own: the others lean on it (removing it leaves the targets unmet)"


def make_design(campaign, *, targets: dict | None = None, tolerances: dict | None = None,
                contraction: float | None = CONTRACTION, budget_min: float | None = None,
                candidates: list[Candidate] | None = None, time_model: TimeModel | None = None,
                model: str = "linear", seed: int | None = 0, start=None, n_sim: int | None = None,
                candidates_source: str = "candidates", sigma_prior=None, instruments=None) -> Design:
    """The designed campaign for ``campaign`` (see the module docstring).

    ``targets`` {quantity: sd in ″/µm}; ``tolerances`` {quantity: Tolerance} (targets from them where no sd is
    given); ``contraction`` σ_model's (None: none); ``budget_min`` machine minutes; ``candidates`` the user's, added
    to the catalogue; ``start`` (ball bar mounted, setup id, mount id) the machine's state (default: a new session,
    nothing mounted); ``sigma_prior`` a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` learnt elsewhere (None:
    the assumed prior): σ_model's quantiles, the contraction's Laplace prior and the exact check's draws and
    posteriors are then the learnt prior's, and the contraction is measured against the wider prior's variance
    (:meth:`.design.Planner.contraction_reference`); ``instruments`` the ones to choose among (names or
    ``"ballbar,probe"``; default every one the campaign has a set-up for, :mod:`.design_instruments`).
    """
    if contraction is not None and not (0.0 < contraction < 1.0):
        raise ParameterError("contraction", f"must lie between 0 and 1, got {contraction!r}")
    if budget_min is not None and not (math.isfinite(budget_min) and budget_min > 0):
        raise ParameterError("budget_min", f"must be a positive number of minutes, got {budget_min!r}")
    want = parse_targets(targets, campaign)
    instruments = chosen_instruments(campaign, instruments)
    cands = design_candidates(campaign, candidates, candidates_source, instruments)
    taken = set(campaign.ballbar.mounts) | {c.mount.id for c in cands if c.instrument == "ballbar"}
    if not cands:
        raise ParameterError("candidates", "no candidate run fits the machine's travels")
    planner = reporting_planner(campaign, cands, want, tolerances=tolerances, model=model, sigma_prior=sigma_prior,
                                instruments=instruments)
    if tolerances:
        for q, sd in targets_from_tolerances(planner, tolerances).items():
            want.setdefault(q, sd)
    if not want and contraction is None and budget_min is None:
        raise ParameterError("targets", "nothing to design for: give target sds, tolerances, a σ_model contraction "
                             "or a budget")
    problem = DesignProblem(planner, taught=taught(instruments))
    goal = Goal(_goal_vector(planner, want), contraction, budget_min)
    det = problem.determination
    refuse_undetermined(problem, goal)
    # a target the campaign does not determine yet is met only once the designed runs determine it
    problem.watch = np.isfinite(goal.targets) & ~det.determined()
    timing = Timing(campaign, time_model or TimeModel())
    start = start or (False, None, None)
    minutes = _remembered(lambda counts: timing.total_of_counts(cands, counts, start))
    floor = timing.floor(cands)
    search = Search(problem, goal, minutes, floor=floor)
    _check_budget(search, goal)
    if goal.has_targets:
        _check_reachable(problem, search, goal, planner.target_units)
    working = Goal(goal.targets.copy(), goal.contraction, goal.budget)
    kw = {} if n_sim is None else {"n_sim": n_sim}
    best, last, checked = None, None, {}
    for rounds in range(1, ROUNDS + 1):
        # a later round's goal moved by a few per cent: its search starts from the last round's design, once
        warm = {} if last is None else {"start": last[0].counts, "restarts": 0}
        result = Search(problem, working, minutes, floor=floor).run(seed, **warm)
        if goal.has_targets and not result.met:
            if best is not None or last is not None:
                break  # a tightened goal out of reach: keep what was found
            _refuse_within_budget(problem, goal, minutes, seed=seed, units_of=planner.target_units)
        runs = designed_runs(cands, result.counts, taken)
        key = np.asarray(result.counts).tobytes()  # a round that finds a design checked before: the same check
        if key not in checked:
            checked[key] = preposterior(planner, runs, seed=seed, taught=problem.taught, targets=goal.targets, **kw)
        check = checked[key]
        last = (result, runs, check, rounds)
        has = np.isfinite(goal.targets)
        short_sd = has & (check.share_met(goal.targets) < PROMISE)
        short_c = goal.contraction is not None and check.contraction.mean() < goal.contraction
        # no run where the closed form finds the goal met already: kept unless the exact posterior today falls short
        # (measured data of several instruments can put σ_model where the closed form's Laplace contraction is high)
        if (runs and not goal.has_targets) or (not runs and not short_sd.any() and not short_c):
            best = last
            break
        p = check.sd_quantile(PROMISE)
        if not short_sd.any() and not short_c and (best is None or result.minutes < best[0].minutes):
            best = last
        slack = np.where(has, goal.targets / p, 1.0)  # > 1: the promise is kept with room to spare
        # only the targets that shape the design are worth loosening: the others' room changes nothing
        binding = has & (result.value.sd_promised[0] >= BINDING * working.targets)
        if not short_sd.any() and not short_c and np.all(slack[binding] < LOOSEN_ABOVE):
            break
        if best is not None and best is not last:
            break  # a moved goal gave a design not kept (short of the promise, or longer): the kept one stands
        # the closed form's promise is off by what the exact check found: move the working targets by it
        working.targets = np.where(has, working.targets * np.clip(slack * 0.98, 0.5, 1.5), working.targets)
        if short_c:
            working.contraction = min(0.99, 1.0 - (1.0 - working.contraction) * (1.0 - goal.contraction) / max(
                1.0 - check.contraction.mean(), 1e-9))
    kept = best is not None
    result, runs, check, rounds = best or last
    return _assembled(campaign, cands, planner, problem, goal=goal, timing=timing, start=start,
                      counts=result.counts, value=result.value, runs=runs, check=check, rounds=rounds, kept=kept,
                      model=model, instruments=instruments, sigma_prior=sigma_prior,
                      short_note=f"the exact check finds some target met in fewer than {PROMISE:.0%} of the simulated "
                      f"machines after {ROUNDS} rounds (see 'met in'): the promise is not kept in full")


def design_of_plan(campaign, cands: list[Candidate], counts: np.ndarray, *, targets: dict | None = None,
                   contraction: float | None = CONTRACTION, budget_min: float | None = None,
                   time_model: TimeModel | None = None, model: str = "linear", seed: int | None = 0, start=None,
                   n_sim: int | None = None, sigma_prior=None, instruments=None, planner: Planner | None = None) -> Design:
    """The design of ``counts`` (K,) runs of ``cands`` as they are, no search: its exact check from today's posterior,
    its minutes from ``start`` and each run's why, as :func:`make_design` gives them (``next`` keeping a plan,
    :mod:`.next_plan`).  ``planner`` the reporting planner of ``cands`` when already made."""
    want = parse_targets(targets, campaign)
    instruments = chosen_instruments(campaign, instruments)
    planner = planner or reporting_planner(campaign, cands, want, model=model, sigma_prior=sigma_prior)
    problem = DesignProblem(planner, taught=taught(instruments))
    goal = Goal(_goal_vector(planner, want), contraction, budget_min)
    problem.watch = np.isfinite(goal.targets) & ~problem.determination.determined()
    timing = Timing(campaign, time_model or TimeModel())
    taken = set(campaign.ballbar.mounts) | {c.mount.id for c in cands if c.instrument == "ballbar"}
    runs = designed_runs(cands, counts, taken)
    kw = {} if n_sim is None else {"n_sim": n_sim}
    check = preposterior(planner, runs, seed=seed, taught=problem.taught, targets=goal.targets, **kw)
    kept = bool(np.all(check.share_met(goal.targets)[np.isfinite(goal.targets)] >= PROMISE)) and (
        goal.contraction is None or check.contraction.mean() >= goal.contraction)
    return _assembled(campaign, cands, planner, problem, goal=goal, timing=timing,
                      start=start or (False, None, None), counts=counts, value=problem.value(counts), runs=runs,
                      check=check, rounds=1, kept=kept, model=model, instruments=instruments,
                      sigma_prior=sigma_prior,
                      short_note=f"the exact check from today's posterior finds some target met in fewer than "
                      f"{PROMISE:.0%} of the simulated machines: the plan's promise is not kept in full here (next "
                      "keeps a plan while the data leave it likelier to meet each target than to miss it)")


def _assembled(campaign, cands, planner, problem, *, goal, timing, start, counts, value, runs, check, rounds, kept,
               model, instruments, sigma_prior, short_note: str) -> Design:
    """The :class:`Design` of the chosen ``counts`` (their closed-form ``value``, ``runs`` and exact ``check``): the
    runs in measuring order, each one's minutes and why, the notes (``short_note`` where the promise is not
    ``kept``)."""
    det = problem.determination
    order = timing.order(runs, start)
    runs = [runs[i] for i in order]
    index = {id(c): k for k, c in enumerate(cands)}
    # every run's candidate less one run at once (rank-r downdates of the design), each candidate's why once
    with_it, (without, _) = problem.value(counts), problem.value_minus_one(counts)
    row = {k: i for i, k in enumerate(np.flatnonzero(counts))}
    said = {k: _why(problem, with_it, without, i, units_of=planner.target_units, targets=goal.targets)
            for k, i in row.items()}
    why = [said[index[id(r.candidate)]] for r in runs]
    minutes_each = timing.per_run(runs, start)
    nodes = ", ".join(f"{units.from_internal(s, 'um'):.2f}" for s in problem.nodes)
    form = "the linear model" if model == "linear" else f"the {model} model linearised at zero deviations"
    notes = [
        f"expected sds from the exact σ-marginal posterior of {form} over {check.sd.shape[0]} simulated machines "
        "(parameters and σ_model from today's posterior, or the priors on a new machine)",
        f"a target is promised when it is met in at least {PROMISE:.0%} of those machines; the search uses the "
        f"closed form at σ_model's quantiles {nodes} µm",
        _candidates_note(instruments, problem.taught),
        "a designed run at an existing set-up assumes the T ball re-set to that set-up's offsets; re-centred, give "
        "the set-up a new id",
    ]
    notes += learnt_notes(campaign, sigma_prior, "σ_model's quantiles, its contraction and the exact check use it")
    notes += [n for n in [left_out(campaign, instruments)] if n]
    c_now = float(problem.value_now().contraction[0])
    if planner.learnt is not None and goal.contraction is not None and c_now >= goal.contraction:
        notes.append(f"σ_model's contraction target {goal.contraction:g} is met before any run ({c_now:.2f}): with "
                     "its prior learnt elsewhere σ_model is known that well already, so no run is designed to teach "
                     "it")
    determined = det.determined(counts)
    left = [t for t, d, g in zip(planner.targets, determined, goal.targets) if np.isfinite(g) and not d]
    if left:
        notes.append(f"not determined by the campaign and the designed runs: {', '.join(left)} (within the budget): "
                     "their targets are not met, whatever their prior's sd")
    if not kept:
        notes.append(short_note)
    return Design(campaign, runs, minutes_each, why, timing, list(planner.targets), list(planner.target_units), goal,
                  check, {"sd_promised": value.sd_promised[0], "sd_mean": value.sd_mean[0],
                          "contraction": float(value.contraction[0]),
                          "contraction_now": c_now},
                  cands, model, notes, start, rounds, learnt_summary(campaign, sigma_prior), determined,
                  not_targeted(planner, det.identifiability()), list(instruments))


def _candidates_note(instruments: list[str], scale: str) -> str:
    """What the design chose among, and which discrepancy scale it learns."""
    words = {"ballbar": "new ball-bar runs of the catalogue within the travels (bar lengths other than the "
                        "campaign's and more repeats of measured runs are not designed: a campaign has one bar "
                        "length, and a later session cannot add repeats to a measured run)",
             "probe": "touch-probe runs of the probe catalogue (each with its own stylus and sphere terms)",
             "rtest": "R-test runs of the R-test catalogue"}
    names = {i: SCALE_OF[i].replace("sigma_", "σ_") for i in instruments}  # σ_model, σ_model_probe, ...
    others = [names[i] for i in instruments if i != scale]
    return ("candidates: " + "; ".join(words[i] for i in instruments)
            + f"; the discrepancy scale the data teach and the search integrates out is {names[scale]}"
            + (f" ({', '.join(others)} at the rms of {'its' if len(others) == 1 else 'their'} prior in the search, "
               "integrated out in the exact check)" if others else "")
            + " (docs/design.md, \"Every instrument\")")


def _remembered(minutes):
    """``minutes(counts)`` computed once per count vector (the search asks again for designs it has timed)."""
    seen: dict[bytes, float] = {}

    def once(counts) -> float:
        key = np.asarray(counts, dtype=np.int64).tobytes()
        if key not in seen:
            seen[key] = minutes(counts)
        return seen[key]

    return once


def _refuse_within_budget(problem: DesignProblem, goal: Goal, minutes, *, seed, units_of) -> None:
    """The targets are out of reach within the budget: name the quantity furthest from its target and the best sd
    a design within the budget reaches for it (a search for that quantity alone)."""
    worst = None
    for i in np.flatnonzero(np.isfinite(goal.targets)):
        alone = np.full_like(goal.targets, np.nan)
        alone[i] = goal.targets[i]
        best = Search(problem, Goal(alone, None, goal.budget), minutes).run(seed, restarts=0)
        sd = float(problem.value(best.counts).sd_promised[0, i])
        if not best.met and sd <= goal.targets[i] * (1 + 1e-9):  # met by its prior only: no run within the budget
            within = "of the candidates" if goal.budget is None else f"within {goal.budget:g} min"
            raise ParameterError("targets", f"{problem.planner.targets[i]}: the search found no design {within} that "
                                 "determines it (its sd would be its prior's): raise the budget or add candidates")
        if sd > goal.targets[i] * (1 + 1e-9) and (worst is None or sd / goal.targets[i] > worst[1]):
            worst = (i, sd / goal.targets[i], sd)
    if worst is not None:
        i, _, sd = worst
        u = units.SYMBOL[units_of[i]]
        raise ParameterError("targets", f"{problem.planner.targets[i]} = {goal.targets[i]:g} {u} is not reachable "
                             f"within {goal.budget:g} min: the best design within the budget reaches {sd:.3g} {u} "
                             f"(at σ_model's {PROMISE:.0%} quantile)")
    best = Search(problem, Goal(np.full_like(goal.targets, np.nan), goal.contraction, goal.budget), minutes).run(
        seed, restarts=0)
    c = float(problem.value(best.counts).contraction[0])
    if goal.contraction is not None and c < goal.contraction:
        raise ParameterError("contraction", f"{goal.contraction:g} is not reachable within {goal.budget:g} min: the "
                             f"best design within the budget teaches σ_model {c:.2f}")
    raise ParameterError("targets", f"the targets together are not reachable within {goal.budget:g} min, although "
                         "each is alone: raise the budget or relax a target")


__all__ = ["Design", "make_design", "design_of_plan", "parse_targets", "targets_from_tolerances", "design_candidates", "CONTRACTION"]
