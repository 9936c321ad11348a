import os

if os.environ.get("PYTEST_XDIST_WORKER"):  # one process per core already (pytest -n): one BLAS thread each, not two
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")

import io
import warnings
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from mtmcal_bayes import load_campaign
from mtmcal_bayes.cli import main

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="session")
def thesis():
    return load_campaign()


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


@pytest.fixture(scope="session")
def thesis_report_run(tmp_path_factory):
    """One ``report --json`` of the built-in campaign (seed 2, the default run), shared by every test that reads
    it: (directory, stdout).  With ``--compare-models`` and ``--tolerances`` (SHARED_REPORT_TOLERANCES): they
    add their sections, files and columns and change nothing else of the report (its other CSVs are
    byte-identical to a report without them), so the model comparison, the conformity and the default report are
    read from one run instead of three."""
    folder = tmp_path_factory.mktemp("rep")
    tolerances = folder / "tolerances.toml"
    tolerances.write_text(SHARED_REPORT_TOLERANCES, encoding="utf-8")
    out = folder / "thesis"
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main(["report", "-o", str(out), "--json", "--seed", "2", "--quiet", "--compare-models",
                     "--tolerances", str(tolerances)])
    assert code == 0
    return out, stdout.getvalue()


@pytest.fixture(scope="session")
def thesis_report(thesis_report_run):
    return thesis_report_run[0]
