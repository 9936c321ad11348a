"""The tables of docs/rtest.md, "Posterior sds per machine minute", are what bench/rtest_minutes.py computes: per
built-in type, the exact posterior sds of the deviations from one instrument's campaign of equal machine minutes
(the ball bar's, the touch probe's, the R-test's), simulated from one stated truth (seeded)."""

from __future__ import annotations

import pytest

from mtmcal_bayes.machine_time import TimeModel, probe_run_minutes, rtest_run_minutes

from .scripts import ROOT, bench_script

MINUTES = bench_script("rtest_minutes")


@pytest.mark.parametrize("machine", MINUTES.TYPES)
def test_docs_hold_the_scripts_tables(machine):
    minutes, rows = MINUTES.table(machine)
    docs = (ROOT / "docs" / "rtest.md").read_text(encoding="utf-8")
    assert MINUTES.markdown(machine, minutes, rows) in docs
    # equal minutes: the probe's and the R-test's repeats fill the ball bar's budget, one more would pass it
    budget = minutes["ballbar"]
    assert minutes["probe"] <= budget and minutes["rtest"] <= budget


def test_repeats_fill_the_budget():
    m = TimeModel()
    budget = 60.0
    r = MINUTES._repeats_within(budget, lambda k: rtest_run_minutes(m, 20, k))
    assert rtest_run_minutes(m, 20, r) <= budget < rtest_run_minutes(m, 20, r + 1)
    r = MINUTES._repeats_within(budget, lambda k: probe_run_minutes(m, 8, k))
    assert probe_run_minutes(m, 8, r) <= budget < probe_run_minutes(m, 8, r + 1)
