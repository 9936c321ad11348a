"""``mtmcal-bayes fleet`` / ``mb.fleet``: a folder of machines on Dask (local cluster or a separately started
scheduler) with identical results, a bad campaign reported while the rest completes, and a killed run that
resumes from its cache computing only what had not finished.

The tree: machine M-1 (two campaigns, a 40″ step in beta_XB between them, beta_XB toleranced ±30″), machine
M-2 (one campaign, and a malformed one beside it), both of type MTX-200 and measured at 20.5–21 °C, one campaign
without a serial, and a hidden folder (skipped): four campaign units and one history unit.
"""

from __future__ import annotations

import datetime
import hashlib
import inspect
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import api, units
from mtmcal_bayes.campaign import Tolerance, Truth
from mtmcal_bayes.io.json_text import json_text
from mtmcal_bayes.simulation.history import drift_from_display, synthetic_history

from .conftest import DATA
from .processes import dask_cluster, scheduler_address, stop, wait_for

VENV_BIN = Path(sys.executable).parent
BROKEN = 'format = "mtmcal-campaign/1"\n[machine]\nserial = "M-2"\n'
N_UNITS = 5  # 4 campaigns + 1 history
#: the reader's one line for a campaign that measures nothing (every machine's)
NO_MEASUREMENTS = ("no measurements: give [[ballbar.runs]], [probe] with its runs or [rtest] with its runs (or, for a "
                   "machine to design a campaign for, its [ballbar.setups] and [ballbar.mounts])")


def _cmp(result_json: dict) -> dict:
    """The results as the command line prints them (rounded, NaN as null): what must be identical."""
    return json.loads(json_text({k: result_json[k] for k in ("machines", "errors")}))


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("fleet") / "machines"
    base = mb.load_campaign()
    base.tolerances = {"beta_XB": Tolerance("beta_XB", units.to_internal(-30.0, "arcsec"),
                                            units.to_internal(30.0, "arcsec"), "tolerances.beta_XB_arcsec")}
    truth = Truth({"beta_XB": units.to_internal(-10.0, "arcsec")})
    dates = [datetime.datetime(2025, 1, 6), datetime.datetime(2025, 7, 7)]
    step = drift_from_display("beta_XB", "step", 40.0, datetime.datetime(2025, 4, 1))
    for serial, drifts, seed, n in (("M-1", [step], 11, 2), ("M-2", [], 12, 1)):
        (root / serial).mkdir(parents=True)
        # temperatures and a shared type: the thermal model and the σ_model pooled over the type run on Dask too
        for c in synthetic_history(base, truth, dates[:n], drifts=drifts, serial=serial, seed=seed,
                                   temperatures=[20.5, 21.0][:n]):
            c.machine.type = "MTX-200"
            mb.save_campaign(c, root / serial / f"{c.date.date()}.toml")
    loose = synthetic_history(base, truth, dates[:1], serial="", seed=13)[0]
    (root / "loose").mkdir()
    mb.save_campaign(loose, root / "loose" / "bench-test.toml")
    (root / "M-2" / "broken.toml").write_text(BROKEN)
    (root / ".old").mkdir()
    (root / ".old" / "ignored.toml").write_text("not a campaign")
    return root


@pytest.fixture(scope="module")
def reference(tree, tmp_path_factory):
    """A clean run on a local cluster of one worker, writing the overview."""
    out = tmp_path_factory.mktemp("fleet-out") / "overview"
    cache = tmp_path_factory.mktemp("fleet-cache")
    return mb.fleet(tree, workers=1, output=out, cache=cache), out, cache


def test_one_and_two_local_workers_give_identical_results_and_a_bad_campaign_is_reported(tree, reference, tmp_path):
    ref = reference[0]
    assert ref.run["computed"] == N_UNITS and ref.run["cached"] == 0 and ref.run["workers"] == 1
    two = mb.fleet(tree, workers=2, cache=tmp_path / "cache")
    assert two.run["workers"] == 2 and two.run["computed"] == N_UNITS
    assert _cmp(two.to_json()) == _cmp(ref.to_json())
    # the malformed campaign: one error with the loader's one-line message; everything else completed
    bad = tree / "M-2" / "broken.toml"
    assert ref.errors == [{"file": str(bad), "message": f"{bad}: ballbar: {NO_MEASUREMENTS}"}]
    assert ref.exit_status == 3 and ref.run["failed"] == 0
    by_id = {m["id"]: m for m in ref.machines}
    assert list(by_id) == ["M-1", "M-2", "file:loose/bench-test.toml"]
    assert [len(by_id[i]["campaigns"]) for i in by_id] == [2, 1, 1]
    assert by_id["file:loose/bench-test.toml"]["serial"] is None
    assert [m["history"] is not None for m in ref.machines] == [True, False, False]
    # the 40″ step is found, and the tolerance is checked
    m1 = by_id["M-1"]
    assert [c["quantity"] for c in m1["changes"]] == ["beta_XB"] and m1["latest"]["beta_XB"]["drift"]
    assert m1["latest"]["beta_XB"]["conformity"] in ("conforms", "undecided", "does not conform")
    assert [f["quantity"] for f in m1["forecast"]] == ["beta_XB"]
    assert not by_id["M-2"]["changes"]


