"""One analysis built once and passed down (issue 25): the cache of a campaign's analyses, the report building each
of them once, the figures drawn in batches while the report goes on, the exact draws of the σ-marginal posterior."""

from __future__ import annotations

import time
from collections import Counter

import numpy as np
import pytest
from matplotlib.figure import Figure

import mtmcal_bayes as mb
from mtmcal_bayes.analysis import CampaignAnalysis, analysis_of
from mtmcal_bayes.errors import StepFailure
from mtmcal_bayes.inference import log_posterior
from mtmcal_bayes.inference.marginal import GridProposal
from mtmcal_bayes.models.probe import ProbeLayout
from mtmcal_bayes.observations import Observations
from mtmcal_bayes.reporting import build
from mtmcal_bayes.reporting.drawing import Drawing


def test_variants_share_one_cache(thesis):
    a = CampaignAnalysis(thesis)
    probe = a.variant(data="probe")
    assert probe is a.variant(data="probe") and probe.data == "probe" and probe.model == "linear"
    assert probe.variant(data="ballbar") is a  # back to the first: the same object, nothing rebuilt
    assert a.log_posterior is a.log_posterior and a.approximation is a.approximation
    assert probe.identification is a.identification  # the deterministic identification of the campaign, once
    htm = analysis_of(a, model="htm-thesis")
    assert htm.data == "ballbar" and htm.linear() is a
    assert analysis_of(thesis).key == ("linear", "ballbar", False, None, None)  # the last: the σ_model prior (assumed)


def test_an_analysis_is_accepted_wherever_a_campaign_is(thesis):
    a = CampaignAnalysis(thesis)
    post = mb.sample(a, seed=5, max_steps=500)
    assert post.sampling.approximation is a.approximation  # what the analysis built is used, not rebuilt
    assert post.summary.loc["beta_XB", "mean"] == pytest.approx(mb.sample(thesis, seed=5, max_steps=500)
                                                                .summary.loc["beta_XB", "mean"], abs=1e-12)
    assert mb.identify(a).ballbar["beta_XB"].display == mb.identify(thesis).ballbar["beta_XB"].display


def test_the_report_builds_each_analysis_of_the_campaign_once(thesis, tmp_path, monkeypatch):
    """Following the built-in campaign down ``build_report`` (in the report's process): every log posterior of the
    campaign (one per model, data set, dx_BT assumption and σ_model) is built once, and from one set of its parts:
    the ball-bar observations and the probe's readings made once, each parameter space (one per data set and dx_BT
    assumption) once."""
    built, parts = Counter(), Counter()
    real = log_posterior.LogPosterior.__init__

    def counting(self, campaign, model="linear", fix_dx_BT=False, sigma_model=None, *, data="ballbar",
                 sigma_prior=None, **kw):
        built[(id(campaign), model, fix_dx_BT, sigma_model, data, sigma_prior)] += 1
        real(self, campaign, model, fix_dx_BT, sigma_model, data=data, sigma_prior=sigma_prior, **kw)

    def counted(name, real_made):
        def made(campaign, *args, **kw):
            if campaign is thesis:
                parts[(name, *args)] += 1
            return real_made(campaign, *args, **kw)
        return made

    monkeypatch.setattr(log_posterior.LogPosterior, "__init__", counting)
    monkeypatch.setattr(log_posterior, "parameter_space", counted("space", log_posterior.parameter_space))
    monkeypatch.setattr(Observations, "from_campaign", counted("observations", Observations.from_campaign))
    real_layout = ProbeLayout.__init__
    monkeypatch.setattr(ProbeLayout, "__init__", lambda self, campaign, *a, **kw: counted(
        "probe readings", lambda c: real_layout(self, c, *a, **kw))(campaign))
    build.build_report(thesis, tmp_path / "r", settings=build.SamplerSettings(seed=1, max_steps=500))
    assert built and max(built.values()) == 1, [k for k, n in built.items() if n > 1]
    own = {k[1:-1] for k in built if k[0] == id(thesis)}
    assert {("linear", False, None, "ballbar"), ("linear", False, None, "probe"),
            ("linear", False, None, "both")} <= own
    assert parts[("observations",)] == 1 and parts[("probe readings",)] == 1, parts
    spaces = {k: n for k, n in parts.items() if k[0] == "space"}
    assert set(spaces.values()) == {1} and {("space", False, "ballbar"), ("space", False, "probe"),
                                             ("space", False, "both")} <= set(spaces), spaces


def _figure(text: str):
    def make():
        fig = Figure(figsize=(2, 1))
        fig.text(0.5, 0.5, text)
        return fig, text
    return make


def _gated_figure(gate, text: str):
    """A figure job that waits until the file ``gate`` exists (the test opens it).  A drawing that waited for this
    job before returning to the caller would never see the gate opened: the job gives up after 60 s and fails,
    so a broken ``start`` or ``wait`` fails the test instead of hanging it (no time is measured)."""
    def make():
        for _ in range(6000):
            if gate.exists():
                return _figure(text)()
            time.sleep(0.01)
        raise RuntimeError(f"{gate.name} never opened: the caller was waiting for this job")
    return make


