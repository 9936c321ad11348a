"""Earlier campaign files stay valid: every command on every file of the corpus ``tests/data/formats/``.

The corpus holds campaign files as earlier versions of the package wrote or published them (its README says which
wrote each).  A file is valid or not the same way for every command (the loader's verdict, with the gaps it
records: :meth:`~mtmcal_bayes.campaign.Campaign.gaps`); a command then exits 0, or — where the file lacks what that
command needs — 2 with one line naming the file and what is missing.  Which commands need what each file lacks is
written out below (``NEEDS``); every other command must succeed on it.  The corpus' history counts once: its second
campaign, written by the same version with the same keys, is read by ``fleet`` with the first, as the history of their
machine.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import mtmcal_bayes as mb

from .conftest import DATA

FORMATS = DATA / "formats"
FILES = sorted(FORMATS.glob("*.toml"))
#: the second campaign of the corpus' history: written by the same version as the first, with the same keys, so it
#: is read by ``fleet`` (with its twin, as their machine's history) rather than by every command again
SECOND_OF_HISTORY = "history_M-7_2_5d7542f.toml"
CORPUS = [f for f in FILES if f.name != SECOND_OF_HISTORY]
TRUTH = DATA / "formats_truth.toml"
NC = Path(mb.__file__).parent / "datasets" / "fig4_30a_bx_original.nc"

#: every command that reads a campaign, as ``name: argv after the command`` (``{f}`` the file, ``{out}`` a fresh
#: folder); the fast samplers where a command offers them (what is tested is the reading of the file)
COMMANDS = {
    "identify": ["identify", "{f}"],
    "sensitivity": ["sensitivity", "{f}"],
    "simulate": ["simulate", "{f}", "--truth", str(TRUTH), "--json"],
    "simulate -o": ["simulate", "{f}", "--truth", str(TRUTH), "--noise", "--seed", "2", "-o", "{out}/sim.toml"],
    "sample": ["sample", "{f}", "--seed", "1", "--quiet"],
    "sample --data both": ["sample", "{f}", "--data", "both", "--sampler", "exact", "--quiet"],
    "report": ["report", "{f}", "-o", "{out}/report", "--sampler", "exact", "--quiet"],
    "plan": ["plan", "{f}"],
    "plan --data both": ["plan", "{f}", "--data", "both"],
    "design": ["design", "{f}"],
    "next": ["next", "{f}"],
    "instruments": ["instruments", "{f}"],
    "compensate": ["compensate", "{f}", str(NC), "-o", "{out}/compensated.nc"],
    "ncgen": ["ncgen", "BX", "{f}"],
    "validate sbc": ["validate", "sbc", "{f}", "--n", "3", "--sampler", "exact", "--scheduler", "{scheduler}",
                     "--quiet"],
    "history": ["history", "{f}"],
}

PROBE_BOTH = ("sample --data both", "plan --data both", "instruments")
MEASURED = ("identify", "sample", "sample --data both", "report", "plan", "plan --data both", "instruments",
            "compensate", "validate sbc", "history")
#: ``{file: {command: what the one-line error must name}}``: what each file lacks for which command
NEEDS = {
    "thesis_first_published.toml": {**{c: "probe.c_axis.stylus" for c in PROBE_BOTH + ("compensate",)},
                                    "history": "at least two campaigns"},
    "simulated_ballbar_566b977.toml": {"sample --data both": "needs touch-probe readings",
                                       "plan --data both": "needs touch-probe readings",
                                       "instruments": "needs ball-bar runs and touch-probe readings",
                                       "history": "at least two campaigns"},
    "simulated_probe_ae98686.toml": {"history": "at least two campaigns"},
    "history_M-7_1_5d7542f.toml": {"history": "at least two campaigns"},
    "designed_thesis_d54cc98.toml": {"history": "at least two campaigns"},
    "designed_new_machine_d54cc98.toml": {c: "ballbar.runs: no measured runs" for c in MEASURED},
}


def test_the_corpus_is_what_its_readme_lists():
    readme = (FORMATS / "README.md").read_text()
    assert {f.name for f in CORPUS} == set(NEEDS) and all(f"`{f.name}`" in readme for f in FILES)
    assert len(CORPUS) >= 6 and SECOND_OF_HISTORY in {f.name for f in FILES}


@pytest.fixture(scope="module")
def scheduler():
    """One in-process Dask cluster for every ``validate sbc`` of the module (a local cluster per run costs more
    than the run)."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:  # no warning: 8787 busy
        yield cluster.scheduler_address


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("file", CORPUS, ids=lambda f: f.stem)
def test_every_command_on_every_earlier_file(run_cli, tmp_path, request, file, command):
    scheduler = request.getfixturevalue("scheduler") if command == "validate sbc" else ""
    argv = [a.format(f=file, out=tmp_path, scheduler=scheduler) for a in COMMANDS[command]]
    code, out, err = run_cli(*argv)
    needed = NEEDS[file.name].get(command)
    if needed is None:
        assert code == 0, err
        if (file.name, command) in CHECKS:
            CHECKS[file.name, command](out, tmp_path)
        return
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith(f"mtmcal-bayes {argv[0]}: error: ") and needed in lines[0], lines[0]
    assert file.name in lines[0], lines[0]
    assert not any(tmp_path.iterdir()), "nothing written"