def test_the_overview_files(reference):
    ref, out, _ = reference
    for name in ("index.html", "fleet.json", "fleet_summary.csv", "machines/M-1/index.html",
                 "machines/M-1/campaigns.html", "machines/M-1/trend.png", "machines/file-loose_bench-test.toml/index.html"):
        assert (out / name).is_file(), name
    page = (out / "index.html").read_text(encoding="utf-8")
    assert 'href="machines/M-1/index.html"' in page and "broken.toml" in page
    assert '<span class="b drift">Δ 2025-07-07</span>' in page and "changed at 2025-07-07" in page
    rows = (out / "fleet_summary.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + sum(len(m["latest"]) for m in ref.machines) and len(ref.machines[0]["latest"]) >= 8
    assert rows[0].startswith("serial,machine,quantity,unit,date,file,mean,sd")
    assert _cmp(json.loads((out / "fleet.json").read_text(encoding="utf-8"))) == _cmp(ref.to_json())
    history = json.loads((out / "machines/M-1/history.json").read_text(encoding="utf-8"))
    assert history["output"] == str(out / "machines/M-1") and len(history["files"]) == 2


def test_cli_json_interface_and_text(run_cli, tree, reference):
    """Everything in the cache: no cluster is started; the JSON has the scripts' interface; exit status 3."""
    _, _, cache = reference
    code, out, err = run_cli("fleet", tree, "--json", "--cache", cache, "--quiet")
    assert code == 3, err
    assert err.splitlines() == [f"mtmcal-bayes fleet: error: {tree / 'M-2' / 'broken.toml'}: ballbar: {NO_MEASUREMENTS}"]
    doc = json.loads(out)
    assert doc["run"]["cached"] == N_UNITS and doc["run"]["computed"] == 0 and doc["run"]["workers"] == 0
    m = doc["machines"][0]
    assert {"serial", "campaigns", "changes"} <= set(m) and m["serial"] == "M-1"
    c = m["campaigns"][0]
    assert c["file"] == str(tree / "M-1" / "2025-01-06.toml") and c["date"] == "2025-01-06"
    assert {"mean", "sd", "hdi_low", "hdi_high"} <= set(c["summary"]["beta_XB"])
    assert set(doc["errors"][0]) == {"file", "message"}
    assert _cmp(doc) == _cmp(reference[0].to_json())
    code, out, _ = run_cli("fleet", tree, "--cache", cache, "--quiet")
    assert code == 3 and "M-1" in out and "beta_XB" in out and "1 failed (the rest completed)" in out


def test_a_separately_started_scheduler_gives_identical_results(run_cli, tree, reference, tmp_path):
    with dask_cluster(tmp_path) as sched_file:
        address = scheduler_address(sched_file)
        code, out, err = run_cli("fleet", tree, "--scheduler", address, "--json", "--cache", tmp_path / "cache",
                                 "--quiet")
    assert code == 3, err
    doc = json.loads(out)
    assert doc["run"]["scheduler"] == address and doc["run"]["computed"] == N_UNITS
    assert _cmp(doc) == _cmp(reference[0].to_json())


def _entries(cache: Path) -> list[Path]:
    """The cache's entries (a run killed while writing one may leave a hidden temporary file: not an entry)."""
    return [p for p in cache.glob("*.json") if not p.name.startswith(".")]


def test_a_killed_run_resumes_computing_only_what_had_not_finished(tree, reference, tmp_path):
    cache = tmp_path / "cache"
    argv = [sys.executable, "-m", "mtmcal_bayes.cli", "fleet", str(tree), "--cache", str(cache), "--workers", "1",
            "--json", "--quiet"]
    proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        wait_for(lambda: _entries(cache) or proc.poll() is not None, 120, "the first finished unit")
        os.killpg(proc.pid, signal.SIGKILL)  # the run and its cluster, at once
        proc.wait()
    finally:
        stop(proc)
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    finished = {p.name: p.stat().st_mtime_ns for p in _entries(cache)}
    assert 1 <= len(finished) < N_UNITS
    again = mb.fleet(tree, workers=2, cache=cache)
    assert again.run["cached"] == len(finished) and again.run["computed"] == N_UNITS - len(finished)
    assert {p.name: p.stat().st_mtime_ns for p in _entries(cache) if p.name in finished} == finished
    assert len(_entries(cache)) == N_UNITS
    assert _cmp(again.to_json()) == _cmp(reference[0].to_json())


def test_every_malformed_campaign_of_the_corpus_is_its_loaders_one_line_error():
    """A folder of nothing but bad campaigns: each one is an error with the message the loader gives; no unit runs."""
    result = mb.fleet(DATA / "bad", cache=False)
    expected = []
    for path in sorted((DATA / "bad").rglob("*.toml"), key=lambda p: p.relative_to(DATA / "bad").as_posix()):
        with pytest.raises(mb.MtmcalError) as info:
            mb.load_campaign(path)
        expected.append({"file": str(path), "message": str(info.value)})
    assert result.machines == [] and result.errors == sorted(expected, key=lambda e: e["file"])
    assert result.exit_status == 3 and result.run["units"] == 0


@pytest.mark.parametrize("argv,fragment", [
    (["{missing}"], "folder not found"),
    (["{empty}"], "DIR: {empty}: no campaign files"),
    (["{tree}", "--workers", "0"], "--workers: 0: at least one worker"),
    (["{tree}", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "--workers: sets the size of a local cluster"),
    (["{tree}", "--max-steps", "3"], "--max-steps: 3 is below"),
    (["{tree}", "-o", "{missing}/out"], "does not exist"),
])
def test_bad_arguments_are_one_line_and_exit_2(run_cli, tree, tmp_path, argv, fragment):
    (tmp_path / "empty").mkdir()
    values = {"missing": tmp_path / "nowhere", "empty": tmp_path / "empty", "tree": tree}
    code, out, err = run_cli("fleet", *[a.format(**values) for a in argv], "--cache", tmp_path / "cache", "--quiet")
    assert code == 2 and out == "" and len(err.splitlines()) == 1, err
    assert err.startswith("mtmcal-bayes fleet: error: ") and fragment.format(**values) in err, err
    assert not (tmp_path / "cache").exists()


def test_fleet_is_an_api_function_not_shadowed_by_its_package():
    import mtmcal_bayes.fleets  # noqa: F401  (a subpackage named "fleet" would replace mb.fleet here)

    assert mb.fleet is api.fleet and mb.fleet.__doc__
    params = list(inspect.signature(mb.fleet).parameters.values())
    assert params[0].name == "directory" and all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params[1:])
    assert {"scheduler", "workers", "seed", "model", "output", "cache", "progress"} <= {p.name for p in params}


def test_a_unit_that_fails_on_its_worker_is_an_error_and_the_rest_is_kept(tree):
    """What a failed unit becomes (no cluster needed: the assembly of payloads as the workers return them)."""
    from mtmcal_bayes.fleets import FleetResult, FleetSettings
    from mtmcal_bayes.fleets.discover import discover
    from mtmcal_bayes.fleets.run import plan_units

    found = discover(tree)
    settings = FleetSettings()
    units_, of_file, of_machine = plan_units(found, settings, pages=False)
    summary = {"beta_XB": {"mean": 1.0, "sd": 0.5, "hdi_low": 0.0, "hdi_high": 2.0, "unit": "arcsec"}}
    ok = {"result": {"seed": 1, "summary": summary, "diagnostics": {"converged": True}, "warnings": []}, "files": {}}
    payloads = {u.key: dict(ok) for u in units_}
    failed_file = str(tree / "M-1" / "2025-07-07.toml")
    payloads[of_file[failed_file]] = {"error": f"{failed_file}: sampler: it broke"}
    payloads[of_machine["M-1"]] = {"error": "internal error: ValueError: singular"}
    run = {"units": len(units_), "cached": 0, "computed": len(units_), "failed": 2,
           "scheduler": None, "workers": 1, "wall_time_s": 1.0}
    result = FleetResult.assemble(found, settings, payloads=payloads, cached=set(), of_file=of_file,
                                  of_machine=of_machine, run=run)
    assert result.exit_status == 3
    assert {"file": failed_file, "message": f"{failed_file}: sampler: it broke"} in result.errors
    assert {"file": None, "machine": "M-1", "message": "history of M-1: internal error: ValueError: singular"} \
        in result.errors
    m1, m2 = result.machines[:2]
    assert [c["file"] for c in m1["campaigns"]] == [str(tree / "M-1" / "2025-01-06.toml")]
    assert any("no posterior" in n for n in m1["notes"]) and m1["history"] is None and len(m2["campaigns"]) == 1
    assert "3 failed (the rest completed)" in result.to_text()


def test_cache_entries_are_whole_or_ignored(tmp_path):
    from mtmcal_bayes.fleets.cache import UnitCache, default_cache

    store = UnitCache(tmp_path / "c")
    assert store.get("campaign", "k1") is None
    store.put("campaign", "k1", {"result": {"x": 1.5}, "files": {}, "elapsed_s": 0.1})
    assert store.get("campaign", "k1") == {"result": {"x": 1.5}, "files": {}, "elapsed_s": 0.1}
    store.path("campaign", "k2").write_text('{"format": "mtmcal-fleet-unit/1", "key": "k2", "res')  # torn
    assert store.get("campaign", "k2") is None
    store.path("campaign", "k3").write_text(store.path("campaign", "k1").read_text())  # another unit's entry
    assert store.get("campaign", "k3") is None
    assert [p.name for p in (tmp_path / "c").iterdir() if p.name.startswith(".")] == []  # no temporary file left
    assert default_cache(tmp_path / "out") == tmp_path / "out" / ".cache"


def test_plant_tolerances_change_conformity_and_every_cache_key(run_cli, tree, reference, tmp_path):
    """``--tolerances FILE`` replaces each campaign's own [tolerances] everywhere: the campaigns' verdicts, the
    history's forecast, the overview's verdicts; no unit of the reference (its own tolerances) is reused from the
    cache, and the same set given from Python as a dict finds the same entries."""
    ref, _, cache = reference
    tight = tmp_path / "plant.toml"
    tight.write_text("[tolerances]\nbeta_XB_arcsec = 5\nalpha_CZ_arcsec = {low = -100, high = 100}\n")
    code, out, err = run_cli("fleet", tree, "--tolerances", tight, "--json", "--cache", cache, "--quiet",
                             "--workers", "1")
    assert code == 3, err
    doc = json.loads(out)
    assert doc["run"]["cached"] == 0 and doc["run"]["computed"] == N_UNITS  # other tolerances: other keys
    assert doc["settings"]["tolerances"] == {"alpha_CZ": {"low": -100.0, "high": 100.0},
                                             "beta_XB": {"low": -5.0, "high": 5.0}}
    before = {m["id"]: m for m in ref.to_json()["machines"]}
    for m in doc["machines"]:
        assert before[m["id"]]["latest"]["alpha_CZ"]["conformity"] is None  # no tolerance of its own
        assert m["latest"]["alpha_CZ"]["conformity"] == "conforms"
        assert m["latest"]["beta_XB"]["tolerance"] == {"low": -5.0, "high": 5.0}
        for c in m["campaigns"]:
            assert c["summary"]["beta_XB"]["tolerance"] == {"low": -5.0, "high": 5.0}
            assert c["summary"]["alpha_CZ"]["conformity"] == "conforms"
    m1 = doc["machines"][0]
    assert m1["id"] == "M-1" and sorted(f["quantity"] for f in m1["forecast"]) == ["alpha_CZ", "beta_XB"]
    assert before["M-1"]["latest"]["beta_XB"]["tolerance"] == {"low": -30.0, "high": 30.0}
    assert m1["latest"]["beta_XB"]["conformity"] == "does not conform"  # ≈ +30″ after the step, against ±5″
    # the same set as {name: Tolerance} from Python: the same keys, all from the cache, the same results
    again = mb.fleet(tree, cache=cache, tolerances=api.tolerances_of(tight))
    assert again.run["computed"] == 0 and _cmp(again.to_json()) == _cmp(doc)


def test_the_cache_key_names_the_tolerances(tree):
    from mtmcal_bayes.fleets import FleetSettings
    from mtmcal_bayes.fleets.units import UNIT_FORMAT, unit_key
    from mtmcal_bayes.version import __version__

    def tol(half: float) -> dict:
        return {"beta_XB": Tolerance("beta_XB", units.to_internal(-half, "arcsec"), units.to_internal(half, "arcsec"))}

    plain, a, a2, b = (FleetSettings(), FleetSettings(tolerances=tol(5)), FleetSettings(tolerances=tol(5)),
                       FleetSettings(tolerances=tol(6)))
    for kind in ("campaign", "history"):
        keys = [unit_key(kind, ["d1", "d2"], s) for s in (plain, a, b)]
        assert len(set(keys)) == 3 and unit_key(kind, ["d1", "d2"], a2) == keys[1]
    # without plant-wide tolerances a campaign's key is what it was before they existed: old entries stay valid
    old = {"model": "linear", "seed": 1, "sampler": "emcee", "target_ess": 1000.0, "max_steps": 20_000}
    text = json.dumps({"format": UNIT_FORMAT, "kind": "campaign", "digests": ["d1"], "settings": old,
                       "version": __version__}, sort_keys=True)
    assert unit_key("campaign", ["d1"], plain) == hashlib.sha256(text.encode("utf-8")).hexdigest()
    with pytest.raises(mb.MtmcalError, match="tolerances"):
        FleetSettings(tolerances={"beta_XB": 5.0})
