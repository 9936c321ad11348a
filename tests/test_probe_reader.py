"""One reader of a campaign's measurement sections for every machine (SPEC §20, issue 42): ``[ballbar]`` and
``[probe]`` are the engine's on every built-in type, the thesis plug-in reading only its own sub-tables of
``[probe]`` (``c_axis``, ``b_axis``); ``[[probe.runs]]`` and ``[probe.styli]`` work on the thesis campaign too, beside
its own runs: read, modelled through the machine's chain, sampled and written back.

The thesis' own probe sections and their bad inputs: tests/test_probe_runs.py and tests/test_bad_inputs.py."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import InputError, api
from mtmcal_bayes.datasets import builtin_campaign_text
from mtmcal_bayes.inference.analytic import gaussian_posterior
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.campaign_writer import campaign_to_dict
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, demo_campaign
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.machines.plugins import provided
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.probe import ChainProbeKernel, ProbeModel
from mtmcal_bayes.units import ARCSEC

#: an extra run on the thesis machine: a sphere on the C table off its axis, probed at C and B positions
EXTRA = {"id": "table", "stylus": "mid", "sphere_mm": [150.0, 50.0, 60.0],
         "angles_deg": {"C": [0.0, 90.0, 180.0, 270.0, 0.0, 0.0], "B": [0.0, 0.0, 0.0, 0.0, 30.0, 60.0]}}


def _thesis_doc() -> dict:
    return tomllib.loads(builtin_campaign_text()[0])


def _load(doc: dict, tmp_path, name: str = "c.toml"):
    path = tmp_path / name
    path.write_text(dumps(doc), encoding="utf-8")
    return mb.load_campaign(path)


def _error(doc: dict, tmp_path) -> InputError:
    with pytest.raises(InputError) as info:
        _load(doc, tmp_path, "bad.toml")
    assert "bad.toml" in str(info.value)
    return info.value


def _with_extra(tmp_path, centres=None, *, stylus: str = "mid"):
    """The thesis campaign with [probe.styli.mid] and the run :data:`EXTRA` (``centres`` (r, 6, 3) mm; default the
    chain's nominal readings, twice)."""
    doc = _thesis_doc()
    doc["probe"]["styli"] = {"mid": {"length_mm": 400.0}}
    run = {**copy.deepcopy(EXTRA), "stylus": stylus}
    run["centres_mm"] = (np.zeros((2, 6, 3)) if centres is None else centres).tolist()
    doc["probe"]["runs"] = [run]
    c = _load(doc, tmp_path)
    if centres is None:  # the chain's nominal readings, read from the run as the engine's model places it
        zero = ProbeModel(c, make_model("htm-thesis", c, data="probe").space).layout.zero[-6:]
        return _with_extra(tmp_path, np.stack([zero, zero]), stylus=stylus)
    return c, doc


def _runs(c) -> list[tuple]:
    return [(r.id, r.stylus, r.section, c.probe.centre_length(r.stylus), tuple(r.angles), r.centres.tolist(),
             r.sphere.tolist()) for r in c.probe.runs]


@pytest.mark.parametrize("machine", BUILTIN_TYPES)
def test_every_built_in_campaign_is_read_by_the_one_reader_and_written_back_the_same(machine, tmp_path):
    """No machine reads its measurement sections its own way (the thesis plug-in gives only its sub-tables of
    [probe]); each type's campaign has probe runs, and saving and reading it again gives the same runs, styli and
    ball-bar runs, and the same document."""
    c = mb.load_campaign(demo_campaign(machine))
    assert provided(c.machine, "campaign_sections") is None
    assert set(provided(c.machine, "probe_keys", ())) <= {"c_axis", "b_axis"}
    assert c.probe is not None and c.probe.runs and c.ballbar.runs
    mb.save_campaign(c, tmp_path / "saved.toml")
    back = mb.load_campaign(tmp_path / "saved.toml")
    assert _runs(back) == _runs(c)
    assert [r.label for r in back.ballbar.runs] == [r.label for r in c.ballbar.runs]
    assert dumps(campaign_to_dict(back, tmp_path)) == dumps(campaign_to_dict(c, tmp_path))


def test_a_thesis_campaign_reads_probe_runs_beside_its_own_sections(tmp_path):
    """[probe.styli] and [[probe.runs]] on the thesis campaign: its own runs first (their sections kept), the engine's
    run after them with its stylus; the truth and the owner rule take the new run's terms."""
    c, _ = _with_extra(tmp_path)
    assert [(r.id, r.stylus, r.section) for r in c.probe.runs] == [
        ("c_axis", "short", "c_axis"), ("b_axis", "short", "b_axis"), ("b_axis", "long", "b_axis"),
        ("table", "mid", None)]
    assert c.probe.styli["mid"] == 400.0 and {"short", "long"} <= set(c.probe.styli)
    owners = c.probe.nuisance_terms(c.machine.description)
    assert ("mid", "dRS") in owners and ("table", "xP") in owners and ("short", "rS") in owners
    # a run of the engine's may use a stylus of the thesis' sections
    c2, _ = _with_extra(tmp_path, stylus="short")
    assert c2.probe.runs[-1].stylus == "short" and c2.probe.centre_length("short") == c.probe.centre_length("short")


def test_the_thesis_probe_model_reads_an_added_run_through_the_chain_and_its_own_runs_as_before(tmp_path):
    """With a run added, the thesis' probe model (``htm-thesis``) reads its own runs exactly as without it, and the
    added run as the engine's chain model of that run alone does (its commanded X, Y, Z in the machine frame), at
    random deviations (30″), stylus and sphere terms (30 µm): the readings move by tens of µm, and agree to rounding."""
    c, _ = _with_extra(tmp_path)
    plain = mb.load_campaign()
    both = make_model("htm-thesis", c, data="probe")
    own = make_model("htm-thesis", plain, data="probe")
    space = both.space
    rng = np.random.default_rng(5)
    theta = rng.normal(size=(4, len(space))) * space.display_scale() * 30
    theta[:, [i for i, p in enumerate(space.parameters) if p.base == "rS"]] = 0.0  # the chain has no pre-travel term
    at = {n: i for i, n in enumerate(space.names)}
    sub = theta[:, [at[n] for n in own.space.names]]
    k_own = len(own.layout.run)
    np.testing.assert_allclose(both.readings(theta)[:, :k_own], own.readings(sub), rtol=0, atol=1e-12)
    alone = copy.copy(c)
    alone.probe = copy.copy(c.probe)
    alone.probe.runs = [c.probe.runs[-1]]
    chain = ProbeModel(alone, kernel=ChainProbeKernel(c.machine.description))
    csub = theta[:, [at[n] for n in chain.space.names]]
    extra = both.readings(theta)[:, k_own:]
    np.testing.assert_allclose(extra, chain.readings(csub), rtol=0, atol=1e-9)
    assert np.abs(extra - both.readings(np.zeros(len(space)))[:, k_own:]).max() > 1e-2


def test_an_added_run_on_the_thesis_machine_is_simulated_sampled_and_written_back(tmp_path):
    """The campaign with its added run simulated at a truth by ``htm-thesis`` (deviations of 15–20″ / 20 µm, the
    added run's sphere off by 40 / −30 µm, its stylus 15 µm long; seeded noise as measured): the exact (``linear``)
    posterior of the probe data, its likelihood holding the added run's 18 readings, recovers where the added run's
    sphere sits across the table within 4 posterior sd, each sd below 10 µm against a prior of hundreds;
    ``sample --data probe`` (exact sampler) gives those terms the same mean within 4 Monte-Carlo errors; the
    simulated campaign written and read back has the same runs and readings."""
    c, _ = _with_extra(tmp_path)
    truth = mb.campaign.Truth({"alpha_XB": 20 * ARCSEC, "beta_XB": -20 * ARCSEC, "gamma_XB": 15 * ARCSEC,
                               "dx_CZ": 0.02}, probe={"table": {"xP": 0.04, "yP": -0.03}, "mid": {"dRS": 0.015}})
    api.simulate(c, truth=truth, model="htm-thesis", noise=True, seed=7, output=tmp_path / "sim.toml")
    sim = mb.load_campaign(tmp_path / "sim.toml")
    assert _runs(sim)[-1][:3] == ("table", "mid", None)
    post = LogPosterior(sim, "linear", data="probe")
    assert sum(k.run == "table" for k in post.forward.observations.keys) == 18
    g = gaussian_posterior(post, 0.0)
    at = {n: i for i, n in enumerate(g.names)}
    expected = {"xP[table]": 0.04, "yP[table]": -0.03}  # its stylus' length error goes with its sphere's height
    for name, value in expected.items():
        i = at[name]
        assert abs(g.mean[i] - value) < 4 * g.sd[i] and g.sd[i] < 0.01, (name, g.mean[i], g.sd[i])
    posterior = api.sample(sim, data="probe", sampler="exact", seed=3, sigma_model_um=0.0).idata.posterior
    for name in expected:
        draws = posterior[name].values.ravel() / 1e3  # µm -> mm
        mc_error = g.sd[at[name]] / np.sqrt(draws.size)  # independent draws
        assert abs(draws.mean() - g.mean[at[name]]) < 4 * mc_error, name
    mb.save_campaign(sim, tmp_path / "again.toml")
    assert _runs(mb.load_campaign(tmp_path / "again.toml")) == _runs(sim)


@pytest.mark.parametrize("change, key, says", [
    (lambda d: d["probe"]["runs"][0].update(id="c_axis"), "probe.runs[0].id", "names a run of [probe.c_axis]"),
    (lambda d: d["probe"]["styli"].update(short={"length_mm": 300.0}), "probe.styli.short",
     "names a stylus of [probe.c_axis]"),
    (lambda d: d["probe"]["runs"][0].update(stylus="medium"), "probe.runs[0].stylus", "no stylus 'medium'"),
    (lambda d: d["probe"].update(cyl={}), "probe.cyl", "unknown key"),
])
def test_a_run_of_the_engine_clashing_with_the_thesis_sections_is_refused_by_name(change, key, says, tmp_path):
    """An added run or stylus may not take the name of one of the thesis' sections (they would share terms they do
    not share), nor name a stylus neither part gives; a key neither reads is unknown."""
    _, doc = _with_extra(tmp_path)
    change(doc)
    err = _error(doc, tmp_path)
    assert err.key == key and says in str(err), str(err)


@pytest.mark.parametrize("machine", BUILTIN_TYPES)
def test_one_rule_of_measurements_and_of_reported_values_on_every_machine(machine, tmp_path):
    """A campaign with neither [ballbar] nor [probe] is refused alike on every machine, naming ``ballbar``; a
    [probe] without runs names ``probe.runs``; ``[reported]`` is read where a plug-in of the machine reads it
    (the thesis') and refused by name where it has none."""
    path = demo_campaign(machine)
    doc = tomllib.loads(open(path, encoding="utf-8").read()) if path is not None else _thesis_doc()
    bare = {k: v for k, v in doc.items() if k not in ("ballbar", "probe", "rtest", "truth", "reported", "design")}
    err = _error(bare, tmp_path)
    assert err.key == "ballbar" and "no measurements" in str(err)
    empty = {**bare, "probe": {}}
    err = _error(empty, tmp_path)
    assert err.key == "probe.runs" and "expected one or more [[probe.runs]]" in str(err)
    # a probe declared without runs (to plan its runs with) is read, but measures nothing
    declared = {**bare, "probe": {"instrument": "probe", "repeatability_um": 1.0}}
    err = _error(declared, tmp_path)
    assert err.key == "ballbar" and "no measurements" in str(err)
    truth = {k: v for k, v in doc.get("truth", {}).items() if k != "probe"}  # a demo's stylus and sphere truth: gone
    planned = {**{k: v for k, v in doc.items() if k != "truth"}, "probe": {"instrument": "probe", "repeatability_um": 1.0}}
    planned |= {"truth": truth} if truth else {}
    c = _load(planned, tmp_path)
    assert c.probe.repeatability == pytest.approx(1e-3) and not c.probe.runs and not c.has_probe_readings()
    again = tmp_path / "again.toml"
    mb.save_campaign(c, again)
    assert mb.load_campaign(again).probe.repeatability == pytest.approx(1e-3)
    reported = {**doc, "reported": {"ballbar": {"alpha_XB_arcsec": 1.0}}}
    if provided(mb.load_campaign(path).machine, "reported_quantities") is None:
        err = _error(reported, tmp_path)
        assert err.key == "reported" and "no reported quantities" in str(err)
    else:
        assert _load(reported, tmp_path).reported["ballbar"]["alpha_XB"].value == pytest.approx(ARCSEC)
