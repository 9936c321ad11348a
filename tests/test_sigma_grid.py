"""The exact σ-marginal posterior's grid where the data put a discrepancy scale near 0 (an instrument simulated
without discrepancy): its moments against a grid 32 times finer over the same range (inference/marginal.py).

With R-test data alone (one scale) the grid spanned the prior's range (0–8.8 µm in 128 cells) whatever the data, so
a posterior of 0.06 ± 0.04 µm lay within two cells and its midpoint moments were 6–8 % off, and ``sample --data
rtest`` warned "do not trust this run" against a reference that was itself off."""

from __future__ import annotations

import numpy as np

import mtmcal_bayes as mb
from mtmcal_bayes.analysis import analysis_of
from mtmcal_bayes.inference.marginal import GRID, MarginalPosterior
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.machine_reader import demo_campaign

from .rtest_campaigns import every_setting_text


def test_a_scale_near_zero_has_its_moments_to_a_percent_of_its_sd():
    base = parse_campaign(every_setting_text("trunnion"))
    truth = mb.load_campaign(demo_campaign("trunnion")).truth  # no discrepancy in the simulation
    c = mb.simulate(base, truth=truth, model="chain", noise=True, seed=1).synthetic_campaign()
    approx = analysis_of(c, model="linear", data="rtest").approximation
    post, grid = approx.post, approx.marginal
    y = post.likelihood.y
    mean, sd = grid.sigma_moments(y)
    priors = post.priors.priors[:post.p]
    fine = MarginalPosterior(grid.A, post.likelihood.base_var, np.array([q.sd for q in priors]) ** 2,
                             [q.frozen() for q in post.priors.priors[post.p:]],
                             prior_mean=np.array([q.mean for q in priors]), groups=post.scale_of,
                             sigma_min=[0.0], sigma_max=[grid.edges[0][-1]], cells=32 * GRID)
    ref_mean, ref_sd = fine.sigma_moments(y)
    assert ref_mean[0] < ref_sd[0] * 2  # near the boundary: the case at issue
    assert abs(mean[0] - ref_mean[0]) < 0.01 * ref_sd[0] and abs(sd[0] / ref_sd[0] - 1) < 0.01, (mean, sd, ref_mean,
                                                                                                  ref_sd)
