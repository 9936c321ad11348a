import os
import sys

# the package's modules compiled once, for every process the tests start (python -m pytest imports them from the
# source tree, and a shell with PYTHONDONTWRITEBYTECODE set would have each process compile all of them again)
sys.dont_write_bytecode = False

# one BLAS thread in every test process (set before numpy is first imported, inherited by the processes the tests
# start): under pytest -n there is one process per core already; under -n 0 on a machine whose cores are busy
# OpenBLAS's second thread waits on the first, and a test then took up to 15 times as long (an SVD, a solve)
for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import io
import shutil
import warnings
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from mtmcal_bayes import load_campaign
from mtmcal_bayes.cli import main

DATA = Path(__file__).parent / "data"

#: the test files that cost most, heaviest first (their tests' summed durations on 2 cores, 2026-11: 15–75 s each);
#: they run before every other file.  Under ``pytest -n`` (worksteal) a worker that runs out of tests takes half of
#: another's queue, but a test already running cannot be shared: a 38 s test begun last would keep one core busy
#: while the other idles.  Started first, the long tests overlap the many short ones.  Only an order: a file missing
#: here, or a name left after its file is gone, changes nothing but when its tests start.
HEAVY_FIRST = ("test_report.py", "test_formats.py", "test_report_machines.py", "test_history.py", "test_design.py",
               "test_degenerate.py", "test_nutating_head.py", "test_properties.py", "test_fleet_described.py",
               "test_history_models.py", "test_rtest_instruments.py", "test_sampler.py", "test_examples.py",
               "test_newcomer.py", "test_fleet.py", "test_api.py", "test_analysis.py", "test_tolerances_machines.py",
               "test_fleet_latest.py", "test_machine_wording.py", "test_report_start.py", "test_sbc_dask.py",
               "test_inference.py")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """The files of :data:`HEAVY_FIRST` first, in its order; the others after them in their own order.  Whole files
    move, each file's tests keeping theirs, so a module-scoped fixture is still made once per file."""
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


@pytest.fixture(scope="session")
def thesis():
    return load_campaign()


@pytest.fixture(scope="session")
def thesis_posterior():
    """``sample(seed=1)`` of the built-in campaign (the default run), read by several modules' tests (read only)."""
    from mtmcal_bayes import sample

    return sample(seed=1)


@pytest.fixture
def run_cli():
    """Run the CLI in-process: returns (exit status, stdout, stderr).

    Python warnings raised on the way are appended to stderr as the interpreter would print them
    (pytest would otherwise capture them, hiding what a user sees on the terminal).
    """

    def run(*argv):
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            try:
                code = main([str(a) for a in argv])
            except SystemExit as exc:  # argparse
                code = exc.code
        shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno) for w in caught)
        return code, out.getvalue(), err.getvalue() + shown

    return run


#: the tolerance set of the shared report (tests/test_metrology.py reads its conformity): an ISO symbol and a
#: thesis name, one quantity that does not conform and one undecided
SHARED_REPORT_TOLERANCES = "[tolerances]\nE_B0B_arcsec = 30\nalpha_XB_arcsec = 10\n"


