"""One candidate catalogue for every machine (issue 42): the thesis machine's is the engine's under the rules its
campaign format states, its feasibility the engine's commands held to the thesis' printed Tables 2.2/2.3."""

from __future__ import annotations

import copy
from collections import Counter

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.patterns import B_PATTERNS
from mtmcal_bayes.planning.catalogue import catalogue, feasibility_check
from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands as printed_commands

TYPES = ("thesis", "trunnion", "vertical-turn-mill", "head-head")


def _campaign(name):
    return api.campaign_of(None if name == "thesis" else api.demo_campaign(name))


@pytest.fixture(scope="module")
def campaigns():
    return {name: _campaign(name) for name in TYPES}


@pytest.mark.parametrize("name", TYPES)
def test_every_candidate_has_its_own_name_and_a_new_run_its_own_geometry(campaigns, name):
    """On every built-in type: no two candidates share a name (a repeat names its held axes), and no two new runs
    are the same run (pattern, set-up, mount, bar, arc, held axes); no new set-up has an existing one's tool length
    (the campaign format refuses a second set-up of one length, so a designed campaign naming one could not be read
    back: the trunnion demo's T1 + 50 mm is its T2, whose runs are candidates of their own)."""
    cands = catalogue(campaigns[name])
    names = Counter(c.name for c in cands)
    assert not [n for n, k in names.items() if k > 1]
    new = Counter((c.pattern, c.setup.id, c.mount.id, c.length, c.arc_deg, c.hold_deg)
                  for c in cands if c.repeat_of is None)
    assert not [k for k, n in new.items() if n > 1]
    setups = campaigns[name].ballbar.setups
    assert not [c.name for c in cands if c.setup.id not in setups and c.setup.R_B in {s.R_B for s in setups.values()}]
    base = campaigns[name].primary_setup()
    for c in cands:
        if c.kind == "tool length":
            assert c.setup.R_B == pytest.approx(base.R_B + c.extension, abs=1e-12) and c.extension > 0


def test_the_thesis_catalogue_follows_its_campaign_format(campaigns):
    """Step 5's extension bars keep R_B + Z_T and X_T (Table 4.3), a B pattern measures with the W ball on the C axis
    (Table 2.2), no run holds the other axis away from 0 and every run has the thesis' grid; the engine's own
    placements and held poses do not appear, the thesis' other R_C and bar lengths do."""
    thesis = campaigns["thesis"]
    base = thesis.primary_setup()
    cands = catalogue(thesis)
    assert len(cands) == 52
    kinds = Counter(c.kind for c in cands)
    assert kinds == {"tool length": 24, "existing setup": 3, "repeats": 5, "other pattern": 8, "other R_C": 4,
                     "bar length": 8}
    for c in cands:
        assert not c.hold_deg and c.arc_deg is None, c.name
        if c.pattern in B_PATTERNS:
            assert c.mount.R_C == 0.0, c.name
        if c.kind == "tool length":
            assert c.setup.R_B + c.setup.Z_T == pytest.approx(base.R_B + base.Z_T, abs=1e-9)
            assert c.setup.X_T == base.X_T
    # the trunnion's catalogue (the engine's own rules) has what the thesis' format cannot express
    assert {"held axes", "other placement"} <= {c.kind for c in catalogue(campaigns["trunnion"])}


def _printed_spans(c, campaign) -> dict[str, float]:
    """The X, Y, Z spans (mm) of a thesis candidate from the commands as Tables 2.2/2.3 print them."""
    m = printed_commands(c.pattern, R_B=c.setup.R_B, Z_C=c.mount.Z_C, R_C=c.mount.R_C, L_B=c.length,
                         cr_geometry=campaign.ballbar.cr_geometry)
    return {a: float(np.ptp(getattr(m, a))) for a in "XYZ"}


@pytest.mark.parametrize("variant", ["as published", "CR outside (Fig 2.6)", "C mount at R_C 150 mm"])
def test_the_thesis_feasibility_is_the_span_of_its_printed_commands(campaigns, variant):
    """The one feasibility check, on the thesis machine (its travels given as lengths, not where the axes sit):
    a candidate is feasible exactly when the span of each of its X, Y, Z commands, as Tables 2.2/2.3 print them,
    fits the travel; the engine computes the commands from the chain, the oracle from the printed tables."""
    thesis = copy.deepcopy(campaigns["thesis"])
    if variant == "CR outside (Fig 2.6)":
        thesis.ballbar.cr_geometry = "RC+LB"
    elif variant == "C mount at R_C 150 mm":
        thesis.ballbar.mounts["C"].R_C = 150.0
    travel = thesis.machine.travel
    check = feasibility_check(thesis)
    verdicts = []
    for c in catalogue(thesis):
        spans = _printed_spans(c, thesis)
        ok, why = check(c)
        assert ok == all(spans[a] <= travel[a] + 1e-6 for a in "XYZ"), (c.name, spans, why)
        verdicts.append(ok)
    assert not all(verdicts)  # each variant has runs beyond the travels: the check can fail
