"""The design's exact check through the machine's kinematics (docs/design.md, "The exact check"; issue 44 item 2):
where the linear model misses the chain's readings at machines drawn from the priors, the check simulates through
the chain, says so, and its readings are the chain's predictions plus the noise the linear check draws."""

from __future__ import annotations


import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.models import build_model
from mtmcal_bayes.planning.design_chain import MISFIT_FRACTION, threshold
from mtmcal_bayes.planning.design_check import preposterior
from mtmcal_bayes.planning.design_runs import with_runs

from .machines import new_machine_runs


@pytest.fixture(scope="module")
def head_head():
    """A new head-head machine (its demo's set-ups and mounts, no runs), its planner and three designed runs."""
    return new_machine_runs("head-head", 3)


def test_the_check_goes_through_the_chain_where_the_linear_misfit_is_large(head_head):
    """At the priors' deviations the head-head chain misses its first order by more than the ball bar's accuracy on
    the designed runs: the check goes through the chain and says so; with a target the threshold is the smaller of
    the accuracy and a tenth of the target in reading units."""
    planner, runs = head_head
    goal = np.full(len(planner.targets), np.nan)
    goal[0] = 3.0
    pp = preposterior(planner, runs, n_sim=40, seed=3, targets=goal)
    k = pp.kinematics
    assert k.model == "chain" and k.through
    assert k.misfit_um > k.threshold_um
    assert k.threshold_um <= 1e3 * planner.campaign.ballbar.accuracy + 1e-12
    assert "through the chain model" in k.line()
    aug = with_runs(planner.campaign, runs, planner.as_run)
    space = planner.space_for(aug)
    A = planner.rows_for(aug, space)  # a new machine: every reading is a designed run's
    reading = np.abs(A @ planner.target_matrix(space)[0]).max() * units.to_internal(3.0, planner.target_units[0])
    expected = min(planner.campaign.ballbar.accuracy, MISFIT_FRACTION * reading)
    assert threshold(planner, A, planner.target_matrix(space), goal) == pytest.approx(expected, rel=1e-12)
    assert k.threshold_um == pytest.approx(units.from_internal(expected, "um"), abs=1e-9)


def test_the_chains_readings_are_its_predictions_plus_the_linear_checks_noise(head_head):
    """An exact property: with one seed the check through the chain draws the same machines as the linear check,
    and its readings differ from the linear check's by the chain's predictions less the rows' at those machines —
    the same noise added to the chain's means."""
    planner, runs = head_head
    chain = preposterior(planner, runs, n_sim=30, seed=5, through=True)
    linear = preposterior(planner, runs, n_sim=30, seed=5, through=False)
    assert chain.kinematics.through and not linear.kinematics.through
    np.testing.assert_array_equal(chain.truth, linear.truth)
    aug = with_runs(planner.campaign, runs, planner.as_run)
    space = planner.space_for(aug)
    A = planner.rows_for(aug, space)
    f = build_model("chain", aug, space).predict(chain.truth)
    noise = linear.readings - chain.truth @ A.T
    np.testing.assert_allclose(chain.readings, f + noise, rtol=0, atol=1e-12)
    # the chain's readings are not the rows': the misfit is there, well above rounding
    assert np.abs(chain.readings - linear.readings).max() > 1e-4
