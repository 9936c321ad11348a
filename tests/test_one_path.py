"""One machine model (SPEC §20): the thesis machine is a description plus a plug-in, and what the engine does it does
for every machine, asking the machine what it provides."""

from __future__ import annotations

import copy
import re

import mtmcal_bayes as mb
from mtmcal_bayes.datasets import builtin_text
from mtmcal_bayes.machines.plugins import provided


def test_the_thesis_machine_is_its_description_and_its_plugin():
    """The built-in thesis campaign's machine has the thesis plug-in, which gives its models, its default data and
    the thesis' names as aliases of the ISO symbols; a described machine has none of these from a plug-in."""
    thesis = mb.load_campaign()
    assert provided(thesis.machine, "kinematic_model") == "htm-thesis"
    assert provided(thesis.machine, "default_data") == "ballbar"
    from mtmcal_bayes.io.machine_reader import builtin_description

    desc = builtin_description("integrex-i200")
    assert desc.plugins == ("thesis",) and desc.name_of("E_X0C") == "dx_CZ" and desc.name_of("E_C0C") == "E_C0C"
    trunnion = builtin_description("trunnion")
    assert trunnion.plugins == () and trunnion.name_of("E_X0C") == "E_X0C"
    assert provided(trunnion, "kinematic_model") is None


def test_a_description_naming_an_unknown_plugin_is_refused(tmp_path, run_cli):
    text = builtin_text("machines/trunnion.toml").replace('configuration =', 'plugins = ["no_such_plugin"]\nconfiguration =', 1)
    machine = tmp_path / "m.toml"
    machine.write_text(text, encoding="utf-8")
    campaign = builtin_text("machines/trunnion-demo.toml")
    campaign = campaign.replace('description = "trunnion"', f'description = "{machine.name}"', 1)
    assert f'description = "{machine.name}"' in campaign
    path = tmp_path / "c.toml"
    path.write_text(campaign, encoding="utf-8")
    code, _, err = run_cli("sample", str(path), "--sampler", "exact")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "plugins" in err and "no_such_plugin" in err, err


def test_a_probe_only_campaign_of_the_thesis_machine_is_a_campaign(tmp_path, run_cli):
    """As on any machine: its probe data sample, and so does its default data (the plug-in's, the ball bar, holds only
    where the campaign has ball-bar runs: else every instrument it has, the probe); the ball bar asked for is refused
    in one line saying to use the probe data."""
    c = copy.deepcopy(mb.load_campaign())
    c.ballbar.runs, c.reported = [], {}
    path = tmp_path / "probe_only.toml"
    mb.save_campaign(c, path)
    code, out, err = run_cli("sample", str(path), "--sampler", "exact", "--data", "probe", "--seed", "1", "--json")
    assert code == 0, err
    code, default, err = run_cli("sample", str(path), "--sampler", "exact", "--seed", "1", "--json")
    assert code == 0, err
    timed = re.compile(r'"[a-z_]*(time|per_s)[a-z_]*": [0-9.e+-]+')  # the run's own timings differ
    assert timed.sub("", default) == timed.sub("", out)
    code, _, err = run_cli("sample", str(path), "--sampler", "exact", "--data", "ballbar")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "use the probe data" in err, err


def test_the_engine_never_asks_which_kind_of_machine_it_holds():
    """No module of the package tests a machine's kind (issue 42 counted 82 such places: ``.described``,
    ``is_described``, ``is_thesis``, ``names == "thesis"``); where behaviour differs it asks the machine's plug-ins
    (``machines/plugins.py``, the one place that resolves them)."""
    import re
    from pathlib import Path

    root = Path(mb.__file__).parent
    idiom = re.compile(r"\.described\b|\bis_described\b|\bis_thesis\b|names\s*==\s*[\"']thesis[\"']")
    found = [f"{p.relative_to(root)}:{i}" for p in root.rglob("*.py")
             for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if idiom.search(line)]
    assert found == []
