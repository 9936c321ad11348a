"""``design`` chooses among the ball bar, the touch probe and the R-test (docs/design.md, "Every instrument").

On a trunnion with one ball-bar set-up and mount, a probe and an R-test and no runs yet: the search picks the
instrument that reaches the target in fewer minutes, as the time model prices them (each made dear in turn); the
minutes of a mixed design add up item by item of the time model; ``--instruments`` restricts the candidates; a
probe-only design is one option away; bad input is one line, exit 2, nothing written.
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.machine_time import TimeModel
from mtmcal_bayes.planning.design import Planner
from mtmcal_bayes.planning.design_instruments import available, other_candidates
from mtmcal_bayes.planning.design_make import design_candidates, make_design
from mtmcal_bayes.planning.design_problem import DesignProblem
from mtmcal_bayes.planning.design_runs import designed_runs
from mtmcal_bayes.planning.design_search import Goal, Search
from mtmcal_bayes.planning.design_timing import Timing

CAMPAIGN = """format = "mtmcal-campaign/1"

[machine]
name = "trunnion, set-ups only"
description = "trunnion"

[ballbar]
instrument = "Renishaw QC20-W"
length_mm = 100.0
accuracy_um = 0.5

[ballbar.setups.T1]
R_B_mm = 150.0

[ballbar.mounts.W1]
position_mm = [0.0, 60.0, 30.0]

[probe]
instrument = "touch-trigger probe"
repeatability_um = 1.0

[probe.styli.S1]
length_mm = 150.0
"""

RTEST = """
[rtest]
instrument = "R-test, 3 sensors"
repeatability_um = 0.5
sphere_mm = [0.0, 60.0, 30.0]

