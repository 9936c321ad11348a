"""``design`` and ``next`` start from every measured instrument (docs/design.md, "Every instrument").

A new trunnion with a probe and an R-test is designed with the probe alone, and with the R-test alone; the first
designed run is measured on a simulated machine and added as the user adds it (its ``to_fill_in.toml`` table, filled
in); ``next`` then counts it as measured, its sds now are the exact posterior's of those readings (``sample --sampler
exact --data probe`` / ``rtest``) and it re-plans the rest, naming the next run as the design names it.  The thesis
campaign's own probe runs in the design's sds before are in tests/test_design.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmcal_bayes.inference.approximation import PosteriorApproximation
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io import parse_campaign
from mtmcal_bayes.planning.design_check import preposterior
from mtmcal_bayes.planning.design_instruments import other_candidates
from mtmcal_bayes.planning.design_make import design_candidates, make_design, reporting_planner
from mtmcal_bayes.planning.design_other_runs import planned_other
from mtmcal_bayes.planning.design_output import designed_campaign, next_text
from mtmcal_bayes.planning.design_problem import DesignProblem
from mtmcal_bayes.planning.design_runs import designed_runs
from mtmcal_bayes.planning.next_run import next_step
from tests.machines import SimulatedMachine, measure_sequentially
from tests.test_design_instruments import CAMPAIGN as INSTRUMENTS_CAMPAIGN
from tests.test_design_instruments import RTEST

# the new trunnion with a ball bar, a probe and an R-test set-up, no run: the instruments test's
CAMPAIGN = INSTRUMENTS_CAMPAIGN + RTEST

N_SIM = 100


@pytest.fixture(scope="module", params=["probe", "rtest"])
def measured(request):
    """The designed campaign (``E_B0C`` ≤ 8″ with the probe, or with the R-test), its first run measured on machine
    1, and ``next`` on it."""
    kind = request.param
    c = parse_campaign(CAMPAIGN, "trunnion.toml")
    design = make_design(c, targets={"E_B0C": 8.0}, instruments=[kind], n_sim=N_SIM)
    planned = designed_campaign(design)
    first = design.runs[0]
    table = next(k for k, v in planned.design.to_fill_in.items() if v == first.label)
    machine = SimulatedMachine(c, seed=1)
    one = machine.measure_other(planned, first, table_id=table)
    return kind, design, planned, one, table, machine, next_step(one, instruments=[kind], n_sim=N_SIM)


def test_a_designed_campaign_names_its_runs_to_fill_in(measured):
    """Every designed probe or R-test run is named in the campaign's ``[design] to_fill_in`` by its table's id."""
    kind, design, planned, *_ = measured
    assert len(design.runs) >= 2 and all(r.instrument == kind for r in design.runs)
    assert list(planned.design.to_fill_in.values()) == [r.label for r in design.runs]
    assert len(planned_other(planned)) == len(design.runs)


def test_next_counts_a_measured_run(measured):
    """The filled-in run is measured; the other designed runs are still planned."""
    kind, design, _, one, table, _, step = measured
    assert step.measured == 1
    assert [r.id for r in getattr(one, kind).runs] == [table]
    assert step.planned_left == [r.label for r in design.runs[1:]]
    assert set(step.dropped) <= set(step.planned_left)


def test_next_starts_from_the_measured_readings(measured):
    """``next``'s sds now are the exact posterior's of the run's readings (the same σ-marginal posterior as ``sample
    --sampler exact --data probe`` / ``rtest``, on the same grid: equal to rounding, 1e-6 of the sd), and the run has
    narrowed a quantity it determines far below its prior's 60″."""
    kind, *_, one, _, _, step = measured
    exact = PosteriorApproximation(LogPosterior(one, "linear", data=kind)).moments(step.targets)
    np.testing.assert_allclose(step.sd_now, [exact[t][1] for t in step.targets], rtol=1e-6)
    assert step.sd_now.min() < 10.0


def test_next_names_the_next_run_as_design_does(measured):
    """The re-plan's first run is a run of the instrument named as the design names its runs (its catalogue name),
    and the sequential loop of the validation measures it under its planned table's id (in the campaign ``next -o``
    writes where the step changed the plan)."""
    from mtmcal_bayes.planning.design_output import designed_campaign

    kind, _, _, one, _, machine, step = measured
    assert step.status == "measure"
    nxt = step.design.runs[0]
    assert nxt.instrument == kind and nxt.label in next_text(step)
    c, _, _ = measure_sequentially(machine, one, max_runs=1, n_sim=N_SIM, instruments=[kind])
    runs = getattr(c, kind).runs
    assert len(runs) == 2
    plan = designed_campaign(step.design, one.design) if step.added or step.dropped else one
    planned_id = [k for k, v in planned_other(plan).items() if v == nxt.label]
    assert runs[-1].id == (planned_id[0] if planned_id else f"design 01 {kind} {nxt.candidate.axis}")