@contextmanager
def _locked(path: Path):
    """Hold an exclusive advisory lock on ``path`` (POSIX ``flock``)."""
    import fcntl

    with open(path, "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def shared_output(tmp_path_factory, name: str, make) -> tuple[Path, str]:
    """``(folder, text)``: ``make(folder)`` run once for the whole test run, its returned text kept beside it.

    Under ``pytest -n`` each worker has its own session, so a session-scoped result that tests on both workers read
    would be computed twice; here the first worker to need it makes it under a lock in the run's shared temporary
    directory and a later one reads it (waiting while it is being made).  Where there are no advisory locks
    (Windows) each worker makes its own, in its own temporary directory."""
    try:
        import fcntl  # noqa: F401
        root = tmp_path_factory.getbasetemp()
        if os.environ.get("PYTEST_XDIST_WORKER"):
            root = root.parent  # the run's directory, above each worker's own
    except ImportError:
        return _made(tmp_path_factory.mktemp(name), make)
    with _locked(root / f"shared-{name}.lock"):
        folder, text, done = root / f"shared-{name}", root / f"shared-{name}.txt", root / f"shared-{name}.done"
        if not done.exists():
            if folder.exists():  # a worker that failed making it
                shutil.rmtree(folder)
            folder.mkdir()
            text.write_text(_made(folder, make)[1], encoding="utf-8")
            done.touch()
        return folder, text.read_text(encoding="utf-8")


def _made(folder: Path, make) -> tuple[Path, str]:
    return folder, make(folder)


def cli_stdout(*argv) -> str:
    """``mtmcal-bayes ARGV`` in this process: its stdout (the exit status must be 0)."""
    stdout, stderr = io.StringIO(), io.StringIO()
    with redirect_stdout(stdout), redirect_stderr(stderr):
        code = main([str(a) for a in argv])
    assert code == 0, stderr.getvalue()
    return stdout.getvalue()


def report_cli(*argv) -> str:
    """``mtmcal-bayes report ...`` in this process: its stdout (the exit status must be 0)."""
    return cli_stdout("report", *argv)


@pytest.fixture(scope="session")
def thesis_report_run(tmp_path_factory):
    """One ``report --json`` of the built-in campaign (seed 2, the default run), shared by every test that reads
    it: (directory, stdout).  With ``--compare-models`` and ``--tolerances`` (SHARED_REPORT_TOLERANCES): they
    add their sections, files and columns and change nothing else of the report (its other CSVs are
    byte-identical to a report without them), so the model comparison, the conformity and the default report are
    read from one run instead of three.  One per test run (:func:`shared_output`); a test that writes files of its
    own writes them elsewhere."""

    def make(folder):
        tolerances = folder / "tolerances.toml"
        tolerances.write_text(SHARED_REPORT_TOLERANCES, encoding="utf-8")
        return report_cli("-o", folder / "thesis", "--json", "--seed", "2", "--quiet", "--compare-models",
                          "--tolerances", tolerances)

    folder, stdout = shared_output(tmp_path_factory, "thesis-report", make)
    return folder / "thesis", stdout


@pytest.fixture(scope="session")
def thesis_report(thesis_report_run):
    return thesis_report_run[0]


#: the tolerances of each demo's shared report (:func:`demo_report`), by the machine's ISO symbols: its first angle
#: (tests/test_report_machines.py) and, on the trunnion, a bound on each side of zero (tests/test_tolerances_machines.py)
DEMO_REPORT_TOLERANCES = {
    "trunnion": "[tolerances]\nE_B0A_arcsec = 5\nE_B0C_arcsec = 20\nE_Y0A_um = {high = 0}\n",
    "vertical-turn-mill": "[tolerances]\nE_A0C_arcsec = 5\n",
    "head-head": "[tolerances]\nE_A0C_arcsec = 5\n",
}
#: the demos whose shared report also compares the machine's models (tests/test_report_machines.py)
DEMO_REPORT_COMPARES = ("trunnion",)


@pytest.fixture(scope="session")
def demo_report(tmp_path_factory):
    """``demo_report(machine)`` → ``(directory, stdout)``: one ``report --machine MACHINE`` of a built-in type's
    demo campaign per test run, exact draws, seed 1, with DEMO_REPORT_TOLERANCES (and ``--compare-models`` on the
    DEMO_REPORT_COMPARES), shared by the tests that read a demo's default report (:func:`shared_output`)."""
    made = {}

    def get(machine: str) -> tuple[Path, str]:
        if machine not in made:
            def make(folder):
                tolerances = folder / "tolerances.toml"
                tolerances.write_text(DEMO_REPORT_TOLERANCES[machine], encoding="utf-8")
                compare = ["--compare-models"] if machine in DEMO_REPORT_COMPARES else []
                return report_cli("--machine", machine, "-o", folder / "rep", "--sampler", "exact", "--seed", "1",
                                  "--tolerances", tolerances, "--quiet", *compare)

            folder, stdout = shared_output(tmp_path_factory, f"report-{machine}", make)
            made[machine] = folder / "rep", stdout
        return made[machine]

    return get


@pytest.fixture(scope="session")
def demo_plan(tmp_path_factory):
    """``demo_plan(machine)`` → the JSON text ``plan --machine MACHINE --json`` prints (the demo campaign's default
    data), made once per test run (:func:`shared_output`) for the tests that read it (tests/test_workflow_described.py,
    tests/test_candidates_file_machines.py, tests/test_design_described.py)."""
    made = {}

    def get(machine: str) -> str:
        if machine not in made:
            made[machine] = shared_output(tmp_path_factory, f"plan-{machine}",
                                          lambda folder: cli_stdout("plan", "--machine", machine, "--json"))[1]
        return made[machine]

    return get
