import io
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
    """Run the CLI in-process: returns (exit status, stdout, stderr)."""

    def run(*argv):
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            try:
                code = main([str(a) for a in argv])
            except SystemExit as exc:  # argparse
                code = exc.code
        return code, out.getvalue(), err.getvalue()

    return run