def test_a_campaign_with_probe_or_rtest_data_alone_designs(measured):
    """A campaign whose only readings are the probe's or the R-test's (set-ups of the ball bar, none of its runs)
    designs with the ball bar and that instrument: σ_model at its prior (the learnt scale, nothing measured of it),
    the readings in the criterion and in the exact check, whose sds before are those of the readings and fall with
    the runs."""
    kind, *_, one, _, _, step = measured
    both = ["ballbar", kind]
    cands = [c for c in design_candidates(one, instruments=both) if c.instrument == "ballbar"][:3] + \
        other_candidates(one, [kind])[:2]
    planner = reporting_planner(one, cands, dict.fromkeys(step.targets, 8.0), instruments=both)
    assert planner.data == kind
    problem = DesignProblem(planner)
    counts = np.array([1, 0, 0, 1, 0])
    assert np.all(np.isfinite(problem.value(counts).sd_nodes))
    check = preposterior(planner, designed_runs(cands, counts), n_sim=50, seed=1)
    now = dict(zip(planner.targets, check.sd_now))
    np.testing.assert_allclose([now[t] for t in step.targets], step.sd_now, rtol=1e-6)
    assert np.all(check.sd_mean <= check.sd_now * (1 + 1e-9))


def test_next_counts_no_set_up_of_the_instrument_on_the_machine(measured):
    """After a probe (R-test) run the probe (R-test) is on the machine: ``next`` continues from it
    (:func:`~mtmcal_bayes.planning.next_run.machine_state`, the run's stylus and sphere), so the rest's schedule has
    no set-up of that instrument, and its minutes are those of its events; the campaign ``next -o`` writes for the
    rest (no ball-bar run in it) keeps that state."""
    from mtmcal_bayes.planning.next_run import machine_state

    kind, _, _, one, _, _, step = measured
    state = machine_state(one)
    assert state[:3] == (False, None, None) and state[3][0] == kind
    if kind == "probe":
        run = one.probe.runs[-1]
        assert state[3][1:] == (one.probe.centre_length(run.stylus), tuple(float(x) for x in run.sphere))
    d = step.design
    assert d.start == state and all(r.instrument == kind for r in d.runs)
    events = d.timing.events(d.runs, d.start)
    assert not any(e.kind.startswith("mount") or e.kind == "change instrument" for e in events), events
    assert d.total_minutes == pytest.approx(sum(e.minutes for e in events), rel=1e-12)
    assert machine_state(designed_campaign(d, one.design)) == state


def test_a_ball_bar_run_after_the_probe_changes_the_instrument(measured):
    """From the probe or the R-test on the machine, its own run comes first and costs no set-up; the ball-bar run
    after it costs the change of instrument and the bar's set-up as in a new session (mounting, tool, W ball); the
    minutes of a plan's counts walk the same schedule (the same float)."""
    from mtmcal_bayes.machine_time import TimeModel
    from mtmcal_bayes.planning.design_timing import Timing

    kind, _, _, one, _, _, step = measured
    bar = [c for c in design_candidates(one, instruments=["ballbar", kind]) if c.instrument == "ballbar"][:1]
    cands = bar + [step.design.runs[0].candidate]
    timing, times = Timing(one, TimeModel()), TimeModel()
    runs = designed_runs(cands, np.array([1, 1]))
    new = timing.total(runs, (False, None, None))
    on = timing.total(runs, step.design.start)
    # the instrument on the machine first, from its state there, then the change and the bar as in a new session
    own = timing.total([r for r in runs if r.instrument == kind], step.design.start)
    bar_alone = timing.total([r for r in runs if r.instrument == "ballbar"], (False, None, None))
    assert on == pytest.approx(own + times.instrument_change_min + bar_alone, rel=1e-12)
    set_up = times.mount_probe_min if kind == "probe" else times.mount_rtest_min
    assert on < new - set_up + times.stylus_change_min + times.move_sphere_min + 1e-9  # its set-up saved
    ordered = [runs[i] for i in timing.order(runs, step.design.start)]
    assert [r.instrument for r in ordered] == [kind, "ballbar"]
    kinds = [e.kind for e in timing.events(ordered, step.design.start)]
    assert not any(k.startswith("mount") and "ball bar" not in k for k in kinds)  # the instrument is not set up
    assert kinds[kinds.index("change instrument") + 1] == "mount ball bar"
    assert timing.total_of_counts(cands, np.array([1, 1]), step.design.start) == on


