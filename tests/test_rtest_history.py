"""Histories and fleets with R-test data (docs/history.md, docs/fleet.md, docs/rtest.md).

A history of three simulated campaigns of R-test runs alone recovers a stated step of a deviation the runs determine
(each date within 3 posterior sd of the truth, the step flagged at its date and nowhere else), with the R-test's own
discrepancy scale and each campaign's own R-test nuisance terms; a history mixing the ball bar and the R-test
samples one scale per instrument, and its grid likelihood of the ball bar's σ_model (the fleet's pooling) equals
the marginal likelihood integrated over the R-test's scale; a fleet with one R-test machine runs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.histories.model import HistoryModel
from mtmcal_bayes.io.campaign_reader import parse_campaign

from .rtest_campaigns import NEST_MM, campaign_text, static_runs, with_every_instrument_text

MACHINE = "trunnion"
#: the stated step: E_B0C, which the trunnion's R-test runs determine (docs/rtest.md), 40″ from the third campaign
STEP_Q, STEP = "E_B0C", 40.0
#: a history's value within this many posterior sd of the truth
WITHIN_SD = 3.0


def _rtest_campaign():
    """The trunnion's one-sphere R-test runs that turn one axis alone (A, then C): tool frame, zeroed at the first."""
    runs = [r for r in static_runs(MACHINE, "tool", "first") if r["id"].endswith("alone")]
    return parse_campaign(campaign_text(MACHINE, runs, nests={"N1": (NEST_MM, False)}))


@pytest.fixture(scope="module")
def rtest_history():
    return api.simulate_history(_rtest_campaign(), truth=Truth({}), n=3, steps=[f"{STEP_Q}={STEP:g}@3"],
                                serial="R-1", seed=3)


def test_history_of_rtest_campaigns_recovers_a_step(rtest_history):
    assert all(c.has_rtest_readings() and not c.ballbar.runs for c in rtest_history)
    r = api.history(list(rtest_history), trend="off")
    hm = r.fit.model
    assert hm.scales == ("sigma_model_rtest",)
    # each campaign its own R-test terms (zeros, placement, nest), integrated with their priors
    assert all({p.group for p in post.space.parameters} == {"deviation", "rtest"} for post in hm.posts)
    row = r.summary.xs(STEP_Q, level="quantity")
    truth = np.array([0.0, 0.0, STEP])
    assert np.all(np.abs(row["mean"].to_numpy() - truth) < WITHIN_SD * row["sd"].to_numpy()), row
    flagged = [(c["quantity"], c["date"]) for c in r.changes if c["flagged"]]
    assert flagged == [(STEP_Q, r.dates[2])]
    doc = r.to_json()["sigma_model"]
    assert doc["scale"] == "sigma_model_rtest" and set(doc["scales"]) == {"sigma_model_rtest"}


def test_every_instrument_one_scale_each_and_the_grid_integrates_the_others():
    """The trunnion's demo (ball bar and probe) with R-test runs: three scales, the ball bar's first; the grid of the
    ball bar's σ_model integrates the others over their priors, which the marginal likelihood at the grid's
    nodes, averaged, reproduces."""
    c = parse_campaign(with_every_instrument_text(MACHINE))
    hist = api.simulate_history(c, truth=Truth({}), n=2, serial="E-1", seed=5)
    hm = HistoryModel(list(hist))
    assert hm.scales == ("sigma_model", "sigma_model_probe", "sigma_model_rtest")
    q2 = np.full((1, hm.d), 1e-8)
    s2 = np.array([1e-6, 4e-6])
    grid = hm.log_marginal_grid(q2, s2)  # (1, 2)
    nodes = [p.frozen().ppf((np.arange(8) + 0.5) / 8) ** 2 for p in hm.sigma_priors[1:]]
    others = np.stack(np.meshgrid(*nodes, indexing="ij"), axis=-1).reshape(-1, 2)
    for g, first in enumerate(s2):
        full = np.column_stack([np.full(len(others), first), others])
        direct = hm.log_marginal(np.repeat(q2, len(others), axis=0), full)
        assert grid[0, g] == pytest.approx(np.logaddexp.reduce(direct) - math.log(len(others)), rel=1e-9)


def test_fleet_with_an_rtest_machine(rtest_history, tmp_path):
    root = tmp_path / "plant"
    api.simulate_history(_rtest_campaign(), truth=Truth({}), n=2, steps=[f"{STEP_Q}={STEP:g}@2"], serial="R-2",
                         seed=4, output=root / "R-2", machine_type="RT")
    result = api.fleet(root, workers=1, sampler="exact", output=tmp_path / "out")
    doc = result.to_json()
    assert not doc.get("errors"), doc.get("errors")
    (machine,) = doc["machines"]
    assert machine["serial"] == "R-2"
