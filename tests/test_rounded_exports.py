"""Readings exported rounded coarser than their scatter (every repeat equal): the probe's and the R-test's pooled
noise rule takes the stated repeatability as the floor of a zero pooled scatter (docs/probe.md, "Noise"), so
``identify`` and ``sample`` run where a zero noise variance made the least squares fail (LinAlgError)."""

from __future__ import annotations

import copy

import numpy as np

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.models.probe import ProbeLayout
from mtmcal_bayes.models.rtest import RTestLayout

from .rtest_campaigns import static_campaign


def _flat_probe():
    """The trunnion demo with each probe position's repeats replaced by their mean (a rounded export)."""
    c = copy.deepcopy(mb.load_campaign(demo_campaign("trunnion")))
    for run in c.probe.runs:
        run.centres[:] = run.centres.mean(axis=0, keepdims=True)
    return c


def test_equal_probe_repeats_take_the_stated_repeatability():
    c = _flat_probe()
    obs = ProbeLayout(c).observations
    r = c.probe.runs[0].centres.shape[0]
    assert np.allclose(obs.base_var, c.probe.repeatability**2 / r, rtol=1e-12)
    ls = mb.identify(c)  # the least squares at σ_model = 0: a zero noise variance made it fail
    assert np.isfinite(ls.least_squares.estimates.table["u"]).all()


def test_equal_rtest_repeats_take_the_stated_repeatability():
    """A one-sphere static R-test campaign of two repeats, each repeat the same simulated reading: the noise is the
    stated repeatability over the repeats, and the least squares run."""
    base = static_campaign("trunnion")
    truth = mb.load_campaign(demo_campaign("trunnion")).truth  # its deviations; the R-test terms at zero
    sim = mb.simulate(base, truth=truth, model="chain", noise=True, seed=3).synthetic_campaign()
    c = copy.deepcopy(sim)
    for run in c.rtest.runs:
        run.displacements = np.repeat(run.displacements[:1], 2, axis=0)
    obs = RTestLayout(c).observations
    assert np.allclose(obs.base_var, c.rtest.repeatability**2 / 2, rtol=1e-12)
    assert units.from_internal(np.sqrt(obs.base_var[0]), "um") > 0.3
    ls = mb.identify(c)
    assert np.isfinite(ls.least_squares.estimates.table["u"]).all()
