"""Errors that cross a process boundary arrive as the line they would have been in the main process.

The package's errors are raised in other processes: the report's drawing and planning processes (forked,
answers through a pipe) and Dask workers (``fleet``; ``validate sbc`` in tests/test_sbc_dask.py).  Each test here
raises a real input error on the far side — the loader's own, reading a malformed campaign of the bad-input
corpus — and checks the line the user gets; an unexpected exception names the step it stopped.
"""

from __future__ import annotations

import pickle

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.errors import InputError, MtmcalError, ParameterError, StepFailure
from mtmcal_bayes.reporting import build
from mtmcal_bayes.reporting.drawing import Drawing, draw_figures

from .conftest import DATA

#: a malformed campaign: its loader raises InputError at ballbar.runs[1].pattern
BAD = DATA / "bad" / "unknown_pattern.toml"


def _load_bad(*args, **kwargs):
    """Read the malformed campaign: the loader's InputError, raised wherever this runs."""
    mb.load_campaign(BAD)


def _loaders_line() -> str:
    with pytest.raises(InputError) as info:
        _load_bad()
    return str(info.value)


def _fault(*args, **kwargs):
    raise ValueError("a fault, not the input's")


@pytest.mark.parametrize("err", [InputError("c.toml", "probe.c_axis.stylus", "missing"),
                                 InputError("c.toml", None, "not a campaign"),
                                 ParameterError("max_steps", "too few draws"), MtmcalError("plain"),
                                 StepFailure("drawing corner.png", "ValueError", "boom", "Traceback ...")])
def test_the_packages_errors_survive_pickling(err):
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err) and str(back) == str(err) and back.args == err.args
    assert vars(back) == vars(err)


def test_an_input_error_in_a_drawing_process_is_the_loaders_line(tmp_path):
    assert Drawing(tmp_path).fork, "the test needs forked drawing processes"
    with pytest.raises(InputError) as info:
        draw_figures([("first.png", _load_bad), ("second.png", _load_bad)], tmp_path)
    assert type(info.value) is InputError and str(info.value) == _loaders_line()
    assert info.value.key == "ballbar.runs[1].pattern"


def test_an_unexpected_exception_in_a_drawing_process_names_the_figure(tmp_path):
    with pytest.raises(StepFailure) as info:
        draw_figures([("corner.png", _fault)], tmp_path)
    assert info.value.step == "drawing corner.png" and info.value.kind == "ValueError"
    assert info.value.message == "a fault, not the input's" and "_fault" in info.value.trace


def test_an_input_error_in_the_reports_planning_process_is_one_line_and_exit_2(run_cli, tmp_path, monkeypatch):
    """The report plans in a forked process beside its sampling; an input error there reaches the user as the
    loader's line, exit 2, and nothing is written."""
    monkeypatch.setattr(build, "_plan_and_figures", _load_bad)
    code, out, err = run_cli("report", "-o", tmp_path / "rep", "--quiet")
    assert code == 2
    assert err.strip() == f"mtmcal-bayes report: error: {_loaders_line()}"
    assert not (tmp_path / "rep").exists()


def test_an_unexpected_exception_in_the_reports_planning_process_names_the_step(run_cli, tmp_path, monkeypatch):
    monkeypatch.setattr(build, "_plan_and_figures", _fault)
    code, out, err = run_cli("report", "-o", tmp_path / "rep", "--quiet")
    assert code == 1
    assert err.strip().startswith("mtmcal-bayes report: internal error in the report's plan (beside the sampling): "
                                  "ValueError: a fault, not the input's")
    assert not (tmp_path / "rep").exists()


@pytest.fixture(scope="module")
def one_machine(tmp_path_factory):
    """A fleet of one machine with one campaign (one unit on one worker)."""
    root = tmp_path_factory.mktemp("fleet-one")
    campaign = mb.load_campaign()
    campaign.machine.serial = "M-9"
    (root / "M-9").mkdir()
    mb.save_campaign(campaign, root / "M-9" / "c1.toml")
    return root


@pytest.mark.parametrize("far_side, line", [
    (_load_bad, lambda file: _loaders_line()),
    (_fault, lambda file: f"internal error in the posterior of {file}: ValueError: a fault, not the input's")])
def test_an_error_on_a_fleets_dask_worker_is_one_line_and_exit_3(one_machine, run_cli, monkeypatch, tmp_path, far_side,
                                                                 line):
    """The local cluster's workers are forked after the patch, so the campaign unit meets the error there."""
    import mtmcal_bayes.posterior as posterior

    monkeypatch.setattr(posterior, "sample_posterior", far_side)
    code, out, err = run_cli("fleet", one_machine, "--workers", "1", "--cache", tmp_path, "--quiet")
    file = one_machine / "M-9" / "c1.toml"
    assert code == 3
    assert f"mtmcal-bayes fleet: error: {line(file)}" in err.splitlines()
