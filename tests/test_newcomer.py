"""A newcomer's first history and fleet (README "A first fleet", docs/fleet.md): the README's three lines and the
demo script produce an overview with a flagged change and a recalibrate-by date; ``simulate --history`` needs no
truth file, takes either spelling of one, and creates its folders."""

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.io.campaign_reader import load_truth
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, THESIS_TYPE, demo_campaign

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _readme_fleet_lines() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text[text.index("**A first fleet**"):]
    block = block[block.index("```sh") + 5:block.index("```", block.index("```sh") + 5)]
    return [ln for ln in block.strip().splitlines() if ln.strip()]


def test_the_readme_lines_and_the_fleet_demo_give_a_fleet_with_a_flagged_change_and_a_recalibrate_by_date(tmp_path):
    """Acceptance, the README's three lines and the demo in one fleet run.

    * The README's two ``simulate`` lines run as written from the clone's root (here: a copy of what they read);
      they write the same two machines as the demo's M-1 and M-2 (same dates, temperatures, and every repeat
      within 0.2 µm: both simulate from the built-in campaign's posterior mean, the CLI's and the API's, which
      round alike but for a few last digits).  The README's ``fleet`` line is read by the CLI's own parser and
      asks what the demo's fleet does: the plant folder, the exact sampler, the examples' tolerance file.
    * The demo, a fresh process from outside the checkout: three machines (a step, a drift over a temperature
      swing, a single campaign beside a broken file), the fleet, and where to look; no warning.  Its fleet shows
      what the README promises: the step flagged on its date, a recalibrate-by date, σ_model pooled over the
      type (fleet/index.html and fleet.json).
    One fleet instead of two (the fleet command itself: tests/test_fleet.py)."""
    from mtmcal_bayes.cli import build_parser

    lines = _readme_fleet_lines()
    assert len(lines) == 3
    (tmp_path / "examples").mkdir()
    (tmp_path / "examples" / "plant_tolerances.toml").write_bytes((ROOT / "examples" / "plant_tolerances.toml").read_bytes())
    argvs = [shlex.split(line) for line in lines]
    assert all(argv[0] == ".venv/bin/mtmcal-bayes" for argv in argvs)
    assert [argv[1] for argv in argvs] == ["simulate", "simulate", "fleet"]
    for line, argv in zip(lines[:2], argvs[:2]):
        done = subprocess.run([str(BIN / "mtmcal-bayes"), *argv[1:]], cwd=tmp_path, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, (line, done.stderr[-2000:])
    fleet = build_parser().parse_args(argvs[2][1:])
    assert (fleet.directory, fleet.output, fleet.sampler) == ("plant", "fleet", "exact")
    assert (tmp_path / fleet.tolerances).read_bytes() == (ROOT / "examples" / "plant_tolerances.toml").read_bytes()

    done = subprocess.run([sys.executable, str(ROOT / "examples" / "fleet_demo.py"), str(tmp_path / "demo")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr and "Warning" not in done.stderr, done.stderr[-2000:]
    out = done.stdout
    assert re.search(r"M-1: beta_CZ changed before 2026-07-06", out), out
    assert re.search(r"M-2: .*recalibrate alpha_XB by \d{4}-\d\d-\d\d", out), out
    assert "reported, the rest completed" in out and "broken.toml" in out
    assert f"open {tmp_path / 'demo' / 'fleet' / 'index.html'}" in out

    for serial in ("M-1", "M-2"):  # the README's machines are the demo's
        readme, demo = sorted((tmp_path / "plant" / serial).glob("*.toml")), sorted((tmp_path / "demo" / "plant" / serial).glob("*.toml"))
        assert [f.name for f in readme] == [f.name for f in demo] and len(readme) == 4
        for a, b in zip(map(mb.load_campaign, readme), map(mb.load_campaign, demo)):
            assert a.machine.serial == b.machine.serial == serial and a.temperature_C == b.temperature_C
            for ra, rb in zip(a.ballbar.runs, b.ballbar.runs, strict=True):
                assert ra.repeats.keys() == rb.repeats.keys()
                for comp in ra.repeats:
                    assert abs(ra.repeats[comp] - rb.repeats[comp]).max() <= 0.2e-3, (serial, comp)

    doc = json.loads((tmp_path / "demo" / "fleet" / "fleet.json").read_text())
    machines = {m["id"]: m for m in doc["machines"]}
    assert [(c["quantity"], c["date"]) for c in machines["M-1"]["changes"]] == [("beta_CZ", "2026-07-06")]
    assert any(f["recalibrate_by"] for f in machines["M-2"]["forecast"] if f["quantity"] == "alpha_XB")
    html = (tmp_path / "demo" / "fleet" / "index.html").read_text()
    assert "Δ 2026-07-06" in html and "↻" in html
    assert max(t["machines"] for t in doc["sigma_model_types"].values()) >= 2
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


@pytest.mark.parametrize("machine", [t for t in BUILTIN_TYPES if t != THESIS_TYPE])
def test_simulate_history_without_a_truth_takes_the_posterior_mean_of_every_deviation_on_every_type(machine):
    """A campaign of a built-in type without [truth] (its demo's, taken away): the history's truth is its posterior
    mean of every deviation the machine samples, by the machine's own names (once only the thesis' names were looked
    for, and a described machine's history was simulated without deviations); each deviation the campaign
    determines one by one lies within 4 posterior sd of the truth the demo was simulated from."""
    import numpy as np

    from mtmcal_bayes.analysis import CampaignAnalysis
    from mtmcal_bayes.inference.identifiability import DETERMINED, campaign_identifiability

    c = mb.load_campaign(demo_campaign(machine))
    stated, c.truth = c.truth, None
    history = mb.simulate_history(c, n=1, seed=2)  # one campaign, no drift: simulated from the truth itself
    assert "posterior mean" in history.truth_source
    truth = history[0].truth.deviations
    analysis = CampaignAnalysis(c)
    post = analysis.log_posterior
    sampled = [q.name for q in post.space.parameters if q.group == "deviation"]
    assert list(truth) == sampled
    names = [q.name for q in post.space.parameters]
    T = np.eye(post.p)[[names.index(n) for n in sampled]]
    _, sd = analysis.marginal.target_moments(post.likelihood.y[None], T)
    determined = campaign_identifiability(post)
    checked = [n for n in sampled if determined.of(n)[0] == DETERMINED]
    assert checked, "the demo determines some deviations one by one"
    for i, n in enumerate(sampled):
        if n in checked:
            assert abs(truth[n] - stated.deviations.get(n, 0.0)) < 4 * sd[0, i], n
