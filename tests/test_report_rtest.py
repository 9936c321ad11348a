"""The report with R-test data (docs/report.md, docs/rtest.md): per run the readings beside the posterior
predictive with the residuals and the R-test's σ_model, its nuisance terms with units, every pair of the instruments
checked, and the sections every report has, on a campaign of R-test runs alone and beside the ball bar."""

from __future__ import annotations

import copy
import re
from html import unescape

import numpy as np
import pandas as pd
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.io.machine_reader import demo_campaign, rtest_demo_campaign
from mtmcal_bayes.simulation.simulate import synthetic_campaign

#: the sections every report with R-test readings has, whatever else the campaign holds
SECTIONS = {"machine", "determined", "results", "least-squares", "truth", "statement", "budget", "corner", "forest",
            "compensation", "rtest", "widths", "diagnostics"}


def _anchors(directory) -> tuple[set[str], str]:
    html = unescape((directory / "index.html").read_text(encoding="utf-8"))
    return set(re.findall(r'<h2 id="([^"]+)">', html)), html


@pytest.mark.parametrize("machine", ["integrex-i200"])  # the plug-in's machine; the trunnion below
def test_the_report_of_an_rtest_demo(machine, tmp_path):
    """The R-test demo's report: every section above, rtest.csv with one row per reading whose observed mean is the
    mean of the campaign's repeats (computed here from its runs) and whose residual is observed − predictive mean,
    rtest_terms.csv with every R-test nuisance term of the posterior (µm, owner, prior sd, the stated truth), the
    figure drawn; the GUM statement names the R-test's σ_model."""
    c = mb.load_campaign(rtest_demo_campaign(machine))
    rep = mb.report(c, output=tmp_path / "r", seed=1, sampler="exact")
    anchors, html = _anchors(tmp_path / "r")
    assert SECTIONS <= anchors, SECTIONS - anchors
    assert (tmp_path / "r" / "rtest.png").stat().st_size > 10_000
    t = pd.read_csv(tmp_path / "r" / "rtest.csv")
    means = np.concatenate([units.from_internal(run.displacements.mean(axis=0), "um").reshape(-1)
                            for run in c.rtest.runs])
    assert len(t) == len(means) == 3 * sum(run.positions for run in c.rtest.runs)
    assert np.allclose(t["observed_mean_um"], means, atol=1e-6)
    assert list(t["component"][:3]) == ["X", "Y", "Z"] and list(t["run"].drop_duplicates()) == [r.id for r in
                                                                                              c.rtest.runs]
    # the CSV has six significant digits: readings up to ~120 µm, so 1e-3 µm
    assert np.allclose(t["residual_um"], t["observed_mean_um"] - t["predictive_mean_um"], atol=1e-3)
    assert (t["predictive_sd_um"] > 0).all() and t["inside_95"].mean() > 0.85
    terms = pd.read_csv(tmp_path / "r" / "rtest_terms.csv")
    nuisance = [p.name for p in rep.posterior.log_posterior.space.parameters if p.group == "rtest"]
    assert list(terms["term"]) == nuisance and (terms["unit"] == "µm").all()
    placed = terms.set_index("term").loc[["xPR[S1]", "yPR[S1]", "zPR[S1]"]]
    truth = [units.from_internal(c.truth.rtest["S1"][b], "um") for b in ("xPR", "yPR", "zPR")]
    assert np.allclose(placed["truth"], truth) and (placed["prior_sd"] == 50.0).all()
    assert "σ_model (R-test)" in html or "sigma_model_rtest" in html


def test_the_report_checks_the_rtest_beside_the_ball_bar(tmp_path):
    """The trunnion demo's ball bar with the R-test demo's runs (its probe dropped), every reading simulated from the
    demo's truth, the last two positions of the first R-test run moved 30 µm along X, reported with ``data="rtest"``
    (a posterior that did not see the ball bar: no eccentricity plots of it): the pair-by-pair section flags that run
    given the ball bar's posterior, consistency_pairs.csv names it, and the compensation section refuses the disputed
    deviations."""
    c = copy.deepcopy(mb.load_campaign(demo_campaign("trunnion")))
    rt = mb.load_campaign(rtest_demo_campaign("trunnion"))
    c.probe, c.rtest = None, rt.rtest
    c.truth.rtest = rt.truth.rtest
    c = synthetic_campaign(c, c.truth, "chain", noise=True, seed=5)
    c.rtest.runs[0].displacements[:, -2:, 0] += 30 * 1e-3
    mb.report(c, output=tmp_path / "r", seed=1, sampler="exact", data="rtest")
    anchors, html = _anchors(tmp_path / "r")
    assert SECTIONS | {"pairs"} <= anchors and "polar" not in anchors
    g = pd.read_csv(tmp_path / "r" / "consistency_pairs.csv")
    first = g[g["group"] == f"R-test {c.rtest.runs[0].id}"]
    assert list(first["verdict"]) == ["disagree"] and (g.loc[g.index != first.index[0], "verdict"] == "agree").all()
    section = html[html.index('id="compensation"'):html.index('id="ppc"')]
    assert "it refuses" in section and "--accept-disagreement" in section


def test_the_report_plans_on_its_own_data(tmp_path):
    """The report's plan rests on the data of the report's posterior: on a trunnion campaign whose ball bar has its
    set-ups but no runs yet, beside R-test runs, the report completes (its plan took the ball bar's data alone and
    failed in the linear algebra) and ranks R-test candidates by the R-test's data (the same table as ``plan`` with
    the report's data: the R-test), and its page says nothing of σ_model's information, which the planner computes
    for the ball bar's data alone."""
    from mtmcal_bayes.planning.plan import plan

    c = mb.load_campaign(demo_campaign("trunnion"))
    rt = mb.load_campaign(rtest_demo_campaign("trunnion"))
    c.ballbar.runs, c.probe, c.rtest, c.truth = [], None, rt.rtest, rt.truth
    mb.report(c, output=tmp_path / "rep", sampler="exact")  # the exact draws: what is tested is the plan
    table = pd.read_csv(tmp_path / "rep" / "plan.csv")
    assert (table["kind"] == "rtest").any()
    alone = plan(c, list(table.filter(like=" sd_after").columns.str.replace(" sd_after", "")), data="rtest").table
    pd.testing.assert_series_equal(table.set_index("name")["eig_bits"].sort_index(),
                                   alone.set_index("name")["eig_bits"].sort_index(), rtol=1e-5)  # CSV: 6 digits
    _, page = _anchors(tmp_path / "rep")
    assert "What would teach σ_model" not in page
