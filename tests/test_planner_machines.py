"""The one closed-form planner on every built-in type (issue 42): a candidate's rows are those of its run in the
campaign, whichever other candidates the planner values beside it; targets by name or ISO symbol on every machine."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.errors import ParameterError
from mtmcal_bayes.inference.log_posterior import parameter_space
from mtmcal_bayes.models import build_model
from mtmcal_bayes.planning.design import Planner, target_names
from mtmcal_bayes.planning.machine_kit import catalogue_of

TYPES = ("integrex-i200", "trunnion", "vertical-turn-mill", "head-head")


@pytest.fixture(scope="module", params=TYPES)
def campaign(request):
    return api.campaign_of(api.demo_campaign(request.param))


def _sample(campaign) -> list:
    """New-run candidates of several kinds at the campaign's bar, at most one per mount the campaign has not used."""
    seen_kinds, new_mounts, out = set(), set(), []
    for c in catalogue_of(campaign):
        if c.repeat_of is not None or c.length != campaign.ballbar.length or c.kind in seen_kinds:
            continue
        if c.mount.id not in campaign.ballbar.mounts:
            if c.mount.id in new_mounts:
                continue
            new_mounts.add(c.mount.id)
        seen_kinds.add(c.kind)
        out.append(c)
    return out


def _columns(rows: np.ndarray, names: list[str], to: list[str]) -> np.ndarray:
    """``rows`` (k, len(names)) laid out over ``to`` (names absent from ``to`` must be zero columns)."""
    index = {n: i for i, n in enumerate(to)}
    out = np.zeros((len(rows), len(to)))
    for j, n in enumerate(names):
        if n in index:
            out[:, index[n]] = rows[:, j]
        else:
            assert not np.any(rows[:, j]), n
    return out


def test_a_candidates_rows_are_its_runs_rows_in_the_measured_campaign(campaign):
    """Each sampled candidate's rows equal the rows its run has once appended to the campaign, taken from the
    machine's `linear` model of that campaign (the model registry, not the planner) over the posterior's own space."""
    cands = _sample(campaign)
    assert len(cands) >= 3
    planner = Planner(campaign, cands, None)
    for c, (A, _) in zip(cands, planner.candidate_rows()):
        aug = copy.copy(campaign)
        bb = copy.copy(campaign.ballbar)
        bb.setups, bb.mounts = dict(bb.setups) | {c.setup.id: c.setup}, dict(bb.mounts) | {c.mount.id: c.mount}
        bb.runs = list(bb.runs) + [planner.as_run(c)]
        aug.ballbar = bb
        space = parameter_space(aug, False, "ballbar")
        design = build_model("linear", aug, space).design
        want = design[-len(A):]
        got = _columns(A, planner.space.names, space.names)
        assert np.allclose(got, want, rtol=0, atol=1e-9 * np.abs(want).max()), c.name


def test_a_candidates_rows_do_not_depend_on_the_other_candidates(campaign):
    """Two candidates at one mount the campaign has not used, with different set-ups: the second one's rows are the
    same valued alone as beside the first.  (The chain places a mount's W ball by the first run there: valued in one
    campaign with the first, the head-head machine's second run would move by 50 mm per radian of tool-side tilt.)"""
    first = next(c for c in catalogue_of(campaign)
                 if c.repeat_of is None and c.mount.id not in campaign.ballbar.mounts)
    longer = next(c for c in catalogue_of(campaign) if c.kind == "tool length" and c.setup.id != first.setup.id)
    second = replace(longer, name="second", mount=first.mount)
    both = Planner(campaign, [first, second], None)
    alone = Planner(campaign, [second], None)
    A2, w2 = both.candidate_rows()[1]
    A1, w1 = alone.candidate_rows()[0]
    assert np.array_equal(_columns(A2, both.space.names, alone.space.names), A1)
    assert np.array_equal(w1, w2)


def test_targets_by_name_or_iso_symbol_and_one_refusal(campaign):
    """Every deviation the planner samples is a target by its name and by its ISO symbol where the machine names it
    otherwise (the thesis' alpha_XB is E_A0B); an unknown name is refused naming the machine's quantities."""
    planner = Planner(campaign, [], None)
    aliases = dict(campaign.machine.description.aliases) if campaign.machine.description else {}
    for d in planner.deviations:
        assert target_names([d], campaign) == [d]
    for symbol, name in aliases.items():
        if name in planner.deviations:
            assert target_names([symbol], campaign) == [name]
    with pytest.raises(ParameterError, match=r"unknown quantity 'beta_QQ' for this machine .*" + planner.deviations[0]):
        target_names(["beta_QQ"], campaign)


