"""Every planning command on each described built-in type's demo campaign, one number each checked against the
exact answer (issue 37, acceptance): ``plan`` (today's sd: the Gaussian posterior at its σ_model, computed here from
the linear model's own design), ``design`` and ``next`` (today's sd: the exact σ-marginal posterior, against
``sample --sampler exact``), ``ncgen`` (every block of the program, against kinematics written out in the test)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mtmcal_bayes import api, units
from mtmcal_bayes.inference.likelihood import GaussianMeanLikelihood
from mtmcal_bayes.inference.priors import make_prior
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines.deviations import quantities
from mtmcal_bayes.models import make_model

from .handchain import HandMachine

TYPES = ("vertical-turn-mill", "trunnion", "head-head")


@pytest.mark.parametrize("machine", TYPES)
def test_plan_states_todays_sd_exactly(machine, run_cli):
    """plan's sd before any new run on the ball bar's data: the Gaussian posterior of the linear model at plan's
    σ_model (to 1e-6 relative), from the campaign's own ball-bar design matrix, noise and priors (the campaign's
    default data, both instruments, is the next test's)."""
    code, out, err = run_cli("plan", "--machine", machine, "--data", "ballbar", "--json")
    assert code == 0, err
    doc = json.loads(out)
    c = api.campaign_of(demo_campaign(machine))
    model = make_model("linear", c)
    A = model.design
    sigma = units.to_internal(doc["sigma_model_um"], "um")
    V = GaussianMeanLikelihood(model.observations, c.ballbar.accuracy).base_var + sigma**2
    var0 = np.array([make_prior(p.name, p.base, p.kind, c.priors).sd for p in model.space.parameters]) ** 2
    cov = np.linalg.inv(np.diag(1 / var0) + A.T @ (A / V[:, None]))
    first = doc["candidates"][0]["targets"]
    for t in doc["targets"]:
        i = model.space.index(t)
        want = units.from_internal(np.sqrt(cov[i, i]), quantities(c.machine.description)[t].unit)
        assert first[t]["sd_before"] == pytest.approx(want, rel=1e-6), t


@pytest.mark.parametrize("machine", TYPES)
def test_plan_rests_on_every_instrument_by_default(machine, demo_plan):
    """Without --data, plan rests on the campaign's default data, as sample does (one rule: every instrument the
    campaign has): its sd today is the exact posterior's of both instruments at plan's σ_model scales, not the ball
    bar's alone (to 1e-6 relative, against the closed form of the same log posterior)."""
    from mtmcal_bayes.inference.analytic import gaussian_posterior
    from mtmcal_bayes.inference.log_posterior import LogPosterior

    doc = json.loads(demo_plan(machine))  # plan --machine MACHINE --json (conftest.demo_plan)
    c = api.campaign_of(demo_campaign(machine))
    assert api.data_of(None, c) == "both"
    sigma = units.to_internal(doc["sigma_model_um"], "um")
    post = LogPosterior(c, "linear", data="both", sigma_model=sigma)
    g = gaussian_posterior(post, sigma)
    g_bb = gaussian_posterior(LogPosterior(c, "linear", data="ballbar", sigma_model=sigma), sigma)
    first = doc["candidates"][0]["targets"]
    differs = 0
    for t in doc["targets"]:
        unit = quantities(c.machine.description)[t].unit
        want = units.from_internal(g.linear_combination({t: 1.0})[1], unit)
        assert first[t]["sd_before"] == pytest.approx(want, rel=1e-6), t
        differs += abs(units.from_internal(g_bb.linear_combination({t: 1.0})[1], unit) / want - 1) > 1e-3
    assert differs  # the probe's readings count: not the ball bar's posterior


@pytest.mark.parametrize("machine", TYPES)
def test_design_and_next_state_todays_sd_as_the_exact_posterior(machine, run_cli):
    """On the measured demo (σ_model's contraction already met, no sd target): design adds nothing, next says stop,
    and both state today's sd of every determined deviation as the exact posterior's (against sample --sampler
    exact's 4000 draws of the posterior of the ball bar's and the probe's readings, which design and next plan from:
    within 5 % of the sd, about 3.5 sampling sds of a sd)."""
    code, out, err = run_cli("design", "--machine", machine, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["runs"] == []
    code, out, err = run_cli("next", demo_campaign(machine), "--json")
    assert code == 0, err
    step = json.loads(out)
    assert step["status"] == "stop"
    post = api.sample(demo_campaign(machine), sampler="exact", seed=1, data="both")
    for t, e in doc["expected"].items():
        assert e["sd_before"] == pytest.approx(float(post.summary.loc[t, "sd"]), rel=0.05), t


@pytest.mark.parametrize("machine", TYPES)
def test_ncgen_commands_the_models_positions(machine, run_cli):
    """Every arc block of the program of each of the demo's runs, against kinematics written out in the test
    (tests/handchain.py, from the description file): the swivelled axis at the run's arc angles, the other rotary
    axes at their holds, and the linear words placing the tool ball (the run's tool length) at the bar length from
    the W ball (the mount's position at the home pose) along the pattern's direction: R radial inwards from K's
    line through the ball on K's side, T along k × r̂, A along k, X/Y/Z along that machine axis.  Tolerance: the
    program's four decimals, each word rounded by ≤ 0.05 µm (√3·0.05 µm on a vector)."""
    c = api.campaign_of(demo_campaign(machine))
    bb = c.ballbar
    hand = HandMachine(machine)
    rotary = [a for a in hand.work + hand.tool if hand.rotary(a)]
    for i, run in enumerate(bb.runs, start=1):
        code, out, err = run_cli("ncgen", "--run", i, "--machine", machine)
        assert code == 0, err
        K, d = run.pattern
        blocks = [line for line in out.splitlines() if line.startswith("G01")]
        assert len(blocks) == len(run.arc_deg), run.pattern
        tool = hand.tool_home(bb.setups[run.setup].R_B)
        ball = np.asarray(bb.mounts[run.mount].position, float)
        holds = run.hold_deg or {}
        for block, angle in zip(blocks, run.arc_deg):
            words = {w[0]: float(w[1:]) for w in block.split()[1:] if w[0].isalpha() and w[0] != "F"}
            assert words[K] == pytest.approx(angle, abs=1e-9), block
            for a in set(rotary) - {K}:
                assert words[a] == pytest.approx(holds.get(a, 0.0), abs=1e-9), (a, block)
            q = {a: np.deg2rad(words[a]) if a in rotary else words[a] for a in hand.work + hand.tool}
            T, W = hand.tool_point(tool, q), hand.work_point(ball, q)
            p, k = hand.axis_line(K, q)
            on_k = W if K in hand.work else T  # the ball on K's side
            radial = (on_k - p) - ((on_k - p) @ k) * k
            r_hat = radial / np.linalg.norm(radial)
            u = {"R": -r_hat, "T": np.cross(k, r_hat), "A": k}.get(d)
            if u is None:
                u = np.eye(3)["XYZ".index(d)]
            assert np.linalg.norm(T - W - bb.length * u) <= np.sqrt(3) * 0.5e-4, (run.pattern, block, T - W)
