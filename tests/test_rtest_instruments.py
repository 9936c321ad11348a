"""``instruments`` with three instruments (docs/rtest.md, docs/probe.md): every pair of the ball bar, the touch probe
and the R-test checked, each against the other's posterior, on campaigns of two built-in types simulated from one
truth (the demo's, with R-test runs added); a shifted group of R-test positions is flagged by the pairs with the
R-test and by them only; the ball bar / probe pair is the two-instrument check unchanged."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.campaign_writer import save_campaign
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.posterior.instrument_check import check_instruments
from mtmcal_bayes.simulation.simulate import synthetic_campaign

from .test_rtest import campaign_text
from .test_rtest_ncgen import NESTS, _runs

TYPES = ("trunnion", "head-head")
PAIRS = ["ball bar / touch probe", "ball bar / R-test", "touch probe / R-test"]
#: the shift of the last two positions of the first R-test run (5 positions, zeroed at the first) along X, µm.
#: Measured on these campaigns (seed 5): p = 0.04 at 15 µm, 0.002–0.008 at 20 µm, 1e-5–1e-4 at 30 µm, given either
#: other instrument's posterior.  The check's power is set by the R-test's discrepancy scale: under its half-normal
#: prior (scale 2 µm) an R-test noisier than assumed explains up to about 15 µm on two positions, as for the probe
#: (docs/probe.md); 30 µm is flagged with a margin of two orders of magnitude below p = 0.01.
SHIFT_UM = 30.0
UM = 1e-3


def _three(machine: str, seed: int = 5):
    """The demo campaign of ``machine`` with the R-test runs of tests/test_rtest_ncgen.py, every instrument simulated
    (chain, with noise) from the demo's truth."""
    rt = campaign_text(machine, _runs(machine), nests=NESTS)
    c = parse_campaign(Path(demo_campaign(machine)).read_text(encoding="utf-8") + "\n" + rt[rt.index("[rtest]"):])
    return synthetic_campaign(c, c.truth, "chain", noise=True, seed=seed)


def _shifted(campaign, shift_um: float = SHIFT_UM):
    c = copy.deepcopy(campaign)
    c.rtest.runs[0].displacements[:, -2:, 0] += shift_um * UM
    return c


@pytest.fixture(scope="module")
def checks():
    made = {}

    def get(machine: str, shift_um: float = 0.0):
        if (machine, shift_um) not in made:
            c = _three(machine)
            made[machine, shift_um] = (c, check_instruments(_shifted(c, shift_um) if shift_um else c, explain=False))
        return made[machine, shift_um]

    return get


@pytest.mark.parametrize("machine", TYPES)
def test_every_pair_of_three_instruments_agrees_on_one_truth(checks, machine):
    """Every pair is checked both ways (each R-test run given the ball bar's and given the probe's posterior, each
    ball-bar run and probe group given the R-test's), every group at p ≥ 0.01; the text and the JSON name each pair;
    each instrument has its discrepancy scale."""
    c, chk = checks(machine)
    g = chk.consistency.groups
    assert list(dict.fromkeys(g["pair"])) == PAIRS
    runs = [f"R-test {r.id}" for r in c.rtest.runs]
    for pair, given in (("ball bar / R-test", "ball-bar"), ("touch probe / R-test", "probe")):
        rows = g[(g["pair"] == pair) & (g["given"] == given)]
        assert list(rows["group"]) == runs
    assert set(g.loc[g["given"] == "R-test", "pair"]) == set(PAIRS[1:])
    assert (g["p_value"] >= 0.01).all(), g[["pair", "group", "given", "p_value"]]
    assert chk.agree and not chk.disputed
    text = chk.to_text()
    assert all(f"  {p}:\n" in text for p in PAIRS) and "agree on every deviation" in text
    doc = chk.to_json()
    assert {r["pair"] for r in doc["consistency"]["groups"]} == set(PAIRS)
    assert {r["pair"] for r in doc["consistency"]["readings"]} == set(PAIRS)
    assert set(chk.scales) == {"sigma_model", "sigma_model_probe", "sigma_model_rtest"}


@pytest.mark.parametrize("machine", TYPES)
def test_a_shifted_group_of_rtest_positions_is_flagged_by_the_pairs_with_the_rtest(checks, machine):
    """The last two positions of R-test run r1 moved SHIFT_UM along X: r1 disagrees given the ball bar's and given
    the probe's posterior (p < 0.01; before, p ≥ 0.01), named in the text and the disputed deviations' verdicts and
    in compensate's refusal; the ball bar / probe pair's rows are those of the unshifted campaign, all agreeing."""
    _, before = checks(machine)
    _, after = checks(machine, SHIFT_UM)
    g = after.consistency.groups
    r1 = g[g["group"] == "R-test r1"].set_index("given")["p_value"]
    assert set(r1.index) == {"ball-bar", "probe"} and (r1 < 0.01).all(), r1
    b = before.consistency.groups
    assert (b.loc[b["group"] == "R-test r1", "p_value"] >= 0.01).all()
    assert set(g.loc[g["verdict"] == "disagree", "pair"]) <= set(PAIRS[1:])
    assert {p for p in PAIRS[1:] if "R-test r1" in set(g.loc[(g["pair"] == p) & (g["verdict"] == "disagree"),
                                                              "group"])} == set(PAIRS[1:])
    bp = g[g["pair"] == PAIRS[0]].reset_index(drop=True)
    assert (bp["verdict"] == "agree").all()
    assert bp.equals(b[b["pair"] == PAIRS[0]].reset_index(drop=True))
    assert not after.agree and after.disputed and "R-test r1" in after.consistency.disagreeing
    assert any("R-test r1 given the" in s for v in after.disputed.values() for s in v)
    refusal = after.refusal(list(after.disputed))
    assert "R-test of" in refusal and "touch probe and the ball bar" not in refusal


