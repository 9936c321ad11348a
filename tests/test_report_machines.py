"""One report for every machine (SPEC §8, §19, §20): on each built-in type every section the campaign and its machine
have what it needs for is in the report, with its CSV; ``--compare-models`` and ``posterior=`` on a described machine.

One report per type, shared by the whole test run (conftest.thesis_report_run, conftest.demo_report); exact draws of
the linear model keep the demos' quick.
"""

from __future__ import annotations

import re
from html import unescape

import numpy as np
import pandas as pd
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.iso import iso_symbol
from mtmcal_bayes.machines.plugins import provided
from mtmcal_bayes.models import models_of
from mtmcal_bayes.sigma_prior import SigmaModelPrior
from tests.conftest import DEMO_REPORT_TOLERANCES, SHARED_REPORT_TOLERANCES

TYPES = ("thesis", "trunnion", "vertical-turn-mill", "head-head")
#: a determined quantity's posterior mean lies within this many posterior sd of the demo's stated truth (seeded;
#: 3 sd leaves a 0.3 % chance per quantity of a false alarm)
Z_MAX = 3.0


def _campaign(machine: str):
    return mb.load_campaign() if machine == "thesis" else mb.load_campaign(demo_campaign(machine))


@pytest.fixture
def reports(request, demo_report):
    """``reports(type)`` → ``(campaign, directory, stdout, toleranced)``: the shared report of the thesis campaign
    (conftest.thesis_report_run) or of a demo (conftest.demo_report: exact draws, seed 1), each with tolerances on
    some of its quantities (``toleranced``: their ISO symbols) so that the conformity section has verdicts.  Made
    when first asked for, so that the workers of ``pytest -n`` make different ones at once."""

    def get(machine: str):
        thesis = machine == "thesis"
        rep, stdout = request.getfixturevalue("thesis_report_run") if thesis else demo_report(machine)
        text = SHARED_REPORT_TOLERANCES if thesis else DEMO_REPORT_TOLERANCES[machine]
        names = (line.split("=")[0].strip().rsplit("_", 1)[0] for line in text.splitlines()[1:] if line)
        toleranced = {iso_symbol(n) or n for n in names}  # a thesis name given: its ISO symbol
        return _campaign(machine), rep, stdout, toleranced

    return get


def _expected(campaign) -> tuple[set[str], set[str]]:
    """The sections (anchors) and CSVs a report of ``campaign`` must have, from what the campaign and its machine
    provide."""
    sections = {"machine", "determined", "results", "least-squares", "statement", "conformity", "budget", "corner",
                "forest", "compensation", "ppc", "widths", "plan", "diagnostics"}  # the machine, its Jacobian, the
    # least squares: on every one
    csvs = {"summary.csv", "loo.csv", "diagnostics.csv", "priors.csv", "budget.csv", "plan.csv", "identifiability.csv",
            "combinations.csv", "least_squares.csv"}
    if campaign.ballbar.runs:
        sections |= {"polar"}
        csvs |= {"ppc.csv"}
    if campaign.ballbar.runs and campaign.has_probe_readings() and campaign.probe_gap() is None:
        sections |= {"instruments"}
        csvs |= {"instruments.csv", "consistency.csv", "consistency_readings.csv"}
    if provided(campaign.machine, "identify") is not None:  # the plug-in's deterministic identification
        sections |= {"thesis"}
        csvs |= {"identification_ballbar.csv", "thesis_assumption_dx_BT.csv"}
    if campaign.truth is not None:
        sections |= {"truth"}
        csvs |= {"truth.csv"}
    return sections, csvs


@pytest.mark.parametrize("machine", TYPES)
def test_every_section_the_machine_supports(reports, machine):
    """Each section the campaign has what it needs for is on the page, each CSV written and named in the file list,
    each figure the page shows exists; the instruments, the plan, the compensation, the polar trajectories and the
    widths are on every built-in type (each demo has both instruments)."""
    campaign, rep, stdout, _ = reports(machine)
    html = unescape((rep / "index.html").read_text(encoding="utf-8"))
    anchors = set(re.findall(r'<h2 id="([^"]+)">', html))
    sections, csvs = _expected(campaign)
    assert {"instruments", "plan", "compensation", "polar", "widths", "conformity"} <= sections
    assert sections <= anchors, sections - anchors
    for name in csvs:
        assert (rep / name).stat().st_size > 0, name
        assert name in stdout, name
    for png in re.findall(r"<strong>([\w.-]+\.png)\.</strong>", html):
        assert (rep / png).stat().st_size > 10_000, png
    text = re.sub(r"<img[^>]*>", "", html)
    assert not re.search(r"\bnan\b", text, re.IGNORECASE)


