"""One touch probe for every machine (SPEC §19, §20): on every built-in type a campaign's probe is its runs and styli,
whatever format it was read from; the owner rule of the probe's nuisance terms, the probe layout and the probe
catalogue are the same functions on each, and a campaign written back and read again has the same runs."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.campaign import ProbeRun
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, demo_campaign
from mtmcal_bayes.machines.probe_terms import probe_terms, stylus_terms
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.models.probe import ProbeLayout
from mtmcal_bayes.parameters import ParameterSpace
from mtmcal_bayes.planning.design import Planner
from mtmcal_bayes.planning.probe_catalogue import ProbeCandidate, probe_catalogue, probe_feasibility

PACKAGE = Path(mb.__file__).parent


def _campaign(name: str):
    return mb.load_campaign(demo_campaign(name))  # the thesis machine's: the thesis campaign


@pytest.fixture(scope="module", params=sorted(BUILTIN_TYPES))
def campaign(request):
    return _campaign(request.param)


def test_every_type_reads_its_probe_as_runs_and_styli(campaign):
    """The same record on every type: runs of one class with the same fields, each naming a stylus of the probe (a
    length and a ball radius), positions one per angle of each indexed axis of the machine, readings r × a × 3."""
    p = campaign.probe
    assert p.runs and all(type(run) is ProbeRun for run in p.runs)
    letters = {a.letter for a in campaign.machine.description.rotary_axes}
    for run in p.runs:
        assert run.stylus in p.styli and p.centre_length(run.stylus) > 0
        assert set(run.angles) <= letters and {len(v) for v in run.angles.values()} == {run.positions}
        assert run.centres.shape[1:] == (run.positions, 3) and np.asarray(run.sphere).shape == (3,)
    assert not campaign.gaps()


def test_the_owner_rule_is_one(campaign):
    """Both spaces (the thesis plug-in's and the engine's) take the probe's terms from the one rule, which asks each
    run: every stylus once, in the order its runs first use it, with the terms its runs state (else the machine's),
    then each run id once with its sphere and datum terms; the layout's owners are the same."""
    desc = campaign.machine.description
    p = campaign.probe
    terms = probe_terms(desc, p)
    probe_names = lambda space: [q.name for q in space.parameters if q.group == "probe"]  # noqa: E731
    assert probe_names(ParameterSpace.for_campaign(campaign, data="probe")) == \
        probe_names(described_space(campaign, data="probe")) == [f"{b}[{o}]" for o, b in terms]
    styli = list(dict.fromkeys(run.stylus for run in p.runs))
    ids = list(dict.fromkeys(run.id for run in p.runs))
    assert list(dict.fromkeys(o for o, _ in terms)) == styli + ids
    for run in p.runs:
        own = run.stylus_terms if run.stylus_terms is not None else stylus_terms(desc)
        assert [b for o, b in terms if o == run.stylus][:len(own)] == list(own)
        assert [b for o, b in terms if o == run.id][-len(run.sphere_terms) - len(run.datum_terms):] == \
            [*run.sphere_terms, *run.datum_terms]
    layout = ProbeLayout(campaign)  # the engine's layout, with the chain's kernel, on every type
    assert list(layout.run) == [run.id for run in p.runs for _ in range(run.positions)]
    assert list(layout.stylus) == [run.stylus for run in p.runs for _ in range(run.positions)]
    assert len(layout.observations) == 3 * sum(run.positions for run in p.runs)


def test_written_back_and_read_again_the_runs_are_the_same(campaign, tmp_path):
    """Saved in its machine's campaign format (the thesis': its own probe sections) and read again: the same runs,
    field by field, and the same styli."""
    path = tmp_path / "c.toml"
    mb.save_campaign(campaign, path)
    again = mb.load_campaign(path)
    a, b = campaign.probe, again.probe
    assert (a.styli, a.ball_radii) == (b.styli, b.ball_radii)
    assert len(a.runs) == len(b.runs)
    for r1, r2 in zip(a.runs, b.runs):
        for f in dataclasses.fields(ProbeRun):
            x, y = getattr(r1, f.name), getattr(r2, f.name)
            if f.name == "angles":
                assert list(x) == list(y)
                for k in x:
                    np.testing.assert_allclose(x[k], y[k], rtol=1e-12, atol=1e-15)
            elif isinstance(x, np.ndarray):
                np.testing.assert_allclose(x, y, rtol=1e-11, atol=1e-12, equal_nan=True)
            else:
                assert x == y, f.name


def test_one_probe_catalogue(campaign):
    """One catalogue on every type: each rotary axis of the description indexed by the campaign's first stylus at
    its first run's sphere; each candidate's own terms are the owner rule's of a campaign holding it alone, and its
    rows over the planner's space are finite and move the readings."""
    desc = campaign.machine.description
    cands = probe_catalogue(campaign)
    assert cands and all(type(c) is ProbeCandidate for c in cands)
    assert {c.axis for c in cands} == {a.letter for a in desc.rotary_axes}
    first = next(iter(campaign.probe.styli))
    assert {c.stylus for c in cands} == {first}
    assert min(c.stylus_length for c in cands) == pytest.approx(campaign.probe.centre_length(first))
    for c in cands[:2]:
        assert c.terms(campaign) == probe_terms(desc, c.alone(campaign).probe)
    feasible = [c for c in cands if probe_feasibility(c, campaign)[0]]
    planner = Planner(campaign, feasible[:1], data="probe")
    (A, noise), = planner.candidate_rows()
    assert np.isfinite(A).all() and np.abs(A).max() > 0.1 and (noise > 0).all()


def test_no_module_outside_the_plugins_names_the_thesis_probe_sections():
    """The thesis' C-axis and B-axis runs are its plug-in's to read: the engine sees runs and styli only."""
    named = [f"{path.relative_to(PACKAGE)}:{k + 1}" for path in sorted(PACKAGE.rglob("*.py"))
             if "plugins" not in path.relative_to(PACKAGE).parts
             for k, line in enumerate(path.read_text(encoding="utf-8").splitlines())
             if re.search(r"\b[cb]_axis\b", line)]
    assert not named, named


@pytest.mark.parametrize("dropped, says", [("probe.c_axis", "No C-axis touch-probe data"),
                                           ("probe.b_axis", "No B-axis touch-probe data")])
def test_the_report_names_the_thesis_probe_run_a_campaign_lacks(dropped, says):
    """The deterministic method's probe sections are its plug-in's to name: a thesis campaign without one of its
    runs says which values Eqs 5.1–5.19 then lack, and with both nothing is said."""
    from mtmcal_bayes.plugins.thesis.identification import identify
    from mtmcal_bayes.reporting.missing import missing_data
    from tests.variants import sections_dropped, thesis_text

    full = mb.parse_campaign(thesis_text(), "<thesis>")
    assert not [s for s in missing_data(full, identify(full)) if "touch-probe data" in s]
    text = thesis_text().replace('stylus = "short"\n', 'R_B_mm = 382.95\n')  # the C-axis run's own stylus
    c = mb.parse_campaign(sections_dropped(text, dropped), "<thesis>")
    assert [s for s in missing_data(c, identify(c)) if "touch-probe data" in s] == \
        [s for s in identify(c).missing_probe] and says in identify(c).missing_probe[0]


def test_a_fleet_digest_follows_the_dprnt_files_of_every_run(tmp_path):
    """A campaign's content digest covers the DPRNT files its probe runs name (the thesis' C-axis run here): a
    changed file changes it."""
    import shutil

    from mtmcal_bayes.datasets import data_path
    from mtmcal_bayes.fleets.discover import content_digest
    from tests.variants import thesis_text

    for a in (0, 90, 180, 270):
        shutil.copy(data_path("fig5_13_dprnt_output.txt"), tmp_path / f"c{a}.txt")
    text = thesis_text()
    start, end = text.index("[probe.c_axis]"), text.index("[probe.b_axis]")
    run = ('[probe.c_axis]\nR_C_mm = 100.0\nZ_C_mm = 64.838\naxis_xy_mm = [-490.0, 0.0]\nstylus = "short"\n'
           'angles_deg = [0.0, 90.0, 180.0, 270.0]\ndprnt = ["c0.txt", "c90.txt", "c180.txt", "c270.txt"]\n\n')
    path = tmp_path / "c.toml"
    path.write_text(text[:start] + run + text[end:], encoding="utf-8")
    c = mb.load_campaign(path)
    assert c.probe.dprnt_files() == ["c0.txt", "c90.txt", "c180.txt", "c270.txt"]
    before = content_digest(path, c)
    (tmp_path / "c270.txt").write_text((tmp_path / "c270.txt").read_text() + "\n", encoding="utf-8")
    assert content_digest(path, c) != before
