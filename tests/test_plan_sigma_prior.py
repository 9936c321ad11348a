"""``plan``, ``design`` and ``next`` under a σ_model prior learnt elsewhere (``--sigma-model-prior``, issue 35).

The learnt prior replaces the assumed one wherever planning uses σ_model's prior: the closed form's σ_model (the rms
of the prior), the quantiles σ_model is integrated out over, the Laplace contraction's prior variance, the
Monte-Carlo checks' draws and exact posteriors, and the probe's scale when the prior names it.  σ_model's
contraction is measured against the wider of the assumed and the learnt prior (docs/design.md), so a narrow learnt
prior meets the goal before any run and the design spends no minutes on it.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.io import parse_campaign
from mtmcal_bayes.io.sigma_prior_file import write_sigma_model_prior
from mtmcal_bayes.planning.catalogue import catalogue
from mtmcal_bayes.planning.design import Planner, sigma_contraction
from mtmcal_bayes.planning.design_make import design_candidates
from mtmcal_bayes.planning.design_problem import NODE_LEVELS, PROMISE, DesignProblem
from mtmcal_bayes.planning.preposterior import realised_sd
from mtmcal_bayes.planning.probe_catalogue import probe_catalogue
from mtmcal_bayes.planning.scale_priors import learnt_notes, learnt_summary
from mtmcal_bayes.sigma_prior import SigmaModelPrior

from . import variants

SOURCE = "fleet test/: 4 machines of the type"
#: a tight learnt prior at a smaller σ_model than the assumed HalfNormal(2 µm) (rms 2 µm), and one at a larger
SMALL = SigmaModelPrior({"sigma_model": (1.0, 0.1)}, SOURCE)
LARGE = SigmaModelPrior({"sigma_model": (3.0, 0.1)}, SOURCE)
#: the Monte-Carlo check's agreement with the closed form that docs/planning.md states (and test_plan.py requires)
MC_TOLERANCE = 0.2


def _rms_um(median_um: float, log_sd: float) -> float:
    return float(np.sqrt(stats.lognorm(s=log_sd, scale=median_um).moment(2)))


@pytest.fixture(scope="module")
def no_cr2():
    return parse_campaign(variants.without_second_tool_length(), "no_cr2.toml")


@pytest.fixture(scope="module")
def new_machine(thesis):
    """The thesis machine before any run: its set-ups and mounts only."""
    from mtmcal_bayes.campaign import Probe

    c = copy.deepcopy(thesis)
    c.ballbar.runs, c.probe, c.reported, c.truth = [], Probe(), {}, None
    return c


# --------------------------------------------------------------------------- plan
def test_plan_sds_follow_the_learnt_prior_and_the_monte_carlo_check_agrees(no_cr2):
    """A learnt prior at a smaller σ_model narrows every expected sd the candidates bring, one at a larger widens it;
    under each, the exact Monte-Carlo preposterior (σ_model drawn from and learnt under the learnt prior) agrees with
    the closed form within the stated tolerance — and is the learnt prior's, not the assumed one's."""
    targets = ["alpha_BT", "dy_CZ", "beta_XB"]
    cands = [c for c in catalogue(no_cr2) if c.name in ("CR @ R_B+150 mm", "CR @ R_B+25 mm", "BZ @ RB1")]
    planners = {name: Planner(no_cr2, cands, targets, sigma_prior=p)
                for name, p in (("small", SMALL), ("assumed", None), ("large", LARGE))}
    for name, prior in (("small", SMALL), ("large", LARGE)):
        assert units.from_internal(planners[name].sigma_model, "um") == pytest.approx(_rms_um(*prior.scales[
            "sigma_model"]), rel=1e-9)
    ev = {name: pl.evaluate() for name, pl in planners.items()}
    moved = ev["assumed"].sd_after < 0.99 * ev["assumed"].sd_before  # what the candidates inform
    assert moved.sum() >= 5
    assert np.all(ev["small"].sd_after[moved] < 0.95 * ev["assumed"].sd_after[moved])
    assert np.all(ev["large"].sd_after[moved] > 1.05 * ev["assumed"].sd_after[moved])
    assert np.all(ev["small"].sd_before <= ev["assumed"].sd_before) and \
        np.all(ev["assumed"].sd_before <= ev["large"].sd_before)
    for name in ("small", "large"):
        for k in range(len(cands)):
            mc = realised_sd(planners[name], k, n_sim=200, seed=k)
            ratio = mc["sd_realised"] / ev[name].sd_after[k]
            assert np.all(np.abs(ratio - 1) < MC_TOLERANCE), (name, cands[k].name, ratio)
            # the realised sds are the learnt prior's: nearer its closed form than the assumed prior's
            assert np.all(np.abs(mc["sd_realised"] - ev[name].sd_after[k])[moved[k]]
                          < np.abs(mc["sd_realised"] - ev["assumed"].sd_after[k])[moved[k]])
    fixed = Planner(no_cr2, [], targets, sigma_model=units.to_internal(1.5, "um"), sigma_prior=LARGE)
    assert fixed.sigma_model == units.to_internal(1.5, "um")  # a fixed σ_model of the closed form still wins
    assert fixed.sigma_prior().median() == pytest.approx(units.to_internal(3.0, "um"))


def test_the_probes_scale_follows_the_learnt_prior_when_it_names_it(thesis):
    both = SigmaModelPrior({"sigma_model": (1.0, 0.1), "sigma_model_probe": (0.5, 0.2)}, SOURCE)
    probe = probe_catalogue(thesis)[:1]
    assert probe
    assumed, ball_only, learnt = (Planner(thesis, probe, sigma_prior=p) for p in (None, SMALL, both))
    assert ball_only.sigma_probe == assumed.sigma_probe  # a scale the file does not give keeps its assumed prior
    assert units.from_internal(learnt.sigma_probe, "um") == pytest.approx(_rms_um(0.5, 0.2), rel=1e-9)
    w_assumed, w_learnt = assumed.candidate_rows()[0][1], learnt.candidate_rows()[0][1]
    assert np.all(w_learnt > w_assumed)  # the readings weigh more under the smaller learnt scale
    assert sum("σ_model (probe) prior: learnt elsewhere" in n for n in learnt_notes(thesis, both, "x")) == 1


# --------------------------------------------------------------------------- design and next
def test_a_tight_learnt_prior_saves_the_runs_the_contraction_needed(new_machine):
    """From nothing, with a loose target (δy_CZ ≤ 20 µm), σ_model's contraction ≥ 0.5 adds a run to the design
    (fewer minutes without that goal).  Under a tight learnt prior σ_model is known before any run: the contraction, measured
    against the (wider) assumed prior's variance, is met already, the design takes strictly fewer minutes, says why, and
    still keeps its promise for the target."""
    tg = {"dy_CZ": 20.0}
    assumed = mb.design(new_machine, targets=tg).design
    no_goal = mb.design(new_machine, targets=tg, contraction=None).design
    learnt = mb.design(new_machine, targets=tg, sigma_model_prior=SMALL).design
    assert no_goal.total_minutes < assumed.total_minutes  # the contraction drove part of the design
    assert learnt.total_minutes < assumed.total_minutes
    assert any("contraction target 0.5 is met before any run" in n for n in learnt.notes), learnt.notes
    assert any(n.startswith("σ_model (ball bar) prior: learnt elsewhere, LogNormal(median 1 µm, log sd 0.1), from "
                            + SOURCE) for n in learnt.notes)
    assert not any("learnt" in n for n in assumed.notes)
    assert learnt.check.contraction.mean() >= 0.5 and learnt.check.contraction_now >= 0.5
    assert assumed.check.contraction_now == 0.0
    met = learnt.check.share_met(learnt.goal.targets)
    assert met[learnt.targets.index("dy_CZ")] >= PROMISE


def test_sigma_model_is_integrated_out_over_the_learnt_prior(new_machine, thesis):
    """σ_model's nodes are the quantiles of the prior in use (a new machine) or of its exact posterior under that
    prior (the thesis runs); under a learnt prior the contraction's reference is the wider of the assumed and the
    learnt prior's variance (without one, the prior's own: the contraction as it was)."""
    cands = design_candidates(new_machine)[:4]
    assumed, learnt = (DesignProblem(Planner(new_machine, cands, sigma_prior=p)) for p in (None, SMALL))
    mm = units.to_internal(1.0, "um")
    np.testing.assert_allclose(assumed.nodes, stats.halfnorm(scale=2 * mm).ppf(NODE_LEVELS), rtol=1e-12)
    np.testing.assert_allclose(learnt.nodes, stats.lognorm(s=0.1, scale=mm).ppf(NODE_LEVELS), rtol=1e-12)
    assert assumed.sigma_reference_var is None
    assert learnt.sigma_reference_var == pytest.approx(stats.halfnorm(scale=2 * mm).var(), rel=1e-12)
    assert learnt.value_now().contraction[0] == pytest.approx(
        1 - stats.lognorm(s=0.1, scale=mm).var() / learnt.sigma_reference_var, rel=1e-9)
    # a learnt prior wider than the assumed one is the reference itself: the ordinary contraction, 0 before any run
    wide = Planner(new_machine, cands, sigma_prior=SigmaModelPrior({"sigma_model": (2.7, 0.5)}, SOURCE))
    assert wide.contraction_reference() == pytest.approx(stats.lognorm(s=0.5, scale=2.7 * mm).var(), rel=1e-12)
    assert learnt_summary(new_machine, wide.learnt)["contraction_reference"]["which"] == "learnt"
    assert DesignProblem(wide).value_now().contraction[0] == pytest.approx(0.0, abs=1e-12)
    assert learnt_summary(new_machine, SMALL)["contraction_reference"]["which"] == "assumed"
    measured = DesignProblem(Planner(thesis, design_candidates(thesis)[:4], sigma_prior=LARGE)).nodes
    assert np.all(np.diff(measured) > 0)
    assert stats.lognorm(s=0.1, scale=3 * mm).ppf(0.001) < measured[0] and \
        measured[-1] < stats.lognorm(s=0.1, scale=3 * mm).ppf(0.999)  # the tight prior dominates the thesis data
    # the reference reduces to the prior's own variance: the contraction without a learnt prior is the old one
    f = np.array([0.0, 1e5, 3e6])
    np.testing.assert_allclose(sigma_contraction(f, 1.4e-6, 1.4e-6), sigma_contraction(f, 1.4e-6), atol=1e-12)


def test_the_commands_take_the_prior_and_name_its_source(run_cli, tmp_path):
    """plan, design and next with --sigma-model-prior: the learnt prior and its source in the JSON and the text; on
    the thesis campaign (whose design without it is a BA run for σ_model alone) the design is empty and next stops."""
    path = tmp_path / "prior.toml"
    write_sigma_model_prior(path, SMALL)
    code, out, err = run_cli("design", "--sigma-model-prior", path, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["runs"] == [] and doc["total_minutes"] == 0
    sig = doc["sigma_model"]
    assert sig["prior"] == "LogNormal(median 1 µm, log sd 0.1)" and sig["prior_source"]["from"] == SOURCE
    assert sig["contraction_reference"]["prior"] == "HalfNormal(2 µm)"
    assert sig["contraction_before"] >= sig["target"] == 0.5
    code, out, err = run_cli("design", "--sigma-model-prior", path)
    assert code == 0 and "against the assumed prior HalfNormal(2 µm)" in out and SOURCE in out, err
    code, out, err = run_cli("next", "--sigma-model-prior", path, "--json")
    assert code == 0, err
    nxt = json.loads(out)
    assert nxt["status"] == "stop" and nxt["sigma_model"]["prior_source"]["from"] == SOURCE
    code, out, err = run_cli("plan", "--sigma-model-prior", path, "--json")
    assert code == 0, err
    plan = json.loads(out)
    info = plan["sigma_model_information"]
    assert info["prior"] == "LogNormal(median 1 µm, log sd 0.1)" and info["prior_source"]["from"] == SOURCE
    assert plan["sigma_model_um"] == pytest.approx(_rms_um(1.0, 0.1))
    assert any(SOURCE in n for n in plan["notes"])
    # the learnt prior meets the contraction before any run: 0 runs needed, in the JSON as in the text
    assert info["contraction_now"] >= 0.5
    assert {c["sigma_model_runs_needed"] for c in plan["candidates"] if c["feasible"]} == {0}


def test_the_reports_plan_is_made_under_the_posteriors_learnt_prior(thesis, tmp_path, monkeypatch):
    """The report plans beside its sampling (build._ahead) and again for unidentified quantities (build._planning):
    both under the learnt prior of the posterior it reports, and on its data (the thesis machine's: the ball bar)."""
    from mtmcal_bayes.analysis import analysis_of
    from mtmcal_bayes.reporting import build
    from mtmcal_bayes.reporting.drawing import Drawing

    seen = []
    monkeypatch.setattr(build, "_plan_and_figures",
                        lambda campaign, directory, targets=None, sigma_prior=None, data=None:
                        (seen.append((sigma_prior, data)), None))
    drawing = Drawing(tmp_path, workers=1)  # drawn here: the job's arguments are seen by this process
    build._ahead(analysis_of(thesis, sigma_prior=SMALL), drawing, say=lambda text: None)
    assert seen == [(SMALL, "ballbar")]
    monkeypatch.setattr(build, "plan", lambda campaign, targets, sigma_prior=None, data=None:
                        seen.append((sigma_prior, data)))
    post = mb.sample(parse_campaign(variants.without_second_tool_length()), seed=1, sampler="exact",
                     sigma_model_prior=SMALL)
    build._planning(post.log_posterior.campaign, post, drawing, batch=0, say=lambda text: None,
                    listed=list(mb.IDENTIFIABLE), planned_for=[])  # not the plan begun ahead: planned again
    assert seen == [(SMALL, "ballbar"), (SMALL, "ballbar")]


def test_a_design_without_runs_is_written_whole_and_replaces_an_earlier_one(run_cli, tmp_path, monkeypatch):
    """design -o: the thesis campaign's ball-bar design (one BA run for σ_model; ``--instruments ballbar``: with the
    probe the design is a probe run) and then, into the same folder, its design under a tight learnt prior (no run):
    every file written, the earlier run's program gone, the timeline saying why it is empty; a design that fails
    while writing leaves the folder as it was (the ball-bar design again, whose run and program would differ from
    what the folder holds: a write begun in place would show)."""
    from mtmcal_bayes.planning import design_figures
    from mtmcal_bayes.io.campaign_reader import load_campaign
    from mtmcal_bayes.planning.machine_kit import kit_of

    out, prior = tmp_path / "design", tmp_path / "prior.toml"
    write_sigma_model_prior(prior, SMALL)
    code, text, err = run_cli("design", "-o", out, "--instruments", "ballbar")
    assert code == 0, err
    first = json.loads((out / "design.json").read_text())
    assert [p.name for p in (out / "programs").iterdir()] == [r["program"].split("/")[-1] for r in first["runs"]]
    # the columns an empty design's table has too: the thesis campaign format's lever arms
    assert first["runs"] and list(first["runs"][0]) == kit_of(load_campaign(None)).run_columns
    assert {"Z_T_mm", "R_C_mm"} <= set(first["runs"][0])
    code, text, err = run_cli("design", "-o", out, "--sigma-model-prior", prior)
    assert code == 0, err
    doc = json.loads((out / "design.json").read_text())
    assert doc["runs"] == [] and not any((out / "programs").iterdir())
    assert {"design.json", "campaign.toml", "design.html", "design_timeline.png", "design_sd.png"} <= \
        {p.name for p in out.iterdir()}
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}

    def broken(*args, **kwargs):
        raise RuntimeError("simulated failure while drawing")

    monkeypatch.setattr(design_figures, "sd_figure", broken)
    code, text, err = run_cli("design", "-o", out, "--instruments", "ballbar")
    assert code == 1 and "simulated failure" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design", "prior.toml"]  # no temporary folder left
