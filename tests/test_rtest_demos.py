"""The R-test demo campaign of each built-in type (docs/rtest.md, "The R-test demos"): written by
examples/machines/make_rtest_demos.py from its stated truth; ``sample`` with its default data (every instrument it
has: the R-test) finds each deviation the campaign determines within 3.5 posterior sd of the truth, with no warning."""

from __future__ import annotations

from pathlib import Path

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, rtest_demo_campaign
from mtmcal_bayes.reporting.machine_sections import truth_table

from .scripts import ROOT, load_script

SCRIPT = ROOT / "examples" / "machines" / "make_rtest_demos.py"
#: |posterior mean − truth| / posterior sd allowed for each determined deviation: about 20 over the four types, so
#: under a correct model P(any beyond 3.5) ≈ 1 % (and the seeds are fixed); a wrong sign or lever arm of a term moves
#: them by tens of sd
Z_MAX = 3.5


def _script():
    return load_script(SCRIPT)


@pytest.mark.parametrize("machine", [t for t in BUILTIN_TYPES if t in _script().SPHERES])
def test_the_rtest_demo_is_its_script_s_and_sample_finds_its_truth(machine):
    path = rtest_demo_campaign(machine)
    assert Path(path).read_text(encoding="utf-8") == _script().text_of(machine)  # rerunnable: the same bytes
    c = mb.load_campaign(path)
    r = mb.sample(c, seed=1)
    assert r.data == "all" and tuple(r.log_posterior.scales) == ("sigma_model_rtest",)
    assert not r.warnings, r.warnings
    determined = campaign_identifiability(r.log_posterior).determined
    assert len(determined) >= 5
    t = truth_table(r, None, c.truth).set_index("quantity")
    assert set(determined) <= set(t.index)
    assert (t["z"].abs() < Z_MAX).all(), t[["truth", "mean", "sd", "z"]]


def test_the_ball_bar_asked_of_an_rtest_campaign_is_one_line(run_cli):
    """The thesis type's R-test demo: its default data is the R-test (the plug-in's default, the ball bar, holds only
    where the campaign has ball-bar runs; it took the ball bar and failed in the linear algebra); the ball bar asked
    for is refused in one line, exit 2."""
    code, out, err = run_cli("sample", rtest_demo_campaign("integrex-i200"), "--data", "ballbar")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "needs ball-bar runs" in err and "Traceback" not in err


def test_the_rtest_demo_by_its_type_on_the_command_line(run_cli):
    """``--machine TYPE --demo rtest`` runs a command on the type's R-test demo (the same output as its path);
    ``--demo`` without ``--machine``, or on a type whose demo has R-test runs of its own: one line, exit 2."""
    by_type = run_cli("identify", "--machine", "head-head", "--demo", "rtest", "--json")
    by_path = run_cli("identify", rtest_demo_campaign("head-head"), "--json")
    assert by_type[0] == 0 and by_type == by_path, by_type[2]
    code, out, err = run_cli("identify", "--demo", "rtest")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "--demo needs --machine" in err
    code, out, err = run_cli("identify", "--machine", "nutating-head", "--demo", "rtest")  # its demo has R-test runs
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "'rtest'" in err, err
