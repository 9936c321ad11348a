"""``plan`` ranks R-test runs (docs/rtest.md, "Planning R-test runs"; docs/planning.md).

On two types, the best R-test candidate reduces the sd of a deviation the campaign leaves undetermined and that the
campaign with that run added determines (the Jacobian's rule, :func:`campaign_identifiability`); a campaign without
``[rtest]`` has no R-test candidate; every candidate's angles lie within the travels; a plan's R-test run is a run
``ncgen --rtest`` writes; the time model prices it and ``--times`` overrides it; a ``--times`` key that does not
exist is one line, exit 2.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.campaign import RTest
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.campaign_reader import load_campaign, parse_campaign
from mtmcal_bayes.io.machine_reader import builtin_description, demo_campaign
from mtmcal_bayes.machine_time import TimeModel
from mtmcal_bayes.planning.rtest_catalogue import INDEXED_POSITIONS, rtest_catalogue

from .rtest_campaigns import NEST_MM, SPHERES, campaign_text, static_runs

#: an [rtest] still to plan for: a nest and the sphere's position, no run yet
PLANNED = ('\n[rtest]\ninstrument = "R-test, 3 sensors"\nrepeatability_um = 0.5\nsphere_mm = {sphere}\n\n'
           f"[rtest.nests.N1]\nlength_mm = {NEST_MM}\n")
#: the smallest fall of the sd of a deviation the best R-test run must give (its sd after / before)
MUST_FALL_TO = 0.5


def _demo_with_planned_rtest(machine: str):
    text = Path(demo_campaign(machine)).read_text(encoding="utf-8")
    return parse_campaign(text + PLANNED.format(sphere=SPHERES[machine][0]))


def _c_runs_only(machine: str):
    """The one-sphere R-test campaign's runs that index C alone (tool, first): the other axis never turns."""
    runs = [r for r in static_runs(machine, "tool", "first") if r["id"] == "C alone"]
    return parse_campaign(campaign_text(machine, runs, nests={"N1": (NEST_MM, False)}))


def _with_run(campaign, candidate):
    """``campaign`` with ``candidate``'s run added to its R-test."""
    out = copy.copy(campaign)
    one = candidate.alone(campaign).rtest
    rt = campaign.rtest
    out.rtest = RTest(rt.instrument, rt.repeatability, rt.placement_sd, rt.nest_length_sd, rt.nest_offset_sd,
                      nests={**rt.nests, **one.nests}, runs=list(rt.runs) + one.runs, sphere=rt.sphere)
    return out


@pytest.mark.parametrize("machine", ["trunnion", "head-head"])
def test_best_rtest_run_determines_what_the_campaign_leaves(machine):
    """R-test runs that turn C alone leave the other rotary axis' errors undetermined: the best R-test candidate
    turns that axis and determines one of them (docs/rtest.md says which)."""
    c = _c_runs_only(machine)
    result = mb.plan(c)
    t = result.table
    r_rows = t[t["kind"] == "rtest"]
    assert len(r_rows) and r_rows["feasible"].all()
    best = r_rows.iloc[0]
    cand = next(x for x in rtest_catalogue(c) if x.name == best["name"])
    before = campaign_identifiability(LogPosterior(c, "linear", data="rtest"))
    after = campaign_identifiability(LogPosterior(_with_run(c, cand), "linear", data="rtest"))
    gained = [d for d in after.determined if d not in before.determined and d in result.targets]
    assert gained, (best["name"], before, after)
    fall = {d: best[f"{d} sd_after"] / best[f"{d} sd_before"] for d in gained}
    assert min(fall.values()) < MUST_FALL_TO, fall
    # its minutes are the time model's: its positions indexed and read, the nest set up where no run is measured yet
    m = TimeModel()
    each = m.index_rtest_min + m.dwell_rtest_min
    expect = (0.0 if c.has_rtest_readings() else m.mount_rtest_min) + (
        cand.sweep_span / m.rotary_deg_per_min if cand.sweep_span else cand.n_positions * each)
    assert best["minutes"] == pytest.approx(expect, rel=1e-12)
    doc = result.to_json()["candidates"]
    entry = next(x for x in doc if x["name"] == best["name"])
    assert entry["minutes"] == pytest.approx(expect) and entry["rtest_run"]["angles_deg"] == cand.angles_deg()


