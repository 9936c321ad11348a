"""Command line: JSON shapes and human output."""

import json
import subprocess
import sys

import pytest

from mtmcal_bayes import IDENTIFIABLE
from mtmcal_bayes.datasets import data_path


def test_identify_json(run_cli):
    code, out, err = run_cli("identify", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert set(data["ballbar"]) == set(IDENTIFIABLE)
    for name in IDENTIFIABLE:
        entry = data["ballbar"][name]
        assert entry["unit"] == ("um" if name in ("dx_CZ_minus_dx_BT", "dy_CZ") else "arcsec")
        assert abs(entry["value"] - entry["reported"]) < 0.01
    beta = data["probe"]["beta_CZ"]
    assert beta["value"] == pytest.approx(-30.46, abs=0.005) and beta["reported"] == -26.28
    assert beta["reproduced"] is False
    assert data["assumptions"] and data["checks"]


def test_identify_human(run_cli):
    code, out, _ = run_cli("identify")
    assert code == 0
    assert "NOT REPRODUCED" in out and "reproduced" in out and "µm" in out and "″" in out


def test_probe_fit_json(run_cli):
    code, out, err = run_cli("probe-fit", data_path("fig5_13_dprnt_output.txt"), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["centre_mm"] == pytest.approx([-390.2175, -0.0005, -472.4176], abs=1e-3)
    assert data["radius_mm"] == pytest.approx(7.9106, abs=1e-3)
    assert any("declares 40" in n for n in data["notes"])


def test_probe_fit_stylus_radius(run_cli):
    code, out, _ = run_cli("probe-fit", data_path("fig5_13_dprnt_output.txt"), "--stylus-radius-mm", "3", "--json")
    assert code == 0
    assert json.loads(out)["radius_mm"] == pytest.approx(4.9106, abs=1e-3)


@pytest.mark.parametrize("content,fragment", [
    ("", "empty file"),
    ("%\nX1 Y2 Zq\n", "line 2"),
    ("%\nX1 Y0 Z0\nX2 Y0 Z0\n", "at least 4"),
])
def test_probe_fit_bad_input(run_cli, tmp_path, content, fragment):
    f = tmp_path / "d.txt"
    f.write_text(content)
    code, out, err = run_cli("probe-fit", f)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and fragment in err and str(f) in err


def test_unknown_command_one_line(run_cli):
    code, _, err = run_cli("frobnicate")
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_a_command_ends_its_process_with_its_status_and_all_its_output(tmp_path):
    """The command line ends a short command's process itself (no teardown of the heap): the exit status, the whole
    of stdout through a pipe and the one-line error still arrive."""
    ok = subprocess.run([sys.executable, "-m", "mtmcal_bayes.cli", "identify", "--json"], cwd=tmp_path,
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and json.loads(ok.stdout)  # complete JSON: every buffered byte was flushed
    bad = subprocess.run([sys.executable, "-m", "mtmcal_bayes.cli", "report", "nowhere.toml", "-o", "r"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stdout == "" and bad.stderr.count("\n") == 1, bad.stderr
    assert "nowhere.toml" in bad.stderr and not (tmp_path / "r").exists()
