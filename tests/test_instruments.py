"""The instruments' check on every built-in machine type (issue 42, defects 1 and 5): the consistency check's
calibration and power, one verdict for its sentences, the conflict explanations and compensate's refusal of the
disputed deviations (docs/probe.md).  The full count of the calibration: bench/instrument_check.py."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.campaign_writer import save_campaign
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.posterior.check_calibration import null_p_values
from mtmcal_bayes.posterior.instrument_check import check_instruments

TYPES = ("integrex-i200", "trunnion", "vertical-turn-mill", "head-head")
#: each type's rotary axes (from its description, written here independently of the code)
ROTARY = {"integrex-i200": {"B", "C"}, "trunnion": {"A", "C"}, "vertical-turn-mill": {"B", "C"},
          "head-head": {"A", "C"}}
#: a program of each type to compensate
PROGRAM = {"integrex-i200": "mtmcal_bayes/datasets/fig4_30a_bx_original.nc",
           "trunnion": "examples/machines/trunnion-five-axis.nc",
           "vertical-turn-mill": "examples/machines/vertical-turn-mill-five-axis.nc",
           "head-head": "examples/machines/head-head-five-axis.nc"}
UM = 1e-3


@pytest.fixture(scope="module")
def campaigns():
    return {name: mb.load_campaign(demo_campaign(name)) for name in TYPES}


@pytest.fixture(scope="module")
def checks(campaigns):
    """``checks(name, shift_um)``: ``check_instruments(..., explain=False)`` of the type's demo campaign (``shift_um``
    0) or of its :func:`shifted` copy, made once for the tests that read it (read only)."""
    made = {}

    def get(name: str, shift_um: float = 0.0):
        if (name, shift_um) not in made:
            c = campaigns[name]
            made[name, shift_um] = check_instruments(shifted(c, shift_um) if shift_um else c, explain=False)
        return made[name, shift_um]

    return get


def shifted(campaign, shift_um: float = 15.0, axis: int = 0):
    """A copy of ``campaign`` whose first probe run's positions at the last angle of its first indexed axis (the
    thesis' C-axis run: C = 270°; a demo's: the four positions of its last tilt) are moved ``shift_um`` along
    machine axis ``axis``."""
    c = copy.deepcopy(campaign)
    run = c.probe.runs[0]
    first = next(iter(run.angles.values()))
    run.centres[:, np.isclose(first, first[-1]), axis] += shift_um * UM
    return c


def _moved_group(before, after) -> str:
    """The one reading group whose observed readings differ between two checks."""
    a, b = before.consistency.readings, after.consistency.readings
    moved = set(a.loc[~np.isclose(a["observed_um"], b["observed_um"]), "group"])
    assert len(moved) == 1, moved
    return moved.pop()


#: the requirement of issue 42 (15 µm flagged at p < 0.01) is not met by the calibrated check: under each campaign's
#: σ_model prior (half-normal, scale 2 µm) a probe noisier than assumed explains a 15 µm shift with probability
#: 0.02–0.05 (thesis p = 0.036, trunnion 0.023, vertical-turn-mill 0.044, head-head 0.024, along X)
UNMET = pytest.mark.xfail(strict=True, reason="15 µm: p = 0.02–0.05 under the σ_model prior (docs/probe.md)")


@pytest.mark.parametrize("name, shift_um", [(n, 25.0) for n in TYPES] + [pytest.param(n, 15.0, marks=UNMET)
                                                                           for n in TYPES])
def test_a_shifted_group_of_probe_positions_is_flagged_and_every_sentence_follows(campaigns, checks, name, shift_um):
    """A group of probe positions moved along X: its reading group disagrees at p < 0.01 (the unmoved campaign's
    agrees at p ≥ 0.01), the check's verdict, its sentence and the disputed deviations say the same, and the
    disputed deviations are the machine's own (its estimated deviations, by its names)."""
    c = campaigns[name]
    before, after = checks(name), checks(name, shift_um)
    group = _moved_group(before, after)
    p_before = before.consistency.groups.set_index("group").loc[group, "p_value"]
    p_after = after.consistency.groups.set_index("group").loc[group, "p_value"]
    assert p_before >= 0.01 and before.agree and "agree on every deviation" in before.to_text()
    assert p_after < 0.01, after.consistency.to_text()
    assert not after.agree and "agree on every deviation" not in after.to_text()
    assert after.to_json()["agree"] is False and after.disputed
    space = mb.sample(c, sampler="exact", seed=1, data="both").summary.index
    assert set(after.disputed) <= set(space)


@pytest.mark.parametrize("name", TYPES)
def test_a_15_um_shift_is_flagged_where_the_probe_is_known_to_discrepancy_of_1_um(campaigns, name):
    """The same 15 µm shift with the probe's σ_model prior half-normal of scale 1 µm (instead of 2 µm): flagged at
    p < 0.01 on every type (measured p = 3·10⁻⁴ thesis, 7·10⁻⁷ trunnion, 3·10⁻⁴ vertical turn-mill, 2·10⁻⁶
    head-head), the unmoved campaign's group still agreeing."""
    c = copy.deepcopy(campaigns[name])
    c.priors["sigma_model_probe"] = {"dist": "halfnormal", "sd": 0.001}
    before, after = check_instruments(c, explain=False), check_instruments(shifted(c, 15.0), explain=False)
    group = _moved_group(before, after)
    assert before.consistency.groups.set_index("group").loc[group, "p_value"] >= 0.01
    assert after.consistency.groups.set_index("group").loc[group, "p_value"] < 0.01 and not after.agree


