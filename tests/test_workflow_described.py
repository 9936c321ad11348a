"""Every planning command on each described built-in type's demo campaign, one number each checked against the
exact answer (issue 37, acceptance): ``plan`` (today's sd: the Gaussian posterior at its σ_model, computed here from
the linear model's own design), ``design`` and ``next`` (today's sd: the exact σ-marginal posterior, against
``sample --sampler exact``), ``ncgen`` (the program's commands: the model's)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mtmcal_bayes import api, units
from mtmcal_bayes.inference.likelihood import GaussianMeanLikelihood
from mtmcal_bayes.inference.priors import make_prior
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines.deviations import quantities
from mtmcal_bayes.machines.patterns import pattern_commands
from mtmcal_bayes.models import make_model

TYPES = ("vertical-turn-mill", "trunnion", "head-head")


@pytest.mark.parametrize("machine", TYPES)
def test_plan_states_todays_sd_exactly(machine, run_cli):
    """plan's sd before any new run: the Gaussian posterior of the linear model at plan's σ_model (to 1e-6 relative),
    from the campaign's own design matrix, noise and priors."""
    code, out, err = run_cli("plan", "--machine", machine, "--json")
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
def test_design_and_next_state_todays_sd_as_the_exact_posterior(machine, run_cli):
    """On the measured demo (σ_model's contraction already met, no sd target): design adds nothing, next says stop,
    and both state today's sd of every determined deviation as the exact posterior's (against sample --sampler
    exact's 4000 draws of the ball-bar posterior, which design and next plan from: within 5 % of the sd, about 3.5
    sampling sds of a sd)."""
    code, out, err = run_cli("design", "--machine", machine, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["runs"] == []
    code, out, err = run_cli("next", demo_campaign(machine), "--json")
    assert code == 0, err
    step = json.loads(out)
    assert step["status"] == "stop"
    post = api.sample(demo_campaign(machine), sampler="exact", seed=1, data="ballbar")
    for t, e in doc["expected"].items():
        assert e["sd_before"] == pytest.approx(float(post.summary.loc[t, "sd"]), rel=0.05), t


@pytest.mark.parametrize("machine", TYPES)
def test_ncgen_commands_the_models_positions(machine, run_cli):
    """The program of the demo's first run commands, at every arc block, the positions the model predicts with."""
    code, out, err = run_cli("ncgen", "--run", "1", "--machine", machine)
    assert code == 0, err
    c = api.campaign_of(demo_campaign(machine))
    run, bb = c.ballbar.runs[0], c.ballbar
    cmd = pattern_commands(c.machine.description, run.pattern, length=bb.setups[run.setup].R_B,
                           ball=bb.mounts[run.mount].position, bar=bb.length, arc_deg=run.arc_deg,
                           hold_deg=run.hold_deg)
    blocks = [line for line in out.splitlines() if line.startswith("G01")]
    assert len(blocks) == len(cmd.psi)
    words = {w[0]: float(w[1:]) for w in blocks[-1].split()[1:] if w[0].isalpha() and w[0] != "F"}
    for a, v in cmd.q.items():
        expect = units.from_internal(v[-1], "deg") if c.machine.description.axes[a].rotary else v[-1]
        assert words[a] == pytest.approx(expect, abs=1e-4), a
