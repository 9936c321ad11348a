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
