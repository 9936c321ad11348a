"""The design's exact check draws the discrepancy scales stratified (docs/design.md, "The exact check"; issue 44
item 2): the share of machines meeting a target a design only just meets is the prior probability of the scale
below a threshold, and the check's own draws of the scale must not move it by their luck."""

from __future__ import annotations


import numpy as np
import pytest

from mtmcal_bayes.planning.design_check import preposterior

from .machines import new_machine_runs


@pytest.fixture(scope="module")
def trunnion():
    """A new trunnion (its demo's set-ups and mounts, no runs), its planner and four designed ball-bar runs."""
    return new_machine_runs("trunnion", 4)


def test_a_new_machines_scales_are_drawn_one_per_stratum_of_their_prior(trunnion):
    """An exact property: the n drawn σ_model, sorted, lie one in each of the n strata of equal prior probability
    (plain draws of 300 are off by about 1/√300 ≈ 0.06 in probability somewhere)."""
    planner, runs = trunnion
    n = 300
    pp = preposterior(planner, runs, n_sim=n, seed=4, through=False)
    u = np.sort(planner.sigma_prior().cdf(pp.scales[:, 0]))
    k = np.arange(n)
    assert np.all(u >= k / n - 1e-12) and np.all(u <= (k + 1) / n + 1e-12)