@pytest.mark.parametrize("machine", TYPES)
def test_the_deterministic_values_beside_the_posterior(reports, machine):
    """The deterministic values beside the posterior: the least squares of what the campaign determines on every
    machine (each deviation the report's identifiability.csv determines one by one), and the thesis' ball-bar values
    on the thesis machine; on a described one the least squares agree with the posterior (weak priors: a fraction of
    a sd) on what the campaign determines, and the demo's stated truth lies within Z_MAX sd of the posterior."""
    campaign, rep, _, _ = reports(machine)
    s = pd.read_csv(rep / "summary.csv", index_col="quantity")
    ls = pd.read_csv(rep / "least_squares.csv").set_index("quantity")
    ident = pd.read_csv(rep / "identifiability.csv")
    assert set(ident.loc[ident["kind"] == "determined", "quantity"]) <= set(ls.index)
    assert (ls["u"] > 0).all()
    if provided(campaign.machine, "identify") is not None:
        assert s["ballbar"].notna().sum() >= 6
        return
    html = unescape((rep / "index.html").read_text(encoding="utf-8"))
    text = (rep / "combinations.csv").read_text(encoding="utf-8")  # empty (no header) where there is none, as
    names = pd.read_csv(rep / "combinations.csv")["name"] if text.strip() else []  # on the demos' computed defaults
    assert all(name in html for name in names)  # what the campaign determines only in combination
    assert "Eqs 4.10" not in html  # no thesis number on a described machine
    determined = [n for n in ls.index if n in s.index]
    assert determined
    assert (np.abs(ls.loc[determined, "estimate"] - s.loc[determined, "mean"]) <= 0.5 * s.loc[determined, "sd"]).all()
    truth = pd.read_csv(rep / "truth.csv")
    assert (np.abs(truth["z"]) <= Z_MAX).all(), truth


@pytest.mark.parametrize("machine", TYPES)
def test_the_conformity_verdict_is_tabulated(reports, machine):
    """A verdict for each quantity given a tolerance (by its ISO symbol, or its alias on the thesis machine), and
    for no other."""
    _, rep, _, toleranced = reports(machine)
    s = pd.read_csv(rep / "summary.csv", index_col="quantity")
    assert set(s["conformity"].dropna()) <= {"conforms", "does not conform", "undecided", "not determined by the data"}
    judged = {iso_symbol(q) or q for q in s.index[s["conformity"].notna()]}
    assert judged == toleranced


def test_compare_models_on_a_described_machine(demo_report):
    """``--compare-models`` on a described machine (the trunnion's shared report, conftest.DEMO_REPORT_COMPARES):
    its two models (linear, chain) side by side, for every deviation, with their fit to the ball bar; the chain's
    first order is the linear model, so on a demo simulated at small deviations their means agree within a
    fraction of a sd."""
    c = mb.load_campaign(demo_campaign("trunnion"))
    rep, _ = demo_report("trunnion")
    for name in ("compare_forest.png", "compare_ppc.png", "compare_models.csv", "compare_fit.csv"):
        assert (rep / name).stat().st_size > 0, name
    table = pd.read_csv(rep / "compare_models.csv")
    assert set(table["model"]) == set(models_of(c.machine)) == {"linear", "chain"}
    deviations = pd.read_csv(rep / "summary.csv", index_col="quantity").index.drop(["sigma_model", "sigma_model_probe"])
    assert set(table["quantity"]) == set(deviations)
    m = table.set_index(["quantity", "model"])
    for q in deviations:
        assert abs(m.loc[(q, "chain"), "mean"] - m.loc[(q, "linear"), "mean"]) <= 0.2 * m.loc[(q, "linear"), "sd"], q
    fit = pd.read_csv(rep / "compare_fit.csv", index_col="model")
    assert set(fit.index) == {"linear", "chain"}
    html = unescape((rep / "index.html").read_text(encoding="utf-8"))
    assert '<h2 id="models">' in html


def test_a_described_machine_report_reuses_a_given_posterior(tmp_path):
    """``report(posterior=...)`` on a described machine: the report is of that posterior (same draws, not sampled
    again), its summary the posterior's own."""
    c = mb.load_campaign(demo_campaign("head-head"))
    post = mb.sample(c, sampler="exact", seed=3)
    rep = mb.report(c, output=tmp_path / "rep", posterior=post)
    assert rep.posterior is post
    s = pd.read_csv(tmp_path / "rep" / "summary.csv", index_col="quantity")
    for col in ("mean", "sd", "hdi_low", "hdi_high"):
        np.testing.assert_allclose(s[col], post.summary.loc[s.index, col], rtol=1e-5, atol=1e-9)
    import arviz as az

    written = az.from_netcdf(tmp_path / "rep" / "posterior.nc")
    q = s.index[0]
    np.testing.assert_array_equal(np.asarray(written.posterior[q]), np.asarray(post.idata.posterior[q]))