[rtest.nests.N1]
length_mm = 150.0
"""

NEW = (False, None, None)


@pytest.fixture(scope="module")
def paths(tmp_path_factory):
    d = tmp_path_factory.mktemp("instruments")
    (d / "all.toml").write_text(CAMPAIGN + RTEST, encoding="utf-8")
    (d / "no_rtest.toml").write_text(CAMPAIGN, encoding="utf-8")
    return d


@pytest.fixture(scope="module")
def small(paths):
    """Six C-pattern ball-bar candidates, the probe's and the R-test's catalogues, valued for E_B0C."""
    c = load_campaign(paths / "all.toml")
    cands = [x for x in design_candidates(c) if x.pattern[0] == "C"][:6] + other_candidates(c, ["probe", "rtest"])
    return c, cands, DesignProblem(Planner(c, cands, ["E_B0C"]))


def _search(c, cands, problem, target, times, allowed=None):
    timing = Timing(c, times)
    result = Search(problem, Goal(np.array([target]), None, None),
                    lambda k: timing.total_of_counts(cands, k, NEW), allowed=allowed).run(0)
    return result, {cands[k].instrument for k in np.flatnonzero(result.counts)}


def test_every_instrument_available(paths):
    assert available(load_campaign(paths / "all.toml")) == {"ballbar": True, "probe": True, "rtest": True}
    assert available(load_campaign(paths / "no_rtest.toml"))["rtest"] is False


def test_compressed_rows_value_as_the_full_criterion(small):
    """A probe or R-test run's rows enter the search compressed to their rank: one more run by the Woodbury
    updates equals the design valued whole, with probe and R-test runs in it (several instances too)."""
    _, cands, problem = small
    counts = np.zeros(len(cands), dtype=int)
    kinds = [x.instrument for x in cands]
    counts[kinds.index("ballbar")] = 1
    counts[kinds.index("probe")] = 2
    counts[len(kinds) - 1] = 1  # an R-test sweep
    v1, _ = problem.value_plus_one(counts)
    v2 = problem.value(counts[None] + np.eye(len(cands), dtype=int))
    assert np.allclose(v1.sd_nodes, v2.sd_nodes, rtol=1e-9)
    assert np.allclose(v1.contraction_nodes, v2.contraction_nodes, rtol=1e-9, atol=1e-12)


def test_the_cheaper_instrument_is_chosen(small):
    """The target is one the ball bar alone reaches (its six candidates three times each reach 2/3 of it): with the
    time model's defaults a probe or R-test design reaches it in fewer minutes than any ball-bar design; with the
    probe's set-up made dear the R-test, with the R-test's the probe; with both dear the ball bar."""
    c, cands, problem = small
    bar = np.array([x.instrument == "ballbar" for x in cands])
    target = 1.5 * float(problem.value(np.where(bar, 3, 0)).sd_promised[0, 0])
    bar_only, _ = _search(c, cands, problem, target, TimeModel(), allowed=bar)
    assert bar_only.met
    cheap, used = _search(c, cands, problem, target, TimeModel())
    assert cheap.met and "ballbar" not in used and cheap.minutes < bar_only.minutes
    rtest, used = _search(c, cands, problem, target, TimeModel(mount_probe_min=400.0))
    assert rtest.met and used == {"rtest"} and rtest.minutes < bar_only.minutes
    probe, used = _search(c, cands, problem, target, TimeModel(mount_rtest_min=400.0))
    assert probe.met and used == {"probe"} and probe.minutes < bar_only.minutes
    dear = TimeModel(mount_rtest_min=400.0, mount_probe_min=400.0)
    bar_again, used = _search(c, cands, problem, target, dear)
    assert bar_again.met and used == {"ballbar"} and bar_again.minutes == pytest.approx(bar_only.minutes)


def test_minutes_add_up(small):
    """A ball-bar run, one probe candidate twice and an R-test sweep, from a new session: the ball bar's clock, then
    a change of instrument, the probe's set-up, its run, a stylus set anew and the sphere placed anew for its second
    run, a change of instrument, the R-test's set-up and its sweep — item by item of the time model."""
    c, cands, _ = small
    tm = TimeModel(instrument_change_min=7.0, stylus_change_min=3.0, move_sphere_min=2.0, mount_probe_min=11.0,
                   mount_rtest_min=13.0, probe_position_min=0.7, rotary_deg_per_min=200.0)
    timing = Timing(c, tm)
    kinds = [x.instrument for x in cands]
    b, p, r = kinds.index("ballbar"), kinds.index("probe"), len(kinds) - 1
    counts = np.zeros(len(cands), dtype=int)
    counts[[b, p, r]] = (1, 2, 1)
    pc, rc = cands[p], cands[r]
    assert rc.sweep_span is not None
    bar_minutes = timing.clock.total(designed_runs(cands, np.eye(len(cands), dtype=int)[b]), NEW)
    probe_run = pc.repeats * len(pc.positions[0][1]) * tm.probe_position_min
    expected = (bar_minutes + tm.instrument_change_min + tm.mount_probe_min + probe_run
                + tm.stylus_change_min + tm.move_sphere_min + probe_run
                + tm.instrument_change_min + tm.mount_rtest_min + rc.repeats * rc.sweep_span / tm.rotary_deg_per_min)
    runs = designed_runs(cands, counts)
    ordered = [runs[i] for i in timing.order(runs, NEW)]
    assert [x.instrument for x in ordered] == ["ballbar", "probe", "probe", "rtest"]
    assert timing.total_of_counts(cands, counts, NEW) == pytest.approx(expected, rel=1e-12)
    assert timing.total(runs, NEW) == timing.total_of_counts(cands, counts, NEW)
    assert sum(timing.per_run(ordered, NEW)) == pytest.approx(expected, rel=1e-12)
    kinds_of = [e.kind for e in timing.events(ordered, NEW)]
    assert kinds_of[-9:] == ["change instrument", "mount probe", "measure", "stylus change", "move sphere", "measure",
                             "change instrument", "mount R-test", "measure"]


def test_the_searchs_minutes_of_any_mixed_design_equal_the_schedules(small):
    """``Timing.total_of_counts`` (the search's minutes, no runs made) equals the schedule of the runs
    ``designed_runs`` makes, to the last bit, for random designs of every instrument (probe candidates run up to three
    times), from a new session, with the bar mounted and with a probe or the R-test on the machine."""
    c, cands, _ = small
    timing = Timing(c, TimeModel(instrument_change_min=7.0, stylus_change_min=3.0, move_sphere_min=2.0))
    probe = next(x for x in cands if x.instrument == "probe")
    bar = next(x for x in cands if x.instrument == "ballbar")
    starts = [NEW, (True, bar.setup.id, bar.mount.id), (False, None, None, ("probe", probe.stylus_length,
                                                                            tuple(probe.sphere))),
              (False, None, None, ("rtest",))]
    rng = np.random.default_rng(2)
    for _ in range(60):
        counts = rng.integers(0, 4, len(cands)) * (rng.random(len(cands)) < 0.3)
        for start in starts:
            runs = designed_runs(cands, counts)
            assert timing.total_of_counts(cands, counts, start) == timing.total(runs, start)