@pytest.mark.parametrize("machine", TYPES)
def test_the_ball_bar_probe_pair_is_the_two_instrument_check(checks, machine):
    """The ball bar / probe rows of the three-instrument check are the check of the same campaign without its R-test
    runs, row for row; that check's text and JSON name no pair (the two-instrument output is unchanged)."""
    c, chk = checks(machine)
    two = copy.deepcopy(c)
    two.rtest = None
    alone = check_instruments(two, explain=False)
    g = chk.consistency.groups
    bp = g[g["pair"] == PAIRS[0]].drop(columns="pair").reset_index(drop=True)
    assert bp.equals(alone.consistency.groups)
    assert "pair" not in alone.consistency.groups and "pair by pair" not in alone.to_text()
    assert all("pair" not in r for r in alone.to_json()["consistency"]["groups"])


def test_the_cli_checks_three_instruments_and_refuses_one(run_cli, tmp_path):
    """``instruments CAMPAIGN --json`` on a saved three-instrument campaign names the pairs; a campaign of R-test
    runs alone: exit 2, one line, no traceback."""
    path = tmp_path / "three.toml"
    save_campaign(_three("trunnion"), path)
    code, out, err = run_cli("instruments", path, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["agree"] is True and list(dict.fromkeys(r["pair"] for r in doc["consistency"]["groups"])) == PAIRS
    alone = tmp_path / "rtest.toml"
    alone.write_text(campaign_text("trunnion", _runs("trunnion"), nests=NESTS), encoding="utf-8")
    code, out, err = run_cli("instruments", alone)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "beside its R-test runs" in err and "Traceback" not in err


def _explained(check, pair: str) -> list[dict]:
    """The candidates of ``pair``'s explanations in a three-instrument check's JSON, best first."""
    doc = check.to_json()["explanations"]
    assert doc is not None and pair in doc, (pair, None if doc is None else list(doc))
    return doc[pair]["candidates"]


def test_a_reversed_sign_of_the_rtest_readings_is_the_explanation_the_data_prefer():
    """Every R-test reading negated (a device exporting nest − sphere) on the trunnion: both pairs with the R-test
    disagree and each pair's best explanation is the reversed sign, decisively (log Bayes factor > 4.6 over the
    campaign as given); the ball bar / probe pair agrees and has none.  On the trunnion every rotary axis carries the
    workpiece, so the two frames read alike and the frame is not weighed; the sessions are weighed per rotary axis,
    the 20″ clamping difference only beside the ball bar."""
    c = copy.deepcopy(_three("trunnion"))
    for run in c.rtest.runs:
        run.displacements = -run.displacements
    chk = check_instruments(c)
    assert set(chk.conflicts) == {("ballbar", "rtest"), ("probe", "rtest")}
    for pair in PAIRS[1:]:
        cands = _explained(chk, pair)
        assert cands[0]["name"] == "R-test readings' sign reversed", [(x["name"], x["log_bayes_factor"]) for x in cands]
        assert cands[0]["log_bayes_factor"] > 4.6
        names = [x["name"] for x in cands]
        assert "R-test in the other frame" not in names
        assert any(n.startswith("sessions differ 20″") for n in names) == pair.startswith("ball bar")
        assert (pair.startswith("touch probe") and any(n.startswith("stylus length") for n in names)) or \
            not any(n.startswith("stylus length") for n in names)
    assert "Where the ball bar's and the R-test's conflict could come from" in chk.to_text()


def test_rtest_readings_in_the_other_frame_are_the_explanation_the_data_prefer():
    """On the head-head (both rotary axes carry the spindle, so the "tool" and "machine" frames differ by the head's
    turn) R-test runs read in the machine frame but labelled "tool": the pairs with the R-test disagree and each
    one's best explanation is the other frame (alone, or with a session difference on top, which the data cannot
    tell apart: within a log Bayes factor of 2.3), decisively over the campaign as given; on the campaign as
    simulated the check agrees and explains nothing."""
    c = _three("head-head")
    assert check_instruments(c).conflicts == {}
    flipped = copy.deepcopy(c)
    for run in flipped.rtest.runs:
        run.frame = "machine" if run.frame == "tool" else "tool"
    chk = check_instruments(flipped)
    assert ("ballbar", "rtest") in chk.conflicts
    for pair, analysis in chk.conflicts.items():
        best = analysis.candidates[0]
        assert best.name.endswith("R-test in the other frame"), analysis.table().head(4)
        frame = next(x for x in analysis.candidates if x.name == "R-test in the other frame")
        assert frame.log_evidence - analysis.given.log_evidence > 4.6
        assert best.log_evidence - frame.log_evidence < 2.3


def test_compensate_checks_the_rtest_beside_one_other_instrument():
    """A trunnion campaign of the R-test beside the ball bar (its probe runs dropped), its run r1
    shifted SHIFT_UM: compensate checks the pair before it corrects and refuses, naming the R-test and
    ``accept_disagreement``.  (It checked only a campaign with the ball bar and the probe: this pair went
    unchecked.)"""
    import mtmcal_bayes as mb
    from mtmcal_bayes.errors import ParameterError

    c = _shifted(_three("trunnion"))
    c.probe = None
    program = Path(__file__).parent / "data" / "machines" / "trunnion-five-axis-12.nc"
    with pytest.raises(ParameterError) as refused:
        mb.compensate(program, campaign=c)
    assert "accept_disagreement" in str(refused.value) and "R-test" in str(refused.value)