def _reports_without_its_probe_comparison(out: str, tmp_path: Path) -> None:
    """The first-published thesis file: the report is written, the instruments' comparison skipped and why."""
    page = (tmp_path / "report" / "index.html").read_text()
    assert "The comparison of the instruments" in page and "skipped: the C-axis run names no stylus" in page
    assert "instruments_forest.png" not in page and "skipped: the C-axis run names no stylus" in out


def _reports_without_probe_data(out: str, tmp_path: Path) -> None:
    """A campaign without touch-probe data (as the first simulate wrote them): the report says so, its probe
    columns are empty and it writes no probe identification."""
    import pandas as pd

    html = (tmp_path / "report" / "index.html").read_text(encoding="utf-8")
    assert "No touch-probe data in this campaign" in html and "No touch-probe data in this campaign" in out
    s = pd.read_csv(tmp_path / "report" / "summary.csv", index_col="quantity")
    assert s["probe_reported"].isna().all() and s["probe_recomputed"].isna().all()
    assert not (tmp_path / "report" / "identification_probe.csv").exists()
    # and no record of a choice of reading: nothing is marked
    assert "†" not in html + out and "rejected reading" not in html and "rests_on_reading" not in s.columns


#: what a successful command must also show on a file, by ``(file, command)``
CHECKS = {("thesis_first_published.toml", "report"): _reports_without_its_probe_comparison,
          ("simulated_ballbar_566b977.toml", "report"): _reports_without_probe_data}


FIRST = FORMATS / "thesis_first_published.toml"


def test_a_ball_bar_plan_on_it_keeps_every_probe_candidate(run_cli):
    """The probe candidates are new runs, each with a stylus of the campaign's B-axis run: the C-axis run's missing
    stylus keeps none of them out (C indexed as well as B), and no note says one was skipped."""
    code, out, err = run_cli("plan", FIRST, "--target", "alpha_BT", "--json")
    assert code == 0, err
    plan = json.loads(out)
    probes = [r for r in plan["candidates"] if r["kind"] == "probe"]
    assert {r["pattern"] for r in probes} == {"probe B", "probe C"}
    assert "stylus 382.95 mm" in {r["setup"] for r in probes}  # the first stylus, short
    assert not any("skipped" in n for n in plan["notes"]), plan["notes"]


def test_where_the_stylus_is_needed_the_line_says_what_would_be_assumed(run_cli):
    code, out, err = run_cli("sample", FIRST, "--data", "probe", "--sampler", "exact", "--quiet")
    assert code == 2
    assert 'probe.c_axis.stylus: missing: the C-axis run names no stylus' in err
    assert 'add stylus = "short" (the shortest of [probe.b_axis.styli]: short, long' in err


def test_naming_the_stylus_is_all_the_first_published_file_needs(tmp_path, run_cli):
    """The gap closes with the key its message names, and the probe then enters the likelihood."""
    text = FIRST.read_text().replace("datum", "datum").replace(
        "[probe.c_axis]\n", '[probe.c_axis]\nstylus = "short"\n', 1)
    fixed = tmp_path / "fixed.toml"
    fixed.write_text(text)
    assert mb.load_campaign(FIRST).gaps() and not mb.load_campaign(fixed).gaps()
    code, out, err = run_cli("instruments", fixed)
    assert code == 0, err


def test_a_fleet_of_the_corpus_reports_the_file_it_cannot_use_and_completes_the_rest(run_cli, tmp_path):
    """Every campaign's posterior and the corpus history's (its two campaigns), on Dask: only the campaign without
    measured runs fails (a failed history would be a line of its own)."""
    code, out, err = run_cli("fleet", FORMATS, "-o", tmp_path / "fleet", "--workers", "1", "--sampler", "exact",
                             "--cache", tmp_path / "cache", "--quiet")
    lines = err.strip().splitlines()
    assert code == 3 and len(lines) == 1, err
    assert "designed_new_machine_d54cc98.toml: ballbar.runs: no measured runs" in lines[0]
    fleet = json.loads((tmp_path / "fleet" / "fleet.json").read_text())
    m7 = next(m for m in fleet["machines"] if m["serial"] == "M-7")
    assert m7["history"] is not None and len(m7["history"]["dates"]) == 2


def test_the_readme_shows_the_line_the_first_published_file_gets(run_cli, tmp_path):
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    shown = next(ln for ln in readme.splitlines() if ln.startswith("mtmcal-bayes instruments: error: first_published"))
    copy = tmp_path / "first_published.toml"
    copy.write_text(FIRST.read_text())
    code, out, err = run_cli("instruments", copy)
    assert code == 2 and err.strip() == shown.replace("first_published.toml", str(copy))