def test_instruments_restrict_the_candidates(paths):
    c = load_campaign(paths / "all.toml")
    assert {x.instrument for x in design_candidates(c, instruments=["probe"])} == {"probe"}
    assert {x.instrument for x in design_candidates(c, instruments=["ballbar", "rtest"])} == {"ballbar", "rtest"}


def test_probe_only_design(paths):
    """``instruments="probe"``: a design of touch-probe runs alone, its scale σ_model_probe learnt, its target met
    in the exact check, its minutes the sum of its runs'."""
    c = load_campaign(paths / "no_rtest.toml")
    d = make_design(c, targets={"E_B0C": 5.0}, contraction=None, seed=0, n_sim=100, instruments="probe")
    assert d.runs and {r.instrument for r in d.runs} == {"probe"} and d.instruments == ["probe"]
    assert sum(d.minutes) == pytest.approx(d.total_minutes, rel=1e-12)
    i = d.targets.index("E_B0C")
    assert d.check.share_met(d.goal.targets)[i] >= 0.8  # promised 0.9; 100 machines: 2 binomial sds below
    assert "σ_model_probe" in " ".join(d.notes)


@pytest.mark.parametrize("args, key", [
    (["--instruments", "rtest"], "--instruments: rtest"),
    (["--instruments", "ballbar,laser"], "--instruments: unknown instrument 'laser'"),
])
def test_bad_instruments(paths, run_cli, tmp_path, args, key):
    out_dir = tmp_path / "out"
    code, out, err = run_cli("design", paths / "no_rtest.toml", "--target", "E_B0C=5", *args, "-o", out_dir)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert key in err and "Traceback" not in err
    assert not out_dir.exists()


def test_bad_times_key(paths, run_cli, tmp_path):
    bad = tmp_path / "times.toml"
    bad.write_text("stylus_change_mins = 1.0\n", encoding="utf-8")
    out_dir = tmp_path / "out"
    code, out, err = run_cli("design", paths / "all.toml", "--target", "E_B0C=5", "--times", bad, "-o", out_dir)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "times.toml" in err and "stylus_change_mins" in err and "Traceback" not in err
    assert not out_dir.exists()


def test_written_design_has_programs_and_tables_to_fill_in(paths, tmp_path):
    """``design -o`` with R-test runs: each run's program (``ncgen --rtest``'s, one block per position) and its
    ``[[rtest.runs]]`` table with empty readings; filled in and added to the campaign, the campaign loads with them."""
    from mtmcal_bayes.api import _other_program, _program
    from mtmcal_bayes.io.toml_reader import parse_toml
    from mtmcal_bayes.io.tomlio import dumps
    from mtmcal_bayes.planning.design_output import write_design

    c = load_campaign(paths / "all.toml")
    d = make_design(c, targets={"E_B0C": 5.0}, contraction=None, seed=0, n_sim=100, instruments="rtest")
    files, _ = write_design(d, tmp_path / "out", program=_program, other_program=_other_program)
    assert d.runs and "to_fill_in.toml" in files
    table = parse_toml((tmp_path / "out" / "to_fill_in.toml").read_text(encoding="utf-8"), "to_fill_in.toml")
    runs = table["rtest"]["runs"]
    assert len(runs) == len(d.runs)
    for i, (run, t) in enumerate(zip(d.runs, runs), start=1):
        k = run.candidate.n_positions
        program = (tmp_path / "out" / f"programs/{i:02d}_rtest_{run.candidate.axis}.nc").read_text(encoding="utf-8")
        assert sum(line.startswith("G01") for line in program.splitlines()) == k
        assert t["displacement_um"] == [] and all(len(v) == k for v in t["angles_deg"].values())
        t["displacement_um"] = np.zeros((1, k, 3)).tolist()
    text = (paths / "all.toml").read_text(encoding="utf-8") + "\n" + dumps({"rtest": {"runs": runs}})
    (tmp_path / "measured.toml").write_text(text, encoding="utf-8")
    measured = load_campaign(tmp_path / "measured.toml")
    assert [r.id for r in measured.rtest.runs] == [t["id"] for t in runs]


