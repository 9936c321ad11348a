"""The design's check through the kinematics with a touch-probe run (issue 44 item 2): where the first order misses
the machine's probe readings at machines drawn from the priors, the check measures the designed probe run through
the probe model of the chain, says so, and its readings are that model's readings plus the noise the linear check
draws with the same seed."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.planning.design_chain import accuracy, threshold
from mtmcal_bayes.planning.design_check import preposterior
from mtmcal_bayes.planning.design_make import design_candidates, reporting_planner
from mtmcal_bayes.planning.design_runs import designed_runs
from mtmcal_bayes.simulation.simulate import probe_readings, truth_from_vector


@pytest.fixture(scope="module")
def head_head_probe():
    """A new head-head machine (its demo's set-ups, mounts and probe, no runs of any instrument), its planner and a
    design of two ball-bar runs and one probe run (its stylus and sphere terms its own)."""
    c = copy.deepcopy(api.campaign_of(api.demo_campaign("head-head")))
    c.ballbar.runs, c.probe.runs, c.truth = [], [], None
    cands = design_candidates(c, instruments=("ballbar", "probe"))
    planner = reporting_planner(c, cands, {})
    counts = np.zeros(len(cands), dtype=int)
    counts[:2] = 1
    probe = next(k for k, x in enumerate(cands) if x.instrument == "probe")
    counts[probe] = 1
    return planner, designed_runs(cands, counts), cands[probe]


def test_a_probe_run_is_checked_through_the_chain(head_head_probe):
    """At the priors' deviations the chain misses its first order on the designed readings by more than the
    threshold: the check goes through the kinematics, says so, and holds the misfit against the smallest accuracy
    of the instruments that read the new rows (the ball bar's and the probe's)."""
    planner, runs, _ = head_head_probe
    goal = np.full(len(planner.targets), np.nan)
    goal[0] = 3.0
    pp = preposterior(planner, runs, n_sim=40, seed=3, targets=goal)
    k = pp.kinematics
    assert k.through and k.model == "chain"
    assert k.misfit_um > k.threshold_um
    c = planner.campaign
    assert k.threshold_um <= 1e3 * min(accuracy(c, "ballbar"), accuracy(c, "probe")) + 1e-12
    assert threshold(planner, np.zeros((0, 1)), np.zeros((0, 1)), None, instruments=["probe"]) == c.probe.repeatability


def test_the_probe_readings_are_the_chains_plus_the_linear_checks_noise(head_head_probe):
    """An exact property: with one seed the check through the kinematics draws the machines of the linear check,
    and its probe readings are the probe model's at each drawn machine (made by ``simulate``'s own path, a campaign
    of the probe run alone) less its nominal readings, plus the noise the linear check added to its rows."""
    planner, runs, cand = head_head_probe
    chain = preposterior(planner, runs, n_sim=12, seed=5, through=True)
    linear = preposterior(planner, runs, n_sim=12, seed=5, through=False)
    assert chain.kinematics.through and not linear.kinematics.through
    np.testing.assert_array_equal(chain.truth, linear.truth)
    one = cand.alone(planner.campaign)
    k = 3 * len(cand.positions[0][1])  # the probe run's readings: the last of the designed ones
    rows, _ = cand.rows(planner.campaign, chain.space, planner.deviations, planner.table)
    noise = linear.readings[:, -k:] - linear.truth @ rows.T
    zero = probe_readings(one, truth_from_vector(chain.space, np.zeros(len(chain.space))), "chain")
    for i in range(len(chain.truth)):
        f = probe_readings(one, truth_from_vector(chain.space, chain.truth[i]), "chain") - zero  # (k/3, 3) mm
        np.testing.assert_allclose(chain.readings[i, -k:], f.reshape(-1) + noise[i], rtol=0, atol=1e-9)
    # the chain's probe readings are not the rows': the misfit is there, well above rounding
    assert np.abs(chain.readings[:, -k:] - linear.readings[:, -k:]).max() > 1e-4
