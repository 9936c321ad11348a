"""``validate sbc`` on Dask: the same result on one local worker and on a separately started cluster of two,
one line for a scheduler that cannot be used, a clean stop on an interruption.  (One against two local workers:
tests/test_validation.py::test_emcee_sbc_is_seeded_and_independent_of_workers.)"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from distributed import Client

import mtmcal_bayes as mb
from mtmcal_bayes import cluster
from mtmcal_bayes.errors import InputError, ParameterError, StepFailure
from mtmcal_bayes.io.json_text import json_text
from mtmcal_bayes.validation import SBCSettings, run_sbc
from mtmcal_bayes.validation.samplers import ExactDraws

from .processes import dask_cluster, stop, wait_for

VENV_BIN = Path(sys.executable).parent
ROOT = Path(__file__).resolve().parents[1]
#: exact sampler (fast), enough replicates that the chunks differ with the number of workers (sbc._chunk_size:
#: 9 replicates per task on one worker, 4 on two)
#: a malformed campaign: its loader raises InputError at ballbar.runs[1].pattern
BAD = Path(__file__).parent / "data" / "bad" / "unknown_pattern.toml"
RUN = {"n": 40, "sampler": "exact", "seed": 7}


def _same(a, b) -> None:
    """Two SBC results are the same: every replicate's numbers, and so the summary, bit for bit."""
    for name in ("ranks", "truth", "post_mean", "post_sd", "covered", "converged", "n_steps", "tau_max"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    pd.testing.assert_frame_equal(a.summary(), b.summary(), check_exact=True)


@pytest.fixture(scope="module")
def one_worker():
    """The reference: a local cluster of one worker, and the progress events it sent."""
    events = []
    return mb.sbc(workers=1, progress=events.append, **RUN), events


def test_progress_counts_every_replicate(one_worker):
    one, events = one_worker
    assert one.settings.workers == 1 and one.document()["scheduler"] is None
    assert one.ranks.shape == (RUN["n"], len(one.quantities)) and one.ranks.min() >= 0 and one.ranks.max() <= 99
    assert [e.done for e in events] == list(range(1, RUN["n"] + 1))
    assert {e.total for e in events} == {RUN["n"]} and events[-1].task == "sbc [linear, exact]"


@pytest.fixture(scope="module")
def scheduler_file(tmp_path_factory):
    """A cluster started as docs/validation.md says: ``dask scheduler``, then ``dask worker`` (two, one thread
    each); its scheduler file.  The workers see this directory, for the test's own sampler classes."""
    tmp = tmp_path_factory.mktemp("dask")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    with dask_cluster(tmp, env=env) as path:
        with Client(scheduler_file=str(path), timeout="10s") as client:
            client.wait_for_workers(2, timeout=60)
        yield str(path)


def test_a_separately_started_cluster_gives_identical_results(one_worker, scheduler_file, run_cli, tmp_path):
    remote = mb.sbc(scheduler=scheduler_file, **RUN)
    _same(one_worker[0], remote)
    assert remote.settings.workers == 2 and remote.document()["scheduler"] == scheduler_file
    address = json.loads(Path(scheduler_file).read_text())["address"]
    code, out, err = run_cli("validate", "sbc", "--sampler", "exact", "--n", RUN["n"], "--seed", RUN["seed"],
                             "--scheduler", address, "--json", "--quiet")
    assert code == 0, err
    assert json.loads(out)["quantities"] == json.loads(json_text(one_worker[0].to_json()))["quantities"]


class _Refusing(ExactDraws):
    """A sampler that fails in the worker the way EmceeDraws does when the step budget gives too few draws."""

    def __call__(self, post, n_ranked, rng):
        raise ParameterError("max_steps", "only 12 posterior draws for 99 ranks: raise the step budget")


class _ReadingABadFile(ExactDraws):
    """A sampler that meets a real input error in the worker: it reads a malformed campaign of the bad corpus."""

    def __call__(self, post, n_ranked, rng):
        mb.load_campaign(BAD)


class _Faulty(ExactDraws):
    """A sampler with a fault of its own (not the user's)."""

    def __call__(self, post, n_ranked, rng):
        raise ZeroDivisionError("a fault of the sampler")


class _Interrupted:
    """A progress callback that stops the run after two replicates, as Ctrl-C would."""

    def __init__(self):
        self.events = []

    def __call__(self, event):
        self.events.append(event)
        if len(self.events) == 2:
            raise KeyboardInterrupt


def _tasks_left(scheduler_file: str) -> int:
    with Client(scheduler_file=scheduler_file, timeout="10s") as client:
        return client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))