#: the σ_model prior learnt elsewhere that the shifted trunnion's report is made under (:func:`shifted_report`)
LEARNT = SigmaModelPrior({"sigma_model": (1.0, 0.1)}, "fleet of test trunnions")


@pytest.fixture(scope="module")
def shifted_report(tmp_path_factory):
    """``(report, directory)``: one report (exact draws, seed 1) of the trunnion demo with one group of probed
    positions (A = −30°) moved 60 µm along Z, under the learnt σ_model prior :data:`LEARNT`, read by the two tests
    below (read only; one report where each made its own): the learnt prior is the ball bar's σ_model's alone, so
    the probe's 60 µm conflict stays a conflict under it (its test checks the verdict), and a prior learnt elsewhere
    is taken the same whether or not the instruments agree."""
    import ast

    text = open(demo_campaign("trunnion"), encoding="utf-8").read()
    line = next(ln for ln in text.splitlines() if ln.startswith("centres_mm = "))
    centres = ast.literal_eval(line.split("=", 1)[1].strip())
    for repeat in centres:
        for i in range(4, 8):  # the positions at A = −30°
            repeat[i][2] += 0.060
    folder = tmp_path_factory.mktemp("shifted")
    path = folder / "shifted.toml"
    path.write_text(text.replace(line, "centres_mm = " + repr(centres)), encoding="utf-8")
    return mb.report(path, output=folder / "rep", sigma_model_prior=LEARNT, sampler="exact", seed=1), folder / "rep"


def test_a_described_machine_report_takes_a_learnt_sigma_model_prior(shifted_report):
    """``report(sigma_model_prior=...)`` on a described machine (the shifted trunnion's shared report): every
    posterior of the report (the main one and the instruments' side posteriors) is sampled under the learnt prior,
    and the budget names its source."""
    rep, out = shifted_report
    assert rep.posterior.log_posterior.sigma_prior == LEARNT
    priors = pd.read_csv(out / "priors.csv", index_col="parameter")
    assert "fleet of test trunnions" in priors.loc["sigma_model", "reason"]
    html = unescape((out / "index.html").read_text(encoding="utf-8"))
    assert "fleet of test trunnions" in html.split('<h2 id="budget">')[1].split("<h2")[0]


def test_a_probe_only_campaign_gets_the_sections_it_has_what_they_need_for(tmp_path):
    """A described campaign with touch-probe runs and no ball bar (the trunnion demo without its [ballbar]): the
    report is written without the sections that need ball-bar runs (trajectories, predictive check of
    eccentricities, the instruments side by side) or a ball-bar set-up (the planner's catalogue), and says why."""
    from tests.variants import probe_only

    path = tmp_path / "probe_only.toml"
    path.write_text(probe_only(open(demo_campaign("trunnion"), encoding="utf-8").read()), encoding="utf-8")
    c = mb.load_campaign(path)
    assert not c.ballbar.runs and c.has_probe_readings()
    rep = mb.report(c, output=tmp_path / "rep", sampler="exact", seed=1)
    html = unescape((tmp_path / "rep" / "index.html").read_text(encoding="utf-8"))
    anchors = set(re.findall(r'<h2 id="([^"]+)">', html))
    assert {"machine", "determined", "results", "least-squares", "budget", "corner", "forest", "widths"} <= anchors
    assert not anchors & {"polar", "instruments", "plan"}
    assert not any((tmp_path / "rep" / f).exists() for f in ("ppc.csv", "polar.png", "plan.csv", "instruments.csv"))
    assert any("No ball-bar runs" in m for m in rep.missing) and any("No ball-bar set-up" in m for m in rep.missing)


def test_a_described_campaign_whose_probe_disagrees_gets_the_explanations(shifted_report):
    """The trunnion demo with one group of probed positions (A = −30°) moved 60 µm along Z (the shared report):
    the consistency check finds the disagreement, and the report then weighs the explanations of the conflict
    (begun only once the comparison finds it: the runs read as the thesis reads them) and shows them."""
    rep, out = shifted_report
    verdicts = pd.read_csv(out / "consistency.csv").set_index("given")["verdict"]
    assert (verdicts == "disagree").any()
    assert "explanations.csv" in rep.files and len(pd.read_csv(out / "explanations.csv")) > 1
    html = unescape((out / "index.html").read_text(encoding="utf-8"))
    assert "Where a conflict could come from" in html
