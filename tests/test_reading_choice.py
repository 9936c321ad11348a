"""A number that rests on a choice says so (issue 35): the campaign's record of a reading chosen over another.

The format (``alternative_convention``, ``alternative_reason``: checked, saved back, dropped from synthetic data),
the built-in campaign's record against the evidence that made the choice, and which quantities the exact
posteriors mark.  The marks as ``sample``, ``report`` and ``compensate`` show them: test_metrology.py,
test_report.py, test_compensation.py.
"""

import copy

import numpy as np
import pytest

from mtmcal_bayes import InputError, load_campaign, parse_campaign, save_campaign
from mtmcal_bayes.analysis import CampaignAnalysis
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.conventions import run_matrix
from mtmcal_bayes.inference import reading_choice
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.posterior import conflict
from mtmcal_bayes.simulation import synthetic_campaign

from . import variants

#: thesis-notes' label of the best rejected reading: B = 0° drawn at +X, 90° at −Z, the BY bar on the −Y side
REJECTED = ("B0=+X,B90=-Z", True)


def _evidence(campaign) -> float:
    post = LogPosterior(campaign, "linear", data="both")
    return conflict._marginal(post, cells=12).log_evidence(post.likelihood.y)


def test_the_recorded_alternative_is_the_best_rejected_reading(thesis):
    """The record is thesis-notes' row "B0=+X,B90=−Z, BY bar at −Y", and that reading has the highest marginal
    likelihood of every reading of the B runs but the chosen one, and a higher one than the chosen (it was rejected
    by the thesis' Sec 4.4.2, not by the data)."""
    alt = thesis.alternative_reading()
    row = conflict.reread(thesis, *REJECTED)
    for a, b in zip(alt.ballbar.runs, row.ballbar.runs):
        assert np.allclose(run_matrix(a, alt.ballbar), run_matrix(b, row.ballbar)), a.label
    evidence = {(o, y): _evidence(moved) for o in conflict.ORIENTATIONS for y in (False, True)
                if not conflict._same_reading(moved := conflict.reread(thesis, o, y), thesis)}
    assert max(evidence, key=evidence.get) == REJECTED
    assert evidence[REJECTED] > _evidence(thesis)


def test_the_record_is_saved_back_and_read_alike(thesis, tmp_path):
    save_campaign(thesis, tmp_path / "c.toml")
    back = load_campaign(tmp_path / "c.toml")
    assert [r.alternative_convention for r in back.ballbar.runs] == [r.alternative_convention for r in thesis.ballbar.runs]
    assert back.ballbar.alternative_reason == thesis.ballbar.alternative_reason != ""
    assert [r.label for r in back.ballbar.reading_choices()] == ["BX@RB1/B", "BY@RB1/B"]
    plain = parse_campaign(variants.without_reading_choice())
    save_campaign(plain, tmp_path / "plain.toml")
    assert "alternative" not in (tmp_path / "plain.toml").read_text(encoding="utf-8")
    assert plain.alternative_reading() is None
    fewer = copy.deepcopy(thesis)  # the runs read by choice removed (a machine's set-ups kept): the reason goes too
    fewer.ballbar.runs = [r for r in fewer.ballbar.runs if not r.alternative_convention]
    save_campaign(fewer, tmp_path / "fewer.toml")
    assert load_campaign(tmp_path / "fewer.toml").ballbar.alternative_reason == ""


@pytest.mark.parametrize("edit, key, fragment", [
    (lambda t: t.replace('convention = "thesis"\n', 'convention = "thesis"\nalternative_reason = "a guess"\n', 1),
     "ballbar.alternative_reason", "no run names an alternative_convention"),
    (lambda t: t.replace('convention = "thesis"\n', 'convention = "thesis"\nalternative_reason = """one\ntwo"""\n', 1),
     "ballbar.alternative_reason", "one line"),
    (lambda t: t.replace('pattern = "CA"             # C axis, axial measurement (step 4)\n',
                         'pattern = "CA"\nalternative_convention = "C0=+X,C90=+X"\n', 1),
     "ballbar.runs[3].alternative_convention", "cannot both be drawn along X"),
])
def test_a_bad_record_is_one_line_naming_the_key(edit, key, fragment):
    with pytest.raises(InputError) as err:
        parse_campaign(edit(variants.without_reading_choice()), source="c.toml")
    assert f"c.toml: {key}: " in str(err.value) and fragment in str(err.value)


def test_a_planned_run_records_no_alternative():
    planned = ('[[ballbar.runs]]\npattern = "BZ"\nsetup = "RB1"\nmount = "B"\nplanned = true\nrepeats = 2\n'
               'alternative_convention = "thesis"\n\n')
    text = variants.without_reading_choice().replace(variants._PROBE, planned + variants._PROBE, 1)
    with pytest.raises(InputError, match=r"c\.toml: ballbar\.runs\[5\]\.alternative_convention: a planned run"):
        parse_campaign(text, source="c.toml")


def test_the_fused_marks_follow_the_weighed_posteriors(thesis):
    """The fused posterior's marks from the shifts of the candidates' own posteriors (conflict.weigh, a separate
    construction): exactly the quantities moving more than their sd, with the alternative's means."""
    table = CampaignAnalysis(thesis, data="both").reading_choice(list(conflict.SHOWN[:2]) + list(conflict.SHOWN[3:]))
    chosen, other = conflict.weigh(thesis, "c", "", ""), conflict.weigh(thesis.alternative_reading(), "a", "", "")
    moved = {n for n in table.index if abs(other.quantities[n][0] - chosen.quantities[n][0]) > chosen.quantities[n][1]}
    assert set(reading_choice.marked(table)) == moved and {"alpha_XB", "gamma_XB", "dy_CZ"} <= moved
    for n in table.index:
        assert table.loc[n, reading_choice.ALTERNATIVE] == pytest.approx(other.quantities[n][0], abs=0.01)


def test_without_a_choice_or_with_probe_data_nothing_is_marked(thesis):
    names = ["alpha_XB", "alpha_BT", "dy_CZ"]
    assert CampaignAnalysis(thesis, data="probe").reading_choice(names) is None  # the ball-bar reading plays no part
    assert CampaignAnalysis(parse_campaign(variants.without_reading_choice())).reading_choice(names) is None
    assert reading_choice.marked(CampaignAnalysis(thesis).reading_choice(names)) == names


def test_synthetic_campaigns_record_no_choice(thesis):
    """Simulated offsets are written in the reading each run names: nothing was chosen."""
    out = synthetic_campaign(thesis, Truth())
    assert out.alternative_reading() is None and out.ballbar.alternative_reason == ""
    assert thesis.alternative_reading() is not None  # the original is not touched
