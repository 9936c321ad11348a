"""A newcomer's first history and fleet (README "A first fleet", docs/fleet.md): the README's three lines and the
demo script produce an overview with a flagged change and a recalibrate-by date; ``simulate --history`` needs no
truth file, takes either spelling of one, and creates its folders."""

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import mtmcal_bayes as mb
from mtmcal_bayes.io.campaign_reader import load_truth

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _readme_fleet_lines() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text[text.index("**A first fleet**"):]
    block = block[block.index("```sh") + 5:block.index("```", block.index("```sh") + 5)]
    return [ln for ln in block.strip().splitlines() if ln.strip()]


def test_the_readme_lines_give_a_fleet_with_a_flagged_change_and_a_recalibrate_by_date(tmp_path):
    """Acceptance: the README's three lines, run as written from the clone's root (here: in a copy of what they
    read, the examples' tolerance file), write fleet/index.html with the step flagged and a recalibrate-by date."""
    lines = _readme_fleet_lines()
    assert len(lines) == 3
    (tmp_path / "examples").mkdir()
    (tmp_path / "examples" / "plant_tolerances.toml").write_bytes((ROOT / "examples" / "plant_tolerances.toml").read_bytes())
    for line in lines:
        argv = shlex.split(line)
        assert argv[0] == ".venv/bin/mtmcal-bayes"
        done = subprocess.run([str(BIN / "mtmcal-bayes"), *argv[1:]], cwd=tmp_path, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, (line, done.stderr[-2000:])
    doc = json.loads((tmp_path / "fleet" / "fleet.json").read_text())
    m1, m2 = doc["machines"]
    assert [(c["quantity"], c["date"]) for c in m1["changes"]] == [("beta_CZ", "2026-07-06")]
    assert any(f["recalibrate_by"] for f in m2["forecast"] if f["quantity"] == "alpha_XB")
    html = (tmp_path / "fleet" / "index.html").read_text()
    assert "Δ 2026-07-06" in html and "↻" in html
    assert doc["sigma_model_types"]["MTX"]["machines"] == 2


def test_the_fleet_demo_runs_and_says_where_to_look(tmp_path):
    """The demo, a fresh process from outside the checkout: three machines (a step, a drift over a temperature
    swing, a single campaign beside a broken file), the fleet, and where to look; no warning."""
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "fleet_demo.py"), str(tmp_path / "demo")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr and "Warning" not in done.stderr, done.stderr[-2000:]
    out = done.stdout
    assert re.search(r"M-1: beta_CZ changed before 2026-07-06", out), out
    assert re.search(r"M-2: .*recalibrate alpha_XB by \d{4}-\d\d-\d\d", out), out
    assert "reported, the rest completed" in out and "broken.toml" in out
    assert f"open {tmp_path / 'demo' / 'fleet' / 'index.html'}" in out
    assert (tmp_path / "demo" / "fleet" / "index.html").exists()
    history = json.loads((tmp_path / "demo" / "fleet" / "machines" / "M-2" / "history.json").read_text())
    assert history["thermal"]["alpha_XB"]["identified"]


def test_simulate_history_without_a_truth_file_says_what_it_used_and_creates_folders(run_cli, tmp_path):
    """No --truth: the built-in campaign has no [truth], so its posterior mean, said in one line; the folder and its
    missing parents are created as -o does elsewhere."""
    target = tmp_path / "plant" / "deep" / "M-9"
    code, out, err = run_cli("simulate", "--history", target, "--campaigns", "2", "--serial", "M-9")
    assert code == 0, err
    assert "posterior mean" in out and len(out.strip().splitlines()) == 1
    files = sorted(target.glob("*.toml"))
    assert len(files) == 2 and mb.load_campaign(files[0]).machine.serial == "M-9"


def test_simulate_history_takes_the_campaigns_own_truth(run_cli, tmp_path, thesis):
    """A campaign with a [truth] (a synthetic one): its truth, said."""
    code, _, err = run_cli("simulate", "--truth", _truth_file(tmp_path, "[deviations]\nbeta_CZ_arcsec = 12\n"),
                           "--noise", "-o", tmp_path / "synthetic.toml")
    assert code == 0, err
    code, out, err = run_cli("simulate", tmp_path / "synthetic.toml", "--history", tmp_path / "h", "--campaigns", "2")
    assert code == 0, err
    assert "[truth] of" in out and "synthetic.toml" in out


def test_both_truth_spellings_give_the_same_truth(tmp_path, thesis):
    """docs/campaign-format.md writes the truth as [truth.deviations] (a campaign's section); a truth file may say
    [deviations] at the top: both work, and a campaign file with its [truth] works as a truth file."""
    top = load_truth(_truth_file(tmp_path, "[deviations]\nbeta_XB_arcsec = -24.11\ndx_CZ_um = 53.13\n"), thesis)
    nested = load_truth(_truth_file(tmp_path, "[truth.deviations]\nbeta_XB_arcsec = -24.11\ndx_CZ_um = 53.13\n",
                                    "nested.toml"), thesis)
    assert top.deviations == nested.deviations and set(top.deviations) == {"beta_XB", "dx_CZ"}


def test_a_truth_written_both_ways_or_misspelt_is_one_line(run_cli, tmp_path):
    both = _truth_file(tmp_path, "[deviations]\nbeta_XB_arcsec = 1\n[truth.deviations]\nbeta_XB_arcsec = 2\n")
    code, _, err = run_cli("simulate", "--history", tmp_path / "h", "--truth", both)
    assert code == 2 and ": truth:" in err and len(err.strip().splitlines()) == 1
    bad = _truth_file(tmp_path, "[truth.deviations]\nbeta_XB = 2\n", "bad.toml")
    code, _, err = run_cli("simulate", "--history", tmp_path / "h2", "--truth", bad)
    assert code == 2 and "truth.deviations.beta_XB" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "h").exists() and not (tmp_path / "h2").exists()


def test_plain_simulate_still_needs_a_truth(run_cli):
    code, _, err = run_cli("simulate")
    assert code == 2 and "--truth" in err and len(err.strip().splitlines()) == 1


def _truth_file(tmp_path, text, name="truth.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path
