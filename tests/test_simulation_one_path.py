"""One simulation for every machine (SPEC §20): the eccentricities of every measured and planned run, the first-order
warning, and the probe model's readings handed to the campaign's runs in order, on the thesis campaign, the three demo
campaigns and a probe-only campaign alike; one JSON (model, eccentricities, machine, truth, probe)."""

from __future__ import annotations

import copy
import json
import re

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.io.campaign_reader import load_truth
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.models import default_kinematic_model, make_model
from mtmcal_bayes.simulation import predict_truth, synthetic_campaign
from mtmcal_bayes.simulation.simulate import DEFAULT_PROBE_SD, simulation_space, truth_vector
from .conftest import DATA

TYPES = ("integrex-i200", "trunnion", "vertical-turn-mill", "head-head")
#: the thesis campaign, the demos, a probe-only campaign (the trunnion's controller cycle) and the thesis campaign
#: with fitted C-axis centres (its observations in each fit covariance's principal axes)
CAMPAIGNS = TYPES + ("trunnion-cycle", "integrex-i200-fitted")
#: digits of a written reading: the campaign writer's rounding, far below any repeatability (0.35 µm and more)
WRITTEN_MM = 1e-6


def _campaign(name: str):
    if name == "trunnion-cycle":
        return mb.load_campaign(DATA / "controller_cycles" / "trunnion-cycle.toml")
    if name == "integrex-i200-fitted":  # as fitted from DPRNT points: a covariance per centre, axes not the frame's
        c = copy.deepcopy(mb.load_campaign())
        run = c.probe.runs[0]  # the C-axis run
        a = np.random.default_rng(5).normal(size=run.centres.shape + (3,)) * 1e-3
        run.centre_cov = a @ np.swapaxes(a, -1, -2)  # (r, a, 3, 3) mm², positive definite
        return c
    return mb.load_campaign(demo_campaign(name))


def _truth(name: str, campaign) -> Truth:
    """The thesis: the truth the corpus files were simulated from; a demo: its own ``[truth]``."""
    if name.startswith("integrex-i200"):
        return load_truth(DATA / "formats_truth.toml", campaign)
    return copy.deepcopy(campaign.truth)


def _positions(probe):
    return [(run.id, run.stylus, i + 1) for run in probe.runs for i in range(run.positions)]


@pytest.mark.parametrize("name", CAMPAIGNS)
def test_the_written_readings_are_what_the_probe_model_predicts(name, tmp_path):
    """The JSON's probe records and the written campaign's readings are the same, position by position in the
    campaign's order; read back, their observations are the probe model's prediction at the truth (a reading handed
    to the wrong run, or left in the model's covariance frame, would not be); the JSON has one set of keys."""
    c = _campaign(name)
    truth = _truth(name, c)
    model = default_kinematic_model(c.machine)
    sim = mb.simulate(c, truth=truth, model=model, output=tmp_path / "s.toml")
    d = json.loads(json.dumps(sim.to_json()))
    assert set(d) == {"model", "eccentricities", "machine", "truth", "probe"}
    # a built-in type by its name, a description file (the controller cycles' list their deviations) by the machine's
    assert d["machine"] == (c.machine.description.builtin or c.machine.name) and set(d["truth"]) == set(truth.deviations)
    written = mb.load_campaign(tmp_path / "s.toml")
    assert [(r["run"], r["stylus"], r["position"]) for r in d["probe"]] == _positions(written.probe) \
        == _positions(c.probe)
    runs = written.probe.runs
    assert all(run.centres.shape[0] == 1 for run in runs)  # noise-free: one repeat
    xyz = np.concatenate([run.centres[0] for run in runs])
    assert np.abs(np.array([[r[f"{x}_mm"] for x in "XYZ"] for r in d["probe"]]) - xyz).max() < WRITTEN_MM
    angles = [{f"{a}_deg": float(v[i]) for a, v in run.angles_deg.items()} for run in runs for i in range(run.positions)]
    assert [{k: v for k, v in r.items() if k.endswith("_deg")} for r in d["probe"]] == angles
    fm = make_model(model, written, simulation_space(written, truth, "probe"), data="probe")
    predicted = fm.predict(truth_vector(fm.space, truth.probe_part())).reshape(-1, 3)
    observed = fm.observations.mean.reshape(-1, 3)
    start = 0
    for run in runs:  # within each run: a run's datum may be where its first reading puts it (the thesis' "first")
        sl = slice(start, start + run.positions)
        moved = predicted[sl] - predicted[start]
        assert np.abs(observed[sl] - observed[start] - moved).max() < WRITTEN_MM, run.id
        start += run.positions
    # the truth moves the readings relative to each other: the check above has power
    assert np.abs(predicted - predicted[0]).max() > 100 * WRITTEN_MM


