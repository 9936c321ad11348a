"""The campaign designer (SPEC §16, docs/design.md): criterion, search, exact check, outputs, ``next``."""

import json

import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.planning.design import Planner
from mtmcal_bayes.planning.design_make import design_candidates
from mtmcal_bayes.planning.design_problem import MAX_INSTANCES, PROMISE, DesignProblem
from mtmcal_bayes.planning.design_runs import designed_runs
from mtmcal_bayes.planning.design_search import Goal, Search, exhaustive, shortfall


@pytest.fixture(scope="module")
def problem(thesis):
    cands = design_candidates(thesis)
    return DesignProblem(Planner(thesis, cands))


def test_criterion_at_one_sigma_is_the_planners_closed_form(thesis):
    """At a single σ node the designer's sds and contraction are the planner's, for the campaign as it is, one more
    run of every candidate, and a second run of a candidate on its own placement (Planner.sigma_information)."""
    cands = design_candidates(thesis)
    pl = Planner(thesis, cands)
    dp = DesignProblem(pl, nodes=np.array([pl.sigma_model]))
    ev = pl.evaluate()
    si = pl.sigma_information(max_runs=2)
    now = dp.value_now()
    np.testing.assert_allclose(now.sd_nodes[0, 0], ev.sd_before, rtol=1e-9)
    np.testing.assert_allclose(now.contraction_nodes[0, 0], si.contraction_now, rtol=1e-9)
    plus, ok = dp.value_plus_one(np.zeros(len(cands), dtype=int))
    assert ok.all()
    np.testing.assert_allclose(plus.sd_nodes[:, 0], ev.sd_after, rtol=1e-9)
    np.testing.assert_allclose(plus.contraction_nodes[:, 0], si.contraction, rtol=1e-9)
    from mtmcal_bayes.planning.design import sigma_contraction

    for k in (0, len(cands) // 2, len(cands) - 1):
        one = np.zeros(len(cands), dtype=int)
        one[k] = 1
        second, _ = dp.value_plus_one(one)
        assert second.contraction_nodes[k, 0] == pytest.approx(sigma_contraction(si.fisher[k, 1], si.prior_var),
                                                               rel=1e-9)


def test_batched_values_equal_one_by_one(problem):
    rng = np.random.default_rng(3)
    K = len(problem.candidates)
    counts = rng.integers(0, MAX_INSTANCES + 1, size=(5, K)) * (rng.random((5, K)) < 0.1)
    batch = problem.value(counts)
    for i in range(5):
        one = problem.value(counts[i])
        np.testing.assert_allclose(batch.sd_nodes[i], one.sd_nodes[0], rtol=1e-10)
        np.testing.assert_allclose(batch.contraction_nodes[i], one.contraction_nodes[0], rtol=1e-10)


def test_more_runs_never_raise_an_sd_nor_lower_the_contraction(problem):
    """Adding a run adds information: every sd at every σ node falls or stays, the contraction grows or stays."""
    rng = np.random.default_rng(4)
    K = len(problem.candidates)
    counts = np.zeros(K, dtype=int)
    for _ in range(6):
        before = problem.value(counts)
        plus, ok = problem.value_plus_one(counts)
        assert np.all(plus.sd_nodes[ok] <= before.sd_nodes[0] * (1 + 1e-9))
        assert np.all(plus.contraction_nodes[ok] >= before.contraction_nodes[0] - 1e-9)
        counts[rng.choice(np.flatnonzero(ok))] += 1


def test_sigma_nodes_follow_the_measured_posterior(problem, thesis):
    """The nodes are quantiles of σ_model's exact posterior given the thesis runs: increasing, inside its grid."""
    from mtmcal_bayes.planning.design_problem import current_posterior

    nodes = problem.nodes
    assert np.all(np.diff(nodes) > 0)
    now = current_posterior(problem.planner)
    w = now.weights(problem.planner.observations.mean[None])[:, 0]
    cdf = np.cumsum(w)
    for q, s in zip((0.1, 0.5, 0.9), nodes[[0, 2, 4]]):
        below = cdf[np.searchsorted(now.sigma[:, 0], s) - 1]
        assert abs(below - q) < 0.02


def test_one_more_run_by_rank_updates_equals_the_direct_inverse(problem):
    """value_plus_one (Woodbury updates) equals value() of each design with the run added, first or further run."""
    rng = np.random.default_rng(5)
    K = len(problem.candidates)
    for _ in range(3):
        counts = rng.integers(0, MAX_INSTANCES, size=K) * (rng.random(K) < 0.15)
        fast, ok = problem.value_plus_one(counts)
        plus = np.repeat(counts[None], K, axis=0) + np.eye(K, dtype=int)
        direct = problem.value(plus)
        np.testing.assert_allclose(fast.sd_nodes[ok], direct.sd_nodes[ok], rtol=1e-7)
        np.testing.assert_allclose(fast.contraction_nodes[ok], direct.contraction_nodes[ok], rtol=1e-7, atol=1e-10)


def test_one_run_less_by_rank_downdates_equals_the_direct_inverse(problem):
    """value_minus_one (Woodbury downdates) equals value() of each design with one run taken away, its only run of
    the candidate or a further one; a perturbed sign of the downdate would not."""
    rng = np.random.default_rng(6)
    K = len(problem.candidates)
    for _ in range(3):
        counts = rng.integers(0, MAX_INSTANCES + 1, size=K) * (rng.random(K) < 0.3)
        assert (counts == 1).any() and (counts > 1).any()
        fast, less = problem.value_minus_one(counts)
        np.testing.assert_array_equal(less.sum(axis=1), counts.sum() - 1)
        direct = problem.value(less)
        np.testing.assert_allclose(fast.sd_nodes, direct.sd_nodes, rtol=1e-7)
        np.testing.assert_allclose(fast.contraction_nodes, direct.contraction_nodes, rtol=1e-7, atol=1e-10)


def test_a_swap_from_the_larger_designs_products_equals_one_more_run_of_the_smaller(problem):
    """value_swap (the design's products corrected by the run taken away) gives the sds of value_plus_one of the
    design less that run, for a candidate run once and one run more often; with a contraction goal the smaller design
    does not reach it is value_plus_one itself."""
    rng = np.random.default_rng(8)
    K = len(problem.candidates)
    counts = rng.integers(0, MAX_INSTANCES + 1, size=K) * (rng.random(K) < 0.3)
    for k in (np.flatnonzero(counts == 1)[0], np.flatnonzero(counts > 1)[0]):
        less = counts.copy()
        less[k] -= 1
        want, ok_want = problem.value_plus_one(less)
        fast, ok = problem.value_swap(counts, k, contraction_met=-np.inf)
        ok_want[k] = False  # not a swap
        np.testing.assert_array_equal(ok, ok_want)
        np.testing.assert_allclose(fast.sd_nodes[ok], want.sd_nodes[ok], rtol=1e-8)
        np.testing.assert_allclose(fast.contraction, problem.value(less).contraction[0], rtol=1e-8)
        slow, _ = problem.value_swap(counts, k, contraction_met=np.inf)
        # the smaller design's own updates (its moments reached from the last design asked: the same to rounding)
        np.testing.assert_allclose(slow.contraction_nodes, want.contraction_nodes, rtol=1e-12)


def test_a_contraction_goal_met_stays_met_one_run_later(problem):
    """With the design's contraction at the goal, value_plus_one gives the design's own contraction for every larger
    design (not updating its traces): a lower bound of each one's own, the sds unchanged."""
    rng = np.random.default_rng(7)
    K = len(problem.candidates)
    counts = rng.integers(0, MAX_INSTANCES, size=K) * (rng.random(K) < 0.3)
    own = float(problem.value(counts).contraction[0])
    full, ok = problem.value_plus_one(counts)
    bound, _ = problem.value_plus_one(counts, contraction_met=own)
    np.testing.assert_array_equal(bound.sd_nodes, full.sd_nodes)
    np.testing.assert_allclose(bound.contraction, own, rtol=1e-9)
    assert np.all(full.contraction[ok] >= own - 1e-9)  # a run added never lowers the information about σ
    again, _ = problem.value_plus_one(counts, contraction_met=own + 1e-3)  # not met: every design its own
    np.testing.assert_array_equal(again.contraction_nodes, full.contraction_nodes)


def test_a_design_containing_one_known_to_meet_the_contraction_goal_meets_it_without_its_traces(thesis):
    """Once a design is known to reach the contraction goal, a larger one (each candidate run at least as often) is
    given that design's contraction, a lower bound meeting the goal, with its own sds; a design not containing it
    still gets its own contraction."""
    cands = design_candidates(thesis)
    problem = DesignProblem(Planner(thesis, cands))
    rng = np.random.default_rng(8)
    K = len(cands)
    small = rng.integers(0, 2, size=K) * (rng.random(K) < 0.2)
    goal = float(problem.value(small).contraction[0]) - 1e-6
    problem.value_plus_one(small, contraction_met=goal)  # now known to meet it
    larger = np.minimum(small + rng.integers(0, 2, size=K) * (rng.random(K) < 0.2), MAX_INSTANCES)
    own = problem.value(larger).contraction[0]
    assert own >= goal
    bound, _ = problem.value_plus_one(larger, contraction_met=goal)
    np.testing.assert_allclose(bound.sd_nodes, problem.value_plus_one(larger)[0].sd_nodes, rtol=1e-12)
    assert np.all(bound.contraction >= goal) and np.all(bound.contraction <= own + 1e-12)
    other = np.zeros(K, dtype=int)
    other[np.flatnonzero(small == 0)[0]] = 1  # one run of a candidate small does not run: short of the goal
    assert problem.value(other).contraction[0] < goal
    full, _ = problem.value_plus_one(other)
    mine, _ = problem.value_plus_one(other, contraction_met=goal)
    np.testing.assert_allclose(mine.contraction_nodes, full.contraction_nodes, rtol=1e-12)


# ---------------------------------------------------------------------------------------------------- search
def test_a_design_containing_one_that_determines_the_targets_is_not_asked_again(new_machine):
    """On a new machine (nothing determined) the watched targets' undetermined parts of designs, and of one more run
    of each candidate, are the determination's own, whether or not the problem has met a smaller design that
    determines them all (then it makes no null space for a larger one)."""
    from mtmcal_bayes.planning.design_problem import _unseen

    cands = design_candidates(new_machine)
    dp = DesignProblem(Planner(new_machine, cands))
    det = dp.determination
    K = len(cands)
    dp.watch = det.determined(np.ones(K, dtype=int))  # every target the catalogue determines
    assert dp.watch.any() and not det.determined()[dp.watch].any()
    rng = np.random.default_rng(5)
    small = [c for c in (rng.integers(0, 2, size=K) * (rng.random(K) < 0.3) for _ in range(40))
             if c.any() and det.determined(c)[dp.watch].all()][0]  # a few runs that determine them
    assert not dp.value(small).undetermined.any()  # now known to determine them
    designs = [small + rng.integers(0, 2, size=K) * (rng.random(K) < 0.1) for _ in range(3)]  # larger ones
    designs += [rng.integers(0, 2, size=K) * (rng.random(K) < 0.1) for _ in range(3)]  # others, some not determining
    assert any(dp._covered(d > 0) for d in designs) and not all(dp._covered(d > 0) for d in designs)
    for d in designs:
        np.testing.assert_array_equal(dp.value(d).undetermined, _unseen(det.unseen_many(d), dp.watch))
        np.testing.assert_array_equal(dp.value_plus_one(d)[0].undetermined,
                                      _unseen(det.unseen_plus_one(d), dp.watch))


@pytest.fixture(scope="module")
def new_machine(thesis):
    """The thesis machine before any run: its set-ups and mounts only."""
    import copy

    from mtmcal_bayes.campaign import Probe

    c = copy.deepcopy(thesis)
    c.ballbar.runs, c.probe, c.reported, c.truth = [], Probe(), {}, None
    return c


#: the search's minutes may exceed the exhaustive optimum by this share (bench/design.py: 20 of 20 at the optimum)
SEARCH_MARGIN = 0.05


def test_search_meets_targets_within_the_margin_of_exhaustive_search(new_machine):
    """On small candidate sets (6 candidates, 0–3 runs each: 4096 designs) the greedy + exchange search finds a
    design meeting the targets in at most (1 + SEARCH_MARGIN) × the exhaustive optimum's minutes."""
    from tests.machines import small_problem

    rng = np.random.default_rng(11)
    compared = 0
    while compared < 5:
        made = small_problem(new_machine, rng)
        if made is None:
            continue
        dp, minutes, tg = made
        goal = Goal(tg, 0.5 if compared % 2 else None)
        best = exhaustive(dp, goal, minutes, max_count=MAX_INSTANCES)
        if not best.met:
            continue
        found = Search(dp, goal, minutes).run(seed=0)
        assert found.met
        assert shortfall(dp.value(found.counts), goal)[0] <= 1e-9
        assert found.minutes <= (1 + SEARCH_MARGIN) * best.minutes + 1e-9
        assert found.minutes == pytest.approx(minutes(found.counts))
        compared += 1


def test_greedy_asks_the_schedule_of_the_candidates_that_could_win_and_picks_the_same(new_machine):
    """With each candidate's floor of minutes (its measuring time) the greedy asks the schedule best bound first and
    stops where no bound beats the best rate found; its picks are those of asking every candidate in turn, for the
    plain start and randomised ones (the same jitter drawn for the same candidates), and it asks fewer schedules."""
    from mtmcal_bayes.machine_time import TimeModel
    from mtmcal_bayes.planning.design_make import design_candidates
    from mtmcal_bayes.planning.design_problem import DesignProblem
    from mtmcal_bayes.planning.design_timing import Timing

    cands = design_candidates(new_machine)
    dp = DesignProblem(Planner(new_machine, cands, ["alpha_XB", "dy_CZ", "beta_CZ"]))
    timing = Timing(new_machine, TimeModel())
    asked = {"floor": 0, "turn": 0}

    def counted(name):
        def minutes(counts):
            asked[name] += 1
            return timing.total_of_counts(cands, counts, (False, None, None))
        return minutes

    goal = Goal(np.array([1.5, 6.0, 3.0]), 0.5)
    for seed in (None, 1, 2):
        rng = lambda: None if seed is None else np.random.default_rng(seed)  # noqa: E731
        with_floor = Search(dp, goal, counted("floor"), floor=timing.floor(cands)).greedy(rng())
        in_turn = Search(dp, goal, counted("turn")).greedy(rng())
        assert np.array_equal(with_floor, in_turn) and with_floor.sum() > 2
    assert asked["floor"] < asked["turn"]


def test_search_within_a_budget_near_the_exhaustive_best(new_machine):
    """With a budget alone, the improvement J of the search's design is within 10 % of the exhaustive best's (0–2 runs
    of each of 6 candidates) and its minutes within the budget (bench/design.py: 17 of 18 problems at the best, the
    worst at 92.5 %: a better design there differs from the search's in four candidates at once)."""
    from mtmcal_bayes.planning.design_search import improvement

    rng = np.random.default_rng(12)
    from tests.machines import small_problem

    for budget in (60.0, 90.0, 120.0):
        made = None
        while made is None:
            made = small_problem(new_machine, rng)
        dp, minutes, _ = made
        goal = Goal(np.full(len(dp.planner.targets), np.nan), None, budget)
        best = exhaustive(dp, goal, minutes, max_count=2)
        found = Search(dp, goal, minutes).run(seed=0)
        now = dp.value_now()
        j_best = improvement(dp.value(best.counts), now)[0]
        j_found = improvement(dp.value(found.counts), now)[0]
        assert found.minutes <= budget + 1e-9
        assert j_found >= 0.90 * j_best - 1e-9


# ---------------------------------------------------------------------------------------------------- designs
@pytest.fixture(scope="module")
def thesis_design(thesis):
    import mtmcal_bayes as mb

    return mb.design(thesis).design


@pytest.fixture(scope="module")
def thesis_exact(thesis):
    """``sample --sampler exact --data both``'s posterior of the thesis campaign: ball bar and touch probe, each its
    own discrepancy scale, integrated out on its grid."""
    from mtmcal_bayes.inference.approximation import PosteriorApproximation
    from mtmcal_bayes.inference.log_posterior import LogPosterior

    return PosteriorApproximation(LogPosterior(thesis, "linear", data="both"))


def test_design_from_the_thesis_campaign_teaches_sigma_model(thesis_design, thesis_exact):
    """Acceptance: from the measured thesis campaign (its ball-bar and its probe runs) the design reaches σ_model
    contraction ≥ 0.5 in expectation (exact σ-marginal posterior of each simulated campaign), from today's exact
    posterior's, which is short of it (0.39: 0.07 from the ball bar's runs alone)."""
    d = thesis_design
    prior_var = Planner(d.campaign, []).sigma_prior().var()
    sd = units.to_internal(thesis_exact.moments(["sigma_model"])["sigma_model"][1], "um")
    assert d.check.contraction_now == pytest.approx(1.0 - sd**2 / prior_var, rel=1e-6)  # the same grid: rounding
    assert d.check.contraction_now < 0.5
    assert d.check.contraction.mean() >= 0.5
    assert 1 <= len(d.runs) <= 3
    assert d.total_minutes == pytest.approx(sum(d.minutes))


def test_design_starts_from_every_measured_instrument(thesis_design, thesis_exact):
    """The design's sds before its runs are the exact posterior's of every measured reading, the thesis' probe runs
    too (the same σ-marginal posterior as ``sample --sampler exact --data both``, on the same grid: equal to
    rounding, 1e-6 of the sd); the probe's C-axis runs pin α_CZ and β_CZ, which the ball bar's runs leave at 8″."""
    d = thesis_design
    exact = thesis_exact.moments(d.targets)
    for q in ("alpha_CZ", "beta_CZ"):
        sd = d.check.sd_now[d.targets.index(q)]
        assert sd == pytest.approx(exact[q][1], rel=1e-6)
        assert sd < 3.0
    assert d.instruments == ["ballbar", "probe"]


def test_a_design_without_the_ball_bar_leaves_its_readings_out(thesis):
    """``--instruments probe`` on the thesis campaign: today's posterior is the probe's readings' alone (the
    ball bar's runs are measured but not among the instruments), as ``sample --sampler exact --data probe``'s."""
    from mtmcal_bayes.inference.approximation import PosteriorApproximation
    from mtmcal_bayes.inference.log_posterior import LogPosterior
    from mtmcal_bayes.planning.design_make import make_design

    d = make_design(thesis, instruments=["probe"], n_sim=50)
    exact = PosteriorApproximation(LogPosterior(thesis, "linear", data="probe")).moments(d.targets)
    np.testing.assert_allclose(d.check.sd_now, [exact[t][1] for t in d.targets], rtol=1e-6)


def test_exact_check_agrees_with_the_closed_form_at_a_known_sigma(thesis):
    """With σ_model's prior narrowed to a point, the Monte-Carlo realised sds equal the closed form's (the linear
    posterior sd does not depend on the data at a known σ): a check of the simulation and the exact posterior."""
    import copy

    from mtmcal_bayes.planning.design_check import preposterior

    c = copy.deepcopy(thesis)
    c.priors = {**c.priors, "sigma_model": {"dist": "normal", "mean": 0.002, "sd": 0.00001}}  # 2 ± 0.01 µm
    cands = design_candidates(c)
    pl = Planner(c, cands)
    dp = DesignProblem(pl, nodes=np.array([0.002]))
    counts = np.zeros(len(cands), dtype=int)
    counts[[0, 5]] = 1
    runs = designed_runs(cands, counts)
    pp = preposterior(pl, runs, n_sim=50, seed=1)
    closed = dp.value(counts).sd_nodes[0, 0]
    np.testing.assert_allclose(pp.sd.mean(axis=0), closed, rtol=2e-3)
    assert pp.sd.std(axis=0).max() < 1e-3 * closed.max()


def test_promised_share_holds_on_simulated_machines(new_machine):
    """Validation (docs/design.md): a design from nothing, measured on 60 machines drawn from the priors (data from
    simulate plus σ_model's discrepancy), exact posterior: each target is met in at least the promised 90 % of
    machines, within the binomial 1 % lower quantile for 60 machines (0.82)."""
    from scipy import stats

    import mtmcal_bayes as mb
    from mtmcal_bayes.planning.design_output import designed_campaign
    from tests.machines import SimulatedMachine, realised_sd

    tg = {"alpha_XB": 1.5, "dy_CZ": 8.0, "alpha_CZ": 10.0}
    d = mb.design(new_machine, targets=tg).design
    dc = designed_campaign(d)
    machines = [SimulatedMachine(new_machine, 1000 + i, model="linear") for i in range(60)]
    sds = np.array([realised_sd(m.measure_all(dc), list(tg)) for m in machines])
    share = np.mean(sds <= np.array(list(tg.values())), axis=0)
    floor = stats.binom.ppf(0.01, 60, PROMISE) / 60
    assert np.all(share >= floor), share
    # the design's own preposterior says the same within the Monte-Carlo error of 60 machines
    promised = d.check.share_met(np.array([tg.get(q, np.nan) for q in d.targets]))
    for q, s in zip(tg, share):
        assert abs(s - promised[d.targets.index(q)]) < 3 * np.sqrt(0.1 * 0.9 / 60)


@pytest.fixture(scope="module")
def sequential_design(new_machine):
    """The design of the sequential tests: α_XB ≤ 1.5″, δy_CZ ≤ 8 µm on the thesis machine from nothing."""
    import mtmcal_bayes as mb

    return mb.design(new_machine, targets={"alpha_XB": 1.5, "dy_CZ": 8.0}).design


def test_next_keeps_a_plan_that_still_holds_without_the_search(new_machine, sequential_design, monkeypatch):
    """After the first planned run, measured on a simulated machine, ``next`` names the plan's next run as planned
    (nothing added or dropped) from the plan's exact check alone: the search is not run (it would raise here)."""
    from mtmcal_bayes.planning import next_run
    from mtmcal_bayes.planning.design_output import designed_campaign
    from mtmcal_bayes.planning.next_plan import KEEP_SHARE
    from tests.machines import SimulatedMachine

    def no_search(*args, **kwargs):
        raise AssertionError("the search ran for a plan that still holds")

    monkeypatch.setattr(next_run, "make_design", no_search)
    planned = designed_campaign(sequential_design)
    c = SimulatedMachine(new_machine, 2000).measure(planned, 0)
    step = next_run.next_step(c, n_sim=200)
    assert step.status == "measure" and not step.added and not step.dropped
    assert [r.label for r in step.design.runs] == [p.label for p in c.ballbar.planned]
    d = step.design
    assert np.all(d.check.share_met(d.goal.targets)[np.isfinite(d.goal.targets)] >= KEEP_SHARE)


def test_next_stops_on_the_plan_measured_in_full_when_its_targets_are_met(new_machine, sequential_design):
    """The design promises σ_model's contraction in expectation over machines; measured in full on a machine where
    the targets are met but the realised contraction falls short of 0.5, ``next`` stops (and says why) where the
    earlier rule measured on.  Without the campaign's plan (no ``[design]``), the same data are measured on."""
    from mtmcal_bayes.planning.design_output import designed_campaign, next_text
    from mtmcal_bayes.planning.next_run import next_step
    from tests.machines import SimulatedMachine, realised_sd

    c = SimulatedMachine(new_machine, 2000).measure_all(designed_campaign(sequential_design))
    assert np.all(realised_sd(c, ["alpha_XB", "dy_CZ"]) <= [1.5, 8.0])
    step = next_step(c, n_sim=100)
    assert step.contraction_now < 0.5  # the case of the rule (this machine's realised contraction)
    assert step.status == "stop"
    assert "promised it in expectation" in next_text(step)
    c.design = None
    again = next_step(c, targets={"alpha_XB": 1.5, "dy_CZ": 8.0}, contraction=0.5, n_sim=100)
    assert again.status == "measure"


def test_sequential_measuring_stops_no_later_than_the_fixed_design(new_machine, sequential_design):
    """``next`` after every run on simulated machines (measured through the thesis machine's kinematic model): it
    stops with every target met; on every machine where the fixed design also meets them (the same machine measuring
    it) it uses no more machine minutes than the fixed design; every run it names says which target it serves
    (3 machines here; 50 per type in bench/next_sequential.py)."""
    import copy

    from mtmcal_bayes.planning.design_output import designed_campaign
    from tests.machines import SimulatedMachine, measure_sequentially, realised_sd

    tg = {"alpha_XB": 1.5, "dy_CZ": 8.0}
    limit = np.array(list(tg.values()))
    d = sequential_design
    fixed = d.total_minutes
    compared = 0
    for i in range(3):
        machine = SimulatedMachine(new_machine, 2000 + i)
        twin = copy.deepcopy(machine)
        trail = []
        c, minutes, step = measure_sequentially(machine, designed_campaign(d), trail=trail)
        assert step.status == "stop"
        assert np.all(realised_sd(c, list(tg)) <= limit)
        assert trail and all(any(q in why for q in tg) for _, _, why, *_ in trail), trail
        if np.all(realised_sd(twin.measure_all(designed_campaign(d)), list(tg)) <= limit):
            compared += 1
            assert minutes <= fixed + 1e-9, (i, minutes, fixed)
    assert compared


# ---------------------------------------------------------------------------------------------------- command line
RUN_KEYS = {"order", "pattern", "setup", "mount", "R_B_mm", "Z_T_mm", "X_T_mm", "R_C_mm", "Z_C_mm", "length_mm",
            "repeats", "minutes", "program", "why"}


@pytest.fixture(scope="module")
def new_machine_file(new_machine, tmp_path_factory):
    from mtmcal_bayes import save_campaign

    path = tmp_path_factory.mktemp("machine") / "new_machine.toml"
    save_campaign(new_machine, path)
    return path


def test_design_json_and_files_through_simulate_sample_and_next(run_cli, new_machine_file, tmp_path):
    """design -o writes the interface's JSON, a campaign to fill in, one program per run and design.html; the
    campaign, filled by simulate, is a normal campaign for sample and next."""
    out = tmp_path / "d"
    code, stdout, err = run_cli("design", new_machine_file, "--target", "alpha_XB=1.5", "--target", "dy_CZ=8",
                                "-o", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert set(doc) >= {"runs", "total_minutes", "expected", "sigma_model", "campaign"}
    assert doc["campaign"] == str(out / "campaign.toml")
    assert all(set(r) >= RUN_KEYS for r in doc["runs"])
    assert [r["order"] for r in doc["runs"]] == list(range(1, len(doc["runs"]) + 1))
    assert doc["total_minutes"] == pytest.approx(sum(r["minutes"] for r in doc["runs"]), abs=0.05)
    for q in ("alpha_XB", "dy_CZ"):
        e = doc["expected"][q]
        assert set(e) >= {"sd_before", "sd_after", "sd_after_p10", "sd_after_p90", "target"}
        assert e["sd_after_p10"] <= e["sd_after"] <= e["sd_after_p90"] and e["sd_after"] < e["sd_before"]
    assert doc["sigma_model"]["contraction_after"] >= 0.5 > doc["sigma_model"]["contraction_before"]
    for r in doc["runs"]:
        text = (out / r["program"]).read_text()
        assert text.startswith("G01") and "F1000" in text
    assert (out / "design.html").read_text().count("data:image/png;base64") == 2
    assert json.loads((out / "design.json").read_text())["runs"] == doc["runs"]

    from mtmcal_bayes import load_campaign

    planned = load_campaign(out / "campaign.toml")
    assert [p.label for p in planned.ballbar.planned] == [f"{r['pattern']}@{r['setup']}/{r['mount']}"
                                                           for r in doc["runs"]]
    assert planned.design.targets == {"alpha_XB": 1.5, "dy_CZ": 8.0}
    truth = tmp_path / "truth.toml"
    truth.write_text("[deviations]\nalpha_XB_arcsec = 12.0\ndy_CZ_um = -30.0\n", encoding="utf-8")
    filled = tmp_path / "filled.toml"
    code, _, err = run_cli("simulate", out / "campaign.toml", "--truth", truth, "--noise", "--model", "linear",
                           "--seed", "3", "-o", filled)
    assert code == 0, err
    code, stdout, err = run_cli("sample", filled, "--sampler", "exact", "--json", "--quiet")
    assert code == 0, err
    code, stdout, err = run_cli("next", filled, "--json")
    assert code == 0, err
    nxt = json.loads(stdout)
    assert set(nxt) >= {"status", "run", "minutes_left", "probability_targets_met", "expected"}
    assert nxt["status"] == "stop" and nxt["run"] is None and nxt["minutes_left"] == 0
    assert nxt["expected"]["alpha_XB"]["sd_now"] <= 1.5
    # nothing measured yet: the first run of the plan
    code, stdout, err = run_cli("next", out / "campaign.toml", "--json")
    assert code == 0, err
    first = json.loads(stdout)
    assert first["status"] == "measure" and set(first["run"]) >= RUN_KEYS
    assert first["minutes_left"] > 0 and 0.0 <= first["probability_targets_met"] <= 1.0


def test_next_text_names_the_run_and_the_time_left(run_cli, thesis):
    code, stdout, err = run_cli("next")
    assert code == 0, err
    assert stdout.startswith("measure next: ") and "time left:" in stdout


@pytest.mark.parametrize("args, flag, words", [
    (["--target", "alpha_XB=0.001"], "--target", ["alpha_XB", "cannot be reached"]),
    (["--target", "alpha_XB=0.5", "--budget-min", "45"], "--target", ["alpha_XB", "within 45 min", "reaches"]),
    (["--budget-min", "20", "--instruments", "ballbar"], "--budget-min", ["shorter than the shortest run"]),
    (["--budget-min", "1"], "--budget-min", ["shorter than the shortest run"]),
    (["--target", "foo_XB=1"], "--target", ["unknown quantity"]),
    (["--target", "alpha_XB"], "--target", ["NAME=SD"]),
    (["--target", "alpha_XB=-2"], "--target", ["positive"]),
    (["--contraction", "1.5"], "--contraction", ["between 0 and 1"]),
])
def test_bad_design_requests_are_one_line_exit_2_nothing_written(run_cli, tmp_path, args, flag, words):
    out = tmp_path / "never"
    code, stdout, err = run_cli("design", *args, "-o", out)
    assert code == 2 and stdout == ""
    assert len(err.strip().splitlines()) == 1 and flag in err, err
    assert all(w in err for w in words), err
    assert not out.exists()


def test_bad_times_and_candidates_files_name_the_file_and_key(run_cli, tmp_path):
    times = tmp_path / "times.toml"
    times.write_text("tool_change_min = -4\n", encoding="utf-8")
    out = tmp_path / "never"
    code, _, err = run_cli("design", "--times", times, "-o", out)
    assert code == 2 and f"{times}: tool_change_min" in err and len(err.strip().splitlines()) == 1
    cands = tmp_path / "cands.toml"
    cands.write_text('[[candidate]]\npattern = "CA"\nsetup = "RB1"\nZ_C_mm = 65.5\nR_C_mm = 900\n', encoding="utf-8")
    code, _, err = run_cli("design", "--candidates", cands, "-o", out)
    assert code == 2 and f"{cands}: candidate[0]" in err and "travel" in err, err
    assert not out.exists()


def test_each_runs_why_is_what_removing_it_costs(new_machine):
    """A design's why per run (all drops weighed at once) says what removing that run costs, as the design less that
    run valued on its own gives it: each targeted sd it lowers by more than WHY_SD, and σ_model's contraction it
    teaches where the drop exceeds WHY_CONTRACTION (runs that teach it and runs that do not)."""
    from mtmcal_bayes.planning.design_make import WHY_CONTRACTION, WHY_SD, make_design

    targets = {"alpha_XB": 1.5, "dy_CZ": 8.0}
    d = make_design(new_machine, targets=targets, contraction=0.5)
    problem = DesignProblem(Planner(new_machine, d.candidates))
    counts = np.zeros(len(d.candidates), dtype=int)
    index = {id(c): k for k, c in enumerate(d.candidates)}
    for r in d.runs:
        counts[index[id(r.candidate)]] += 1
    with_it = problem.value(counts)
    where = [problem.planner.targets.index(q) for q in targets]
    teaching = []
    for r, why in zip(d.runs, d.why):
        less = counts.copy()
        less[index[id(r.candidate)]] -= 1
        without = problem.value(less)
        a, b = with_it.sd_promised[0], without.sd_promised[0]
        for q, i in zip(targets, where):
            if b[i] / a[i] - 1.0 > WHY_SD:
                assert f"{q} {b[i]:.3g} → {a[i]:.3g}" in why
        teaching.append(with_it.contraction[0] - without.contraction[0] > WHY_CONTRACTION)
        if teaching[-1]:
            assert f"teaches σ_model (contraction {without.contraction[0]:.2f} → {with_it.contraction[0]:.2f})" in why
        else:
            assert "teaches" not in why
    assert any(teaching) and not all(teaching)