def test_a_users_error_in_a_worker_comes_back_as_itself(thesis, scheduler_file):
    with pytest.raises(ParameterError) as info:
        run_sbc(thesis, SBCSettings(n=6, sampler="exact", scheduler=scheduler_file), sampler=_Refusing())
    assert type(info.value) is ParameterError and info.value.parameter == "max_steps"
    assert "raise the step budget" in info.value.message


def test_an_input_error_in_a_worker_arrives_as_the_loaders_line(thesis, scheduler_file):
    with pytest.raises(InputError) as here:
        mb.load_campaign(BAD)
    with pytest.raises(InputError) as info:
        run_sbc(thesis, SBCSettings(n=6, sampler="exact", scheduler=scheduler_file), sampler=_ReadingABadFile())
    assert type(info.value) is InputError and str(info.value) == str(here.value)
    assert (info.value.source, info.value.key) == (str(BAD), "ballbar.runs[1].pattern")


def test_an_unexpected_exception_in_a_worker_names_its_replicate(thesis, scheduler_file):
    with pytest.raises(StepFailure) as info:
        run_sbc(thesis, SBCSettings(n=6, sampler="exact", scheduler=scheduler_file), sampler=_Faulty())
    assert info.value.kind == "ZeroDivisionError" and info.value.message == "a fault of the sampler"
    assert info.value.step.startswith("replicate ") and "simulation-based calibration (linear)" in info.value.step
    assert 'raise ZeroDivisionError("a fault of the sampler")' in info.value.trace  # its traceback on the worker


def test_an_interruption_cancels_the_remaining_replicates(thesis, scheduler_file):
    stop = _Interrupted()
    with pytest.raises(KeyboardInterrupt):
        run_sbc(thesis, SBCSettings(n=400, sampler="emcee", scheduler=scheduler_file), progress=stop)
    assert len(stop.events) == 2
    wait_for(lambda: _tasks_left(scheduler_file) == 0, 20, "the scheduler to forget the cancelled tasks")


def test_ctrl_c_stops_a_local_run_with_one_line(tmp_path):
    """Ctrl-C reaches the whole process group: the run stops, says so in one line, and leaves no process."""
    argv = [sys.executable, "-m", "mtmcal_bayes.cli", "validate", "sbc", "--n", "100", "--workers", "1",
            "-o", str(tmp_path / "o")]
    proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        first = proc.stderr.readline()  # the first finished replicate
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        stop(proc)
    assert first.startswith("sbc [linear, emcee]: 1/100 replicates"), first
    assert proc.returncode == 130 and err == "mtmcal-bayes: interrupted\n" and out == "", err
    assert not (tmp_path / "o").exists()
    wait_for(lambda: subprocess.run(["pgrep", "-g", str(proc.pid)], capture_output=True).returncode == 1, 10,
              "the workers to end")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("argv, fragment", [
    (["--scheduler", "tcp://127.0.0.1:{port}"], "--scheduler: cannot reach the Dask scheduler 'tcp://127.0.0.1:"),
    (["--scheduler", "{tmp}/nowhere.json"], "--scheduler: {tmp}/nowhere.json: no such scheduler file"),
    (["--scheduler", "tcp://127.0.0.1:{port}", "--workers", "2"], "--workers: sets the size of a local cluster"),
])
def test_a_scheduler_that_cannot_be_used_is_one_line_and_exit_2(run_cli, tmp_path, monkeypatch, argv, fragment):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1)
    values = {"port": _free_port(), "tmp": tmp_path}
    code, out, err = run_cli("validate", "sbc", "--sampler", "exact", "--n", "8", "-o", tmp_path / "o",
                             *[a.format(**values) for a in argv])
    assert code == 2 and out == "" and len(err.splitlines()) == 1, err
    assert err.startswith("mtmcal-bayes validate: error: ") and fragment.format(**values) in err, err
    assert not (tmp_path / "o").exists()