def test_next_keeps_the_planned_probe_and_rtest_runs_without_the_search(measured, monkeypatch):
    """The designed probe or R-test runs not measured yet are ``next``'s plan as the ball bar's planned runs are: kept
    from the plan's exact check alone while it holds (the search is not run: it would raise here), each named as
    the design named it, those the data made unnecessary dropped."""
    from mtmcal_bayes.planning import next_run

    def no_search(*args, **kwargs):
        raise AssertionError("the search ran for a plan that still holds")

    kind, design, _, one, _, _, _ = measured
    monkeypatch.setattr(next_run, "make_design", no_search)
    step = next_run.next_step(one, instruments=[kind], n_sim=N_SIM)
    assert step.status == "measure" and not step.added
    labels = [r.label for r in step.design.runs]
    assert sorted(labels + step.dropped) == sorted(r.label for r in design.runs[1:])
    assert [r.instance for r in step.design.runs] == [1] * len(labels)


def test_a_planned_further_probe_run_sets_its_stylus_and_sphere_anew(measured):
    """A planned probe run that is a candidate's second run (``<name> #2``) is priced as the design priced it: its
    stylus and sphere set anew, even where the probe on the machine has them already."""
    import dataclasses

    from mtmcal_bayes.machine_time import TimeModel
    from mtmcal_bayes.planning.design_timing import Timing

    kind, _, _, one, _, _, _ = measured
    if kind != "probe":
        pytest.skip("a probe run's stylus and sphere")
    c = other_candidates(one, ["probe"])[0]
    state = (False, None, None, ("probe", c.stylus_length, tuple(c.sphere)))
    first = dataclasses.replace(c.again(1), name=c.name)
    second = dataclasses.replace(c.again(2), name=f"{c.name} #2")
    timing, times = Timing(one, TimeModel()), TimeModel()
    kinds = [[e.kind for e in timing.events(designed_runs([x], np.array([1])), state)] for x in (first, second)]
    assert kinds == [["measure"], ["stylus change", "move sphere", "measure"]]
    assert timing.total_of_counts([second], np.array([1]), state) == pytest.approx(
        times.stylus_change_min + times.move_sphere_min + timing.floor([second])[0], rel=1e-12)


def test_the_simulated_machine_measures_a_probe_or_rtest_run_through_the_chain(measured):
    """The validation's machine measures a designed probe or R-test run through its kinematic chain, with the run's
    own nuisance terms and the instrument's repeatability: at a deviation far beyond its prior (1°, where the chain
    and its first order differ by tens of µm) and no discrepancy, the mean readings are the chain's at the machine's
    truth within 5 standard errors of the repeatability, and far from the linear model's."""
    import copy

    from mtmcal_bayes.inference.log_posterior import parameter_space
    from mtmcal_bayes.planning.design_instruments import SCALE_OF
    from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector

    kind, design, planned, *_ = measured
    machine = SimulatedMachine(parse_campaign(CAMPAIGN, "trunnion.toml"), seed=7)
    machine.values["E_B0C"] = np.radians(1.0)
    machine.scales[SCALE_OF[kind]] = 0.0
    out = machine.measure_other(planned, design.runs[0], table_id="through the chain")
    one = copy.deepcopy(out)
    one.ballbar.runs, one.ballbar.planned = [], []
    setattr(one, "rtest" if kind == "probe" else "probe", None)
    space = parameter_space(one, False, kind)
    truth = truth_from_vector(space, np.array([machine.values[n] for n in space.names]))

    def readings(c):
        run = getattr(c, kind).runs[-1]
        return run.centres if kind == "probe" else run.displacements

    mean = readings(out).mean(axis=0)
    se = getattr(one, kind).repeatability / np.sqrt(readings(out).shape[0])
    chain, linear = (readings(synthetic_campaign(one, truth, model))[0] for model in ("chain", "linear"))
    assert np.max(np.abs(mean - chain)) < 5 * se
    assert np.max(np.abs(mean - linear)) > 20 * se
