"""docs/campaign-format.md describes what the reader accepts: its example of a described machine's campaign loads
as it stands, with every key read into the campaign, and its `[priors]` example loads on the thesis machine."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import PlannedRun
from mtmcal_bayes.datasets import builtin_campaign_text

DOC = Path(__file__).resolve().parents[1] / "docs" / "campaign-format.md"


def _example(marker: str) -> str:
    """The TOML block that follows ``<!-- example: marker -->`` in the doc."""
    text = DOC.read_text(encoding="utf-8")
    m = re.search(rf"<!-- example: {re.escape(marker)} -->\s*```toml\n(.*?)```", text, re.S)
    assert m, f"no example {marker!r} in {DOC}"
    return m.group(1)


def test_the_documented_campaign_of_a_described_machine_loads(tmp_path):
    path = tmp_path / "campaign.toml"
    path.write_text(_example("described campaign"), encoding="utf-8")
    c = mb.load_campaign(path)
    m = c.machine
    assert m.description.builtin == "trunnion" and (m.name, m.serial, m.type) == (
        "cell 3 trunnion", "T-0417", "five-axis trunnion")
    assert c.date.year == 2026 and c.temperature_C == 20.4
    bb = c.ballbar
    assert bb.feed_mm_per_min == 1000.0 and set(bb.setups) == {"T1", "T2"}
    assert np.allclose(bb.mounts["W1"].position, [0.0, 60.0, 30.0])
    ar, cr = bb.runs
    assert np.allclose(ar.arc_deg, np.arange(-60.0, 30.5, 1.0)) and set(ar.repeats) == {"ey", "ez"}
    assert cr.hold_deg == {"A": -45.0} and len(cr.arc_deg) == 72  # C's own grid: a turn by 5°
    (planned,) = bb.planned
    assert isinstance(planned, PlannedRun) and (planned.repeats, planned.order) == (3, 1)
    probe = c.probe
    assert probe.styli["S1"] == 153.0 and probe.ball_radii["S1"] == 3.0  # as written: to the ball's tip
    assert probe.centre_length("S1") == pytest.approx(150.0) and probe.centre_length("long") == 200.0
    sphere, long = probe.runs
    assert sphere.id == "sphere" and sphere.centres.shape == (1, 4, 3) and long.stylus == "long"
    assert set(c.priors) == {"E_C0C", "dRB", "sigma_model_probe"}
    assert c.design.targets == {"E_B0A": 2.0, "E_X0C": 1.5} and c.design.contraction == 0.5
    t = c.truth
    assert t.deviations["E_Y0A"] == pytest.approx(units.to_internal(15.0, "um"))
    assert set(t.setups["T1"]) == {"dRB"} and set(t.mounts["W1"]) == {"xW"}
    assert set(t.probe["S1"]) == {"yS"} and set(t.probe["sphere"]) == {"zP"}


def test_the_documented_campaign_of_a_described_machine_is_analysed(tmp_path):
    """Loading is not all: the example's measurements go into the exact posterior of both instruments."""
    path = tmp_path / "campaign.toml"
    path.write_text(_example("described campaign"), encoding="utf-8")
    r = mb.sample(path, sampler="exact", seed=1)
    assert r.data == "both" and "E_B0A" in r.summary.index


def test_the_documented_priors_load_on_the_thesis_machine():
    text = DOC.read_text(encoding="utf-8")
    block = re.search(r"### `\[priors\]` \(optional\).*?```toml\n(.*?)```", text, re.S).group(1)
    thesis = builtin_campaign_text()[0]
    head, rest = thesis.split("[priors]\n", 1)
    tail = rest[rest.index("\n["):]  # the thesis' own priors dropped: the doc's in their place
    c = mb.io.parse_campaign(head + block + tail, "doc.toml")
    assert set(c.priors) == {"beta_XB", "xW", "sigma_model", "dRB"}
