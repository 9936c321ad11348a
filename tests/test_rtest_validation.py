"""Validation of the R-test (issue 43, docs/rtest.md): the tables of what a one-sphere static R-test campaign
determines on each built-in type are the ones the Jacobian gives (bench/rtest_determines.py); simulation-based
calibration with R-test data alone passes on three types and rejects a wrong posterior (bench/rtest_sbc.py: every type,
the R-test alone and every instrument, N = 200)."""

from __future__ import annotations


import pytest

from mtmcal_bayes.cluster import dask_client
from mtmcal_bayes.inference import LogPosterior
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.validation import SBCSettings, run_sbc

from .rtest_campaigns import every_setting_text
from .scripts import ROOT, bench_script
from .test_validation import _Distorted

DOC = ROOT / "docs" / "rtest.md"


DETERMINES = bench_script("rtest_determines")


def _doc_section(machine: str) -> str:
    """The text of ``machine``'s part of docs/rtest.md's "What a one-sphere static R-test campaign determines"."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## What a one-sphere static R-test campaign determines"):]
    section = section[:section.index("\n## ", 1)]
    part = section[section.index(f"### `{machine}`"):]
    return part[:part.index("\n### ", 1)] if "\n### " in part[1:] else part


@pytest.mark.parametrize("machine", DETERMINES.TYPES)
def test_the_documented_table_is_the_computed_one(machine):
    """Each type's table in the docs is the one computed from the campaign's Jacobian now (over the machine's
    default selection of deviations, for the four settings of frame and zero), and its runs line the campaign's."""
    part = _doc_section(machine)
    assert DETERMINES.table(machine) in part
    assert f"runs (°): {DETERMINES.runs(machine)}" in part


def test_the_table_covers_every_deviation_and_setting():
    """The table is not empty of verdicts: each type's campaign determines some deviations and leaves some out, and
    each row names a verdict for every setting."""
    for machine in DETERMINES.TYPES:
        by = DETERMINES.verdicts(machine)
        for ident in by.values():
            assert ident.determined and ident.undetermined
            named = set(ident.determined) | set(ident.undetermined) | {n for c in ident.combinations for n in c.weights}
            assert named == set(ident.deviations)


# --------------------------------------------------------------------------- simulation-based calibration
#: replicates of the tests below: the exact sampler on R-test data takes about 1 s per 100 here
N_SBC = 200


@pytest.fixture(scope="module")
def scheduler():
    """One local Dask cluster for the runs below (starting one takes seconds)."""
    with dask_client(workers=1) as client:
        yield client.scheduler.address


@pytest.fixture(scope="module")
def campaigns():
    made = {}

    def get(machine: str):
        if machine not in made:
            made[machine] = parse_campaign(every_setting_text(machine))
        return made[machine]

    return get


@pytest.mark.parametrize("machine", ["trunnion", "head-head", "nutating-head"])
def test_exact_sbc_with_rtest_data_passes(machine, campaigns, scheduler):
    """``validate sbc --data rtest --sampler exact``, seed 1 (the CLI's default), N = 200, on the one-sphere static
    runs in all four settings of frame and zero: the ranked quantities are what the R-test data determine (one by
    one and in combination) and the R-test's discrepancy scale, and every one passes the module's criterion (p > 0.01
    and the 90 % coverage inside its 99 % binomial range)."""
    c = campaigns(machine)
    r = run_sbc(c, SBCSettings(n=N_SBC, sampler="exact", data="rtest", scheduler=scheduler, seed=1))
    ident = campaign_identifiability(LogPosterior(c, "linear", data="rtest"))
    identified = ident.determined + tuple(x.name for x in ident.combinations)
    assert len(identified) >= 4 and r.quantities == identified + ("sigma_model_rtest",)
    s = r.summary()
    assert s["ok"].all(), s[["p_uniform", "coverage_90", "ok"]]


@pytest.mark.parametrize("width, shift, what", [(0.7, 0.0, "overconfident"), (1.5, 0.0, "underconfident"),
                                                (1.0, 0.5, "biased")])
def test_sbc_with_rtest_data_rejects_a_wrong_posterior(width, shift, what, campaigns, scheduler):
    """The same run (the trunnion, seed 1, N = 200) with the exact posterior's draws 0.7×/1.5× too wide or shifted by
    0.5 sd fails every identified quantity: the passing test above has the power to see a posterior that far off."""
    c = campaigns("trunnion")
    r = run_sbc(c, SBCSettings(n=N_SBC, sampler="exact", data="rtest", scheduler=scheduler, seed=1),
                sampler=_Distorted(width=width, shift=shift))
    s = r.summary().loc[list(r.identified)]
    assert not s["ok"].any(), (what, s[["p_uniform", "coverage_90"]])


@pytest.mark.parametrize("machine", ["integrex-i200", "vertical-turn-mill"])
def test_exact_sbc_of_the_rtest_demo_passes(machine, scheduler):
    """``validate sbc --sampler exact`` on the R-test demo of the two types the test above leaves out (docs/rtest.md,
    "The R-test demos"; N = 100, seed 1, every instrument the demo has: bench/rtest_demo_sbc.py runs N = 200 on all
    four): the ranked quantities are what the demo determines and the R-test's scale, every one passing."""
    from mtmcal_bayes.io import load_campaign
    from mtmcal_bayes.io.machine_reader import rtest_demo_campaign

    c = load_campaign(rtest_demo_campaign(machine))
    r = run_sbc(c, SBCSettings(n=100, sampler="exact", data="all", scheduler=scheduler, seed=1))
    ident = campaign_identifiability(LogPosterior(c, "linear", data="rtest"))
    assert set(r.quantities[:-1]) == set(ident.determined + tuple(x.name for x in ident.combinations))
    assert r.quantities[-1] == "sigma_model_rtest"
    s = r.summary()
    assert s["ok"].all(), s[["p_uniform", "coverage_90", "ok"]]