def test_batches_drawn_while_the_caller_goes_on_all_arrive(tmp_path):
    """Two batches, the first still drawing when the second starts: every file of both is written, each job's
    extra comes back, and starting a batch returns at once: with fork, the first batch's jobs wait for a gate the
    test opens only after both ``start`` calls returned, and none of its files exists before that."""
    drawing = Drawing(tmp_path)
    gate = tmp_path.parent / f"{tmp_path.name}.gate"
    first = [(f"a{i}.png", _gated_figure(gate, f"a{i}") if drawing.fork else _figure(f"a{i}")) for i in range(4)]
    drawing.start(first)
    drawing.start([(f"b{i}.png", _figure(f"b{i}")) for i in range(3)]
                  + [("note.txt", lambda: (tmp_path / "note.txt").write_text("x") and None)])
    if drawing.fork:  # both start calls returned while the first batch was held at its gate
        assert not any(tmp_path.glob("a*.png"))
        gate.touch()
    extras = drawing.finish()
    names = [f"a{i}.png" for i in range(4)] + [f"b{i}.png" for i in range(3)]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names + ["note.txt"])
    assert {n: extras[n] for n in names} == {n: n[:-4] for n in names} and extras["note.txt"] is None


def test_a_failing_job_is_raised_by_finish(tmp_path):
    def broken():
        raise RuntimeError("simulated failure while drawing")

    drawing = Drawing(tmp_path)
    with pytest.raises(StepFailure) as info:  # forked, at finish; drawn in this process, at once
        drawing.start([("ok.png", _figure("ok")), ("bad.png", broken)])
        drawing.finish()
    assert (info.value.step, info.value.kind) == ("drawing bad.png", "RuntimeError")
    assert info.value.message == "simulated failure while drawing"


def test_a_failing_job_drawn_without_fork_names_its_step_too(tmp_path):
    def broken():
        raise RuntimeError("simulated failure while drawing")

    drawing = Drawing(tmp_path, workers=1)
    assert not drawing.fork
    with pytest.raises(StepFailure) as info:
        drawing.start([("ok.png", _figure("ok")), ("bad.png", broken)])
    assert (info.value.step, info.value.kind) == ("drawing bad.png", "RuntimeError")



def test_one_batch_waited_for_while_another_goes_on_and_a_cancelled_batch_leaves_nothing(tmp_path):
    """``wait`` returns the waited batch's extras without waiting for a slower batch; a cancelled batch's job is
    ended (its file never written) and its name and extra are gone; ``finish`` still brings the rest.  With fork
    the slow and the cancelled batch wait for a gate the test opens only after ``wait`` returned (a ``wait`` that
    waited for them would see them fail, _gated_figure); the cancelled one never gets to draw."""
    drawing = Drawing(tmp_path)
    gate = tmp_path.parent / f"{tmp_path.name}.gate"
    never = tmp_path.parent / f"{tmp_path.name}.never"
    held = _gated_figure if drawing.fork else (lambda _gate, text: _figure(text))
    slow = drawing.start([("slow.png", held(gate, "slow"))])
    quick = drawing.start([("quick", lambda: (None, 42))])
    dropped = drawing.start([("dropped.png", held(never, "dropped"))])
    assert drawing.wait(quick)["quick"] == 42
    if drawing.fork:  # the slow batch was not waited for: still held at its gate
        assert not (tmp_path / "slow.png").exists()
        gate.touch()
    drawing.cancel(dropped)
    drawing.cancel(None)  # nothing begun: nothing to end
    extras = drawing.finish()
    drawing.stop()
    assert "dropped.png" not in extras and "dropped.png" not in drawing.names
    assert extras["slow.png"] == "slow" and extras["quick"] == 42
    if drawing.fork:  # (without fork each batch is drawn when it starts, so the cancelled one wrote its file)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["slow.png"]
    assert slow != quick != dropped

def test_exact_draws_per_cell_equal_the_gathered_product(thesis):
    """The proposal's draws, one product per σ cell, equal θ = μ_j + L_j z drawn row by row (to rounding)."""
    a = CampaignAnalysis(thesis, data="both")
    prop = GridProposal(a.marginal, a.log_posterior.likelihood.y)
    theta, sigma = prop.draw(3000, np.random.RandomState(4))
    r = np.random.RandomState(4)
    j = r.choice(prop.cell_prob.size, size=3000, p=prop.cell_prob)
    r.rand(3000, prop.low.shape[1])
    z = r.randn(3000, prop.P)
    k = prop.slot[j]
    assert (k >= 0).all()  # only cells of some weight are drawn
    expected = prop.mean[k] + np.einsum("nij,nj->ni", prop.chol[k], z)
    assert np.allclose(theta, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