def test_planned_rtest_on_a_demo():
    """A demo campaign with an [rtest] still to plan for (a nest and sphere_mm, no run): R-test candidates at the named
    sphere, each priced with the nest's set-up."""
    c = _demo_with_planned_rtest("vertical-turn-mill")
    result = mb.plan(c)
    r_rows = result.table[result.table["kind"] == "rtest"]
    assert len(r_rows) == len(rtest_catalogue(c)) > 0
    assert all(x.setup.sphere == tuple(SPHERES["vertical-turn-mill"][0]) for x in rtest_catalogue(c))
    assert (r_rows["minutes"] > TimeModel().mount_rtest_min).all()


def test_no_rtest_no_rtest_candidates():
    result = mb.plan(demo_campaign("trunnion"))
    assert "rtest" not in set(result.table["kind"]) and "minutes" not in result.table
    assert all("rtest_run" not in c for c in result.to_json()["candidates"])


@pytest.mark.parametrize("machine", list(SPHERES))
def test_candidates_within_travels(machine):
    """Every R-test candidate's angles lie within its axes' travels (where stated), on every built-in type."""
    runs = static_runs(machine, "tool", "first")[:1]
    c = parse_campaign(campaign_text(machine, runs, nests={"N1": (NEST_MM, False)}))
    axes = {a.letter: a for a in builtin_description(machine).rotary_axes}
    cands = rtest_catalogue(c)
    assert {x.axis for x in cands} == set(axes)
    for x in cands:
        for letter, angles in x.positions:
            lo, hi = (-np.inf, np.inf) if axes[letter].travel is None else np.rad2deg(axes[letter].travel)
            assert lo - 1e-9 <= min(angles) and max(angles) <= hi + 1e-9, (x.name, letter, angles)
        assert x.sweep_span is not None or x.n_positions == INDEXED_POSITIONS


def test_planned_run_has_a_program(tmp_path):
    """The plan's R-test run, added to the campaign as a [[rtest.runs]] table, is one ncgen --rtest writes: one block
    per position."""
    machine = "trunnion"
    c = _c_runs_only(machine)
    best = next(x for x in mb.plan(c).to_json()["candidates"] if x["kind"] == "rtest")
    run = best["rtest_run"]
    k = len(next(iter(run["angles_deg"].values())))
    runs = static_runs(machine, "tool", "first")[:1] + [
        {"id": "planned", "nest": run["nest"], "sphere": run["sphere_mm"], "angles": run["angles_deg"],
         "frame": run["frame"], "zero": run["zero"]}]
    path = tmp_path / "c.toml"
    path.write_text(campaign_text(machine, runs, nests={"N1": (NEST_MM, False)}), encoding="utf-8")
    program = mb.ncgen(campaign=str(path), rtest="planned")
    blocks = [line for line in program.splitlines() if line.startswith("G01")]
    assert len(blocks) == k


def test_times_override_and_bad_key(tmp_path, run_cli):
    c = _c_runs_only("trunnion")
    times = {"index_rtest_min": 1.0, "dwell_rtest_min": 0.5}
    t = mb.plan(c, times=times).table
    indexed = t[(t["kind"] == "rtest") & t["name"].str.contains("×")]
    assert np.allclose(indexed["minutes"], INDEXED_POSITIONS * 1.5)  # the nest is in place: no set-up
    bad = tmp_path / "times.toml"
    bad.write_text("index_rtest_mins = 1.0\n", encoding="utf-8")
    camp = tmp_path / "c.toml"
    camp.write_text(campaign_text("trunnion", static_runs("trunnion", "tool", "first")[:1],
                                  nests={"N1": (NEST_MM, False)}), encoding="utf-8")
    code, out, err = run_cli("plan", camp, "--times", bad, "-o", tmp_path / "out")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "times.toml" in err and "index_rtest_mins" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_planned_rtest_section_saves_and_loads(tmp_path):
    """A campaign's [rtest] without runs (nests and sphere_mm: an R-test to plan for) saves and loads unchanged."""
    from mtmcal_bayes.io.campaign_writer import save_campaign

    c = _demo_with_planned_rtest("vertical-turn-mill")
    assert not c.has_rtest_readings() and c.rtest.sphere is not None
    save_campaign(c, tmp_path / "c.toml")
    again = load_campaign(tmp_path / "c.toml")
    assert np.array_equal(again.rtest.sphere, c.rtest.sphere) and again.rtest.nests == c.rtest.nests
    save_campaign(again, tmp_path / "again.toml")
    assert (tmp_path / "again.toml").read_bytes() == (tmp_path / "c.toml").read_bytes()