@pytest.mark.parametrize("name", TYPES)
def test_the_check_is_calibrated_without_a_conflict(campaigns, name):
    """Campaigns of each type's design simulated without a conflict (both instruments from one truth; the sphere's
    placement, the stylus length and the datum held at zero as in the demos, the rest drawn from the priors): every
    group's p-values are uniform, a Kolmogorov–Smirnov test at 0.001 over the groups (Bonferroni).  Power: at
    n = 100 it rejects a largest distance D ≥ 0.23 between the p-values' distribution and the uniform; the check
    before issue 42 (χ² against σ_model at its prior mean, dof the count of readings) failed it on every type:
    on these simulations (seed 11) its probe groups gave KS p ≤ 1e-4, mean p 0.63–0.78, and 3–20 % of the
    p-values below 0.01."""
    df = null_p_values(campaigns[name], n=100, seed=11)
    groups = df.groupby(["given", "group"], sort=False)
    for (given, group), d in groups:
        ks = stats.kstest(d["p_value"], "uniform").pvalue
        assert ks > 0.001 / groups.ngroups, (group, given, ks, d["p_value"].mean())


@pytest.mark.parametrize("name", TYPES)
def test_instruments_explains_a_conflict_on_every_machine(campaigns, name, run_cli, tmp_path):
    """``instruments`` on a campaign whose probe disagrees with its ball bar: no internal error; the explanations
    weigh the stylus length known to 0.3 mm (where its prior is narrower) and a difference of the sessions on each
    rotary axis of the machine (named by its letter); every reading of the B runs it weighs changes the evidence (none where the runs are read in the
    machine frame)."""
    path = tmp_path / "shifted.toml"
    save_campaign(shifted(campaigns[name], 25.0), path)
    code, out, err = run_cli("instruments", path, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["agree"] is False and doc["explanations"] is not None  # two instruments: the one analysis
    cands = doc["explanations"]["candidates"]
    probe = LogPosterior(campaigns[name], "linear", data="probe")
    narrow = any(w < 0.3 for n, w in zip(probe.space.names, probe.priors.width) if n.startswith("dRS["))
    assert narrow == any(c["kind"] == "probe" and c["name"].startswith("stylus length") for c in cands)
    sessions = {c["name"].split("(")[1].split(" axis")[0] for c in cands if c["kind"] == "sessions"}
    assert sessions == ROTARY[name]
    assert all(c["log_bayes_factor"] != 0.0 for c in cands if c["kind"] == "ball-bar reading")
    assert all(c["quantities"] for c in cands)
    code, out, err = run_cli("instruments", path)
    assert code == 0 and "Where the instruments' conflict could come from" in out, err


@pytest.mark.parametrize("name", TYPES)
def test_compensate_refuses_the_disputed_deviations_on_every_machine(campaigns, checks, name, run_cli, tmp_path):
    """Exit 2 and one line naming a disputed deviation and the way out; with --accept-disagreement it compensates
    and warns."""
    path = tmp_path / "shifted.toml"
    save_campaign(shifted(campaigns[name], 25.0), path)
    disputed = checks(name, 25.0).disputed
    out_nc = tmp_path / "out.nc"
    code, out, err = run_cli("compensate", path, PROGRAM[name], "-o", out_nc)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--accept-disagreement" in err and any(d in err for d in disputed) and "χ²" in err
    assert not out_nc.exists()
    code, out, err = run_cli("compensate", path, PROGRAM[name], "-o", out_nc, "--accept-disagreement")
    assert code == 0, err
    assert "compensated although" in err and out_nc.exists()


def test_a_group_its_flat_terms_leave_no_free_direction_is_unchecked(campaigns):
    """W-ball clamping known to 1 mm only (instead of 35 µm): on the vertical turn-mill's runs about the W ball on
    the B axis its offsets span both eccentricities, so those groups have no χ² — *unchecked*, no p-value, not a
    disagreement, and the text names them."""
    c = copy.deepcopy(campaigns["vertical-turn-mill"])
    for k in ("xW", "yW", "zW"):
        c.priors[k] = {"dist": "normal", "mean": 0.0, "sd": 1.0}
    chk = check_instruments(c, explain=False)
    g = chk.consistency.groups
    unchecked = g[g["verdict"] == "unchecked"]
    assert len(unchecked) and (unchecked["dof"] == 0).all() and unchecked["p_value"].isna().all()
    assert chk.agree and "Not checked: " + ", ".join(unchecked["group"]) in chk.to_text()
    assert (g.loc[g["verdict"] != "unchecked", "dof"] > 0).all()
