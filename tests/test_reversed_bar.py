"""A run's bar reversed, the T ball on the other side of the W ball (docs/machines.md, docs/campaign-format.md):
read, written back and modelled on every described machine; the thesis' BT and its Fig 2.6 CR are such runs
(tests/test_chain.py holds the kinematics against thesis Tables 2.2/2.3)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.io import load_campaign, save_campaign
from mtmcal_bayes.models.ballbar import ChainBallbarModel
from tests.variants import demo_with_first_run_key

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


@pytest.mark.parametrize("machine", TYPES)
def test_a_reversed_run_is_read_written_and_seen_otherwise(machine, tmp_path):
    """The first tangential run reversed (its T ball trailing, as the thesis' BT): written as ``reversed = true``,
    read back so; the chain predicts it otherwise (the same deviations move its eccentricities differently: beyond
    1e-9 mm, where the rest agree to rounding, 1e-12 mm), every other run as before."""
    c = load_campaign(api.demo_campaign(machine))
    i = next(k for k, r in enumerate(c.ballbar.runs) if r.pattern.endswith("T"))
    other = copy.deepcopy(c)
    other.ballbar.runs[i].reversed = True
    path = tmp_path / "reversed.toml"
    save_campaign(other, path)
    assert path.read_text(encoding="utf-8").count("reversed = true") == 1
    back = load_campaign(path)
    assert [k for k, r in enumerate(back.ballbar.runs) if r.reversed] == [i]
    a, b = ChainBallbarModel(c), ChainBallbarModel(back)
    theta = np.random.default_rng(3).normal(size=(4, len(a.space))) * a.space.display_scale() * 20
    first = [j for j, k in enumerate(a.observations.keys) if k.run == i]
    rest = [j for j, k in enumerate(a.observations.keys) if k.run != i]
    pa, pb = a.predict(theta), b.predict(theta)
    assert np.abs(pa[:, rest] - pb[:, rest]).max() < 1e-12
    assert np.abs(pa[:, first] - pb[:, first]).max() > 1e-9  # mm: another bar, another sensitivity
    assert "reversed" in b.observations.keys[first[0]].label


def test_reversed_must_be_true_or_false(tmp_path, run_cli):
    bad = tmp_path / "bad.toml"
    bad.write_text(demo_with_first_run_key("trunnion", 'reversed = "yes"'), encoding="utf-8")
    code, _, err = run_cli("sample", str(bad), "--sampler", "exact", "--seed", "1")
    assert code == 2 and "Traceback" not in err
    assert "ballbar.runs[0].reversed" in err.strip().splitlines()[-1]
