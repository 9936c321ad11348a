"""The examples run as a user runs them: each a fresh process, from a directory outside the checkout."""

import subprocess
import sys
from pathlib import Path

import pytest

#: the fleet demo writes where it is told and is checked for what it shows (tests/test_newcomer.py)
EXAMPLES = sorted(p for p in (Path(__file__).resolve().parents[1] / "examples").glob("*.py") if p.name != "fleet_demo.py")


def test_there_are_examples():
    assert {p.name for p in EXAMPLES} >= {"python_api.py", "identify_thesis.py", "simulate_and_identify.py"}


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(example, tmp_path):
    proc = subprocess.run([sys.executable, str(example)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and "Warning" not in proc.stderr, proc.stderr[-2000:]
    assert proc.stdout.strip()
    assert list(tmp_path.iterdir()) == []  # whatever an example writes goes to its own temporary directory