def test_next_names_a_probe_run(paths):
    """``next`` on a campaign whose only instrument chosen is the probe: the next run is a probe run, named in the
    text with its stylus and sphere."""
    from mtmcal_bayes.planning.design_output import next_text
    from mtmcal_bayes.planning.next_run import next_step

    c = load_campaign(paths / "no_rtest.toml")
    step = next_step(c, targets={"E_B0C": 5.0}, contraction=None, seed=0, n_sim=100, instruments=["probe"])
    assert step.status == "measure" and step.design.runs[0].instrument == "probe"
    assert next_text(step).startswith(f"measure next: {step.design.runs[0].candidate.name} (stylus 150 mm, sphere at")


def test_an_rtest_candidate_names_its_sphere_once(paths):
    """On a campaign without R-test runs the sphere has the default placement (named "sphere" itself): a candidate's
    place is "sphere at [...] mm", not "sphere sphere at"; where a run places it, the placement is named."""
    from mtmcal_bayes.planning.plan import rtest_where

    c = load_campaign(paths / "all.toml")
    cand = other_candidates(c, ["rtest"])[0]
    assert not cand.setup.measured
    assert rtest_where(cand)["mount"] == "sphere at [0, 60, 30] mm"
    measured = load_campaign(paths / "all.toml")
    run = cand.run()
    run.placement = None  # named after the run that places it
    measured.rtest.runs = [run]
    assert rtest_where(other_candidates(measured, ["rtest"])[0])["mount"] == f"sphere {run.id} at [0, 60, 30] mm"


def test_next_measures_the_planned_run_before_the_runs_a_replan_adds(paths, monkeypatch):
    """A re-plan that keeps the planned R-test run and adds another R-test run names the planned one next — their
    order costs nothing there, and the plan may yet be enough on this machine (the added run then dropped) — where
    the search lists the added run first (the catalogue's order); the runs keep their whys and the minutes add up as
    before.  A planned run is not moved where that changes the measuring order: the R-test's run stays after the
    ball bar's."""
    from mtmcal_bayes.planning import next_run
    from mtmcal_bayes.planning.design_make import design_of_plan
    from mtmcal_bayes.planning.design_output import designed_campaign
    from mtmcal_bayes.planning.next_plan import planned_first

    c = load_campaign(paths / "all.toml")
    rtest = {x.name: x for x in other_candidates(c, ["rtest"])}
    added, kept = rtest["R-test A swept -120…30°"], rtest["R-test C swept 0…350°"]
    settings = dict(targets={"E_B0C": 1.5}, contraction=None, seed=0, n_sim=100)
    planned = designed_campaign(design_of_plan(c, [kept], np.array([1]), **settings))
    replan = design_of_plan(c, [added, kept], np.array([1, 1]), **settings)
    assert [r.label for r in replan.runs] == [added.name, kept.name]  # the search's order, the added run first
    monkeypatch.setattr(next_run, "plan_holds", lambda design: False)  # the plan falls short: designed again
    monkeypatch.setattr(next_run, "_designed_again", lambda *args, **kwargs: replan)
    step = next_run.next_step(planned, **settings)
    assert step.status == "measure" and step.added == [added.name] and not step.dropped
    assert [r.label for r in step.design.runs] == [kept.name, added.name]
    assert step.design.why == replan.why[::-1]
    assert sum(step.design.minutes) == pytest.approx(sum(replan.minutes), rel=1e-12)
    assert step.design.total_minutes == pytest.approx(replan.total_minutes, rel=1e-12)

    bar = design_candidates(c)[0]
    mixed = design_of_plan(c, [bar, kept], np.array([1, 1]), **settings)
    assert [r.instrument for r in mixed.runs] == ["ballbar", "rtest"]
    assert planned_first(mixed, {kept.name}) is mixed