@pytest.mark.parametrize("name", CAMPAIGNS)
@pytest.mark.parametrize("stated", [True, False])
def test_simulated_readings_scatter_by_the_repeatability(name, stated):
    """With noise, each reading scatters about the noise-free one by the probe's repeatability (a probe that states
    none: 1 µm), independently: 400 repeats of every position, the mean deviation within 4 standard errors of zero at
    every position and the pooled sd within 4 of its own of the repeatability.  On the thesis machine, whose probe
    model takes only a stated repeatability, a probe without one is not simulated (the JSON lists no readings)."""
    c = copy.deepcopy(_campaign(name))
    if not stated:
        c.probe.repeatability = None
    truth = _truth(name, c)
    model = default_kinematic_model(c.machine)
    records = mb.simulate(c, truth=truth, model=model).to_json().get("probe")
    if not stated and name.startswith("integrex-i200"):
        assert records is None
        return
    sd = c.probe.repeatability if stated else DEFAULT_PROBE_SD
    r = 400
    noisy = synthetic_campaign(c, truth, model, noise=True, seed=11, repeats=r).probe.runs
    centres = np.concatenate([run.centres for run in noisy], axis=1)  # (r, k, 3)
    mean = np.array([[rec[f"{x}_mm"] for x in "XYZ"] for rec in records])
    dev = centres - mean
    assert centres.shape == (r, len(records), 3)
    assert np.abs(dev.mean(axis=0)).max() < 4 * sd / np.sqrt(r) + WRITTEN_MM
    n = dev.size
    assert abs(dev.std() / sd - 1) < 4 / np.sqrt(2 * n)


@pytest.mark.parametrize("name", TYPES)
def test_the_first_order_warning_on_every_machine(name):
    """``linear`` warns where the machine's kinematic model predicts eccentricities further from it than the ball bar's
    accuracy, naming that model and the largest difference (computed here from both models' predictions); the demo's
    own truth and a truth 300 times as large (degrees) are each checked, and the large one warns."""
    c = _campaign(name)
    base = _truth(name, c)
    kinematic = default_kinematic_model(c.machine)
    for scale in (1.0, 300.0):
        truth = Truth({k: v * scale for k, v in base.deviations.items()})
        gap = np.abs(predict_truth(c, truth, kinematic)[1] - predict_truth(c, truth, "linear")[1]).max()
        warnings = mb.simulate(c, truth=truth, model="linear").warnings
        assert bool(warnings) == (gap > c.ballbar.accuracy), (scale, warnings)
        assert not mb.simulate(c, truth=truth, model=kinematic).warnings
        if scale > 1:
            assert len(warnings) == 1 and f"{kinematic} predicts" in warnings[0]
            said = float(re.search(r"up to ([0-9.]+) µm", warnings[0]).group(1))
            assert abs(said - units.from_internal(gap, "um")) <= 0.05


def test_a_probe_only_thesis_campaign_is_simulated(tmp_path, run_cli):
    """The thesis machine's probe-only campaign (valid as on any machine) simulates its readings: no eccentricities,
    the probe model's readings, written with noise as measured."""
    c = copy.deepcopy(mb.load_campaign())
    c.ballbar.runs, c.reported = [], {}
    path = tmp_path / "probe_only.toml"
    mb.save_campaign(c, path)
    truth = DATA / "formats_truth.toml"
    code, out, err = run_cli("simulate", path, "--truth", truth, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["eccentricities"] == [] and [(r["run"], r["stylus"], r["position"]) for r in d["probe"]] \
        == _positions(c.probe)
    code, _, err = run_cli("simulate", path, "--truth", truth, "--noise", "--seed", "2", "-o", tmp_path / "s.toml")
    assert code == 0, err
    written = mb.load_campaign(tmp_path / "s.toml")
    assert [run.centres.shape for run in written.probe.runs] == \
        [run.centres.shape for run in c.probe.runs]


@pytest.mark.parametrize("name", ("integrex-i200", "trunnion"))
def test_nothing_to_simulate_is_one_line(name, tmp_path, run_cli):
    """A campaign with neither ball-bar runs (measured or planned) nor probe readings: one line, on every machine."""
    c = copy.deepcopy(_campaign(name))
    c.ballbar.runs, c.ballbar.planned, c.probe, c.reported, c.truth = [], [], None, {}, None
    path = tmp_path / "empty.toml"
    mb.save_campaign(c, path)
    truth = tmp_path / "t.toml"
    truth.write_text("[deviations]\n", encoding="utf-8")
    code, out, err = run_cli("simulate", path, "--truth", truth, "--json")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "ballbar.runs" in err and "nothing to simulate" in err