def test_the_catalogues_rows_made_together_equal_each_made_alone(campaign):
    """The planner makes the rows of the new runs at one measured mount, bar length and set-up from one model of them
    all: every catalogue candidate's rows and weights equal those of a planner given that candidate alone
    (to 1e-12 of the rows' largest entry; the same columns)."""
    cands = [c for c in catalogue_of(campaign) if c.repeat_of is None][:40]
    together = Planner(campaign, cands, None)
    got = together.candidate_rows()
    grouped = sum(c.mount.id in {r.mount for r in campaign.ballbar.runs} for c in cands)
    assert grouped >= 10  # the test sees runs made together
    for c, (A, w) in zip(cands, got):
        alone = Planner(campaign, [c], None)
        (A1, w1), = alone.candidate_rows()
        A1 = _columns(A1, alone.space.names, together.space.names)
        assert A.shape == A1.shape and np.abs(A - A1).max() <= 1e-12 * max(np.abs(A1).max(), 1e-300), c.name
        assert np.array_equal(w, w1)


@pytest.mark.parametrize("kind", ["trunnion", "head-head"])
def test_rows_made_together_at_a_new_mount_equal_each_made_alone(kind):
    """On a new machine (no run yet) the planner makes the rows of the runs at one mount, bar length and set-up from
    one model, the first run placing the W ball for the others at the set-up they share: each candidate's rows and
    weights equal a planner's given it alone, to the bit."""
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    c.ballbar.runs, c.probe, c.rtest, c.truth = [], None, None, None
    groups: dict = {}
    for cand in catalogue_of(c):
        if cand.repeat_of is None:
            groups.setdefault((cand.mount.id, cand.length, cand.setup.id), []).append(cand)
    cands = [x for g in groups.values() if len(g) > 2 for x in g[:3]][:12]
    assert len(cands) == 12  # four groups of three runs made together
    together = Planner(c, cands, None)
    for cand, (A, w) in zip(cands, together.candidate_rows()):
        alone = Planner(c, [cand], None)
        (A1, w1), = alone.candidate_rows()
        assert np.array_equal(A, _columns(A1, alone.space.names, together.space.names)), cand.name
        assert np.array_equal(w, w1)


@pytest.mark.parametrize("kind", ["integrex-i200", "head-head"])
def test_the_jacobian_by_disjoint_columns_is_the_jacobian_column_by_column(kind):
    """The complex-step Jacobian of a ball-bar model steps the columns of disjoint support together (a run's readings
    depend on the deviations and its own set-up's and mount's terms, and on the set-up that placed its W ball):
    the same matrix, to the bit, as one column at a time, on a campaign of many runs at several mounts and set-ups
    (the demo's runs and a catalogue run at each of its mounts and set-ups)."""
    import importlib

    from mtmcal_bayes.machines.space import described_space
    from mtmcal_bayes.models.ballbar import BallbarModel

    jac = importlib.import_module("mtmcal_bayes.models.jacobian")
    c = copy.deepcopy(api.campaign_of(None if kind == "integrex-i200" else api.demo_campaign(kind)))
    first: dict = {}
    for cand in catalogue_of(c):  # one catalogue run per mount, bar length and set-up
        if cand.repeat_of is None and cand.length == c.ballbar.length:
            first.setdefault((cand.mount.id, cand.setup.id), cand)
    cands = list(first.values())[:16]
    planner = Planner(c, cands, None)
    c.ballbar = copy.copy(c.ballbar)
    c.ballbar.setups, c.ballbar.mounts = planner._setups, planner._mounts
    c.ballbar.runs = list(c.ballbar.runs) + [planner.as_run(x) for x in cands]
    model = BallbarModel(c, described_space(c, data="ballbar"))
    colours = jac._colours(model.column_support())
    assert colours.max() + 1 < len(colours)  # columns are stepped together
    h = 1e-20 * model.space.display_scale()
    one_by_one = (model.predict(1j * np.diag(h)).imag / h[:, None]).T
    assert np.array_equal(jac.complex_step_jacobian(model), one_by_one)


@pytest.mark.parametrize("machine", ["thesis", "nutating-head"])
def test_an_extended_planner_values_new_candidates_as_a_new_planner_does(machine):
    """The tool-length sweep's candidates (new set-ups) valued by the report's planner extended to them and by a
    planner made anew for them with the same targets, data and scales: the same sds, information and identifiability
    (to 1e-12 relative), on the thesis machine and on the nutating head with every instrument."""
    from mtmcal_bayes.planning.catalogue import sweep_candidates

    campaign = api.campaign_of(None if machine == "thesis" else api.demo_campaign(machine))
    data = "ballbar" if machine == "thesis" else "all"
    planner = Planner(campaign, catalogue_of(campaign)[:20], None, data=data)
    pattern = next(c.pattern for c in catalogue_of(campaign) if c.kind == "tool length")
    cands = sweep_candidates(campaign, pattern, (0.0, 25.0, 50.0))
    got = planner.extended(cands).evaluate()
    want = Planner(campaign, cands, planner.targets, sigma_model=planner.sigma_model, data=data).evaluate()
    assert got.targets == want.targets and len(got.targets) >= 3
    for name in ("sd_before", "sd_after", "eig_bits"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-12, atol=0)
    assert np.array_equal(got.identified_after, want.identified_after)
    assert np.array_equal(got.identified_before, want.identified_before)
