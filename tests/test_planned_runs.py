"""Planned runs (``planned = true``) and ``[design]``: loading, saving, ordering, filling by simulate, and the
commands that need data refusing a campaign that has none (docs/campaign-format.md, "Planned runs and [design]")."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import InputError, load_campaign, parse_campaign, save_campaign
from mtmcal_bayes.campaign import Ballbar, Campaign, DesignGoal, Machine, PlannedRun
from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.io import campaign_to_dict
from mtmcal_bayes.io.tomlio import dumps

from .conftest import DATA

MINIMAL = (DATA / "minimal_one_repeat.toml").read_text()
#: the minimal campaign's machine, bar, setups and mounts, without its runs: a new machine
BASE = MINIMAL[:MINIMAL.index("[[ballbar.runs]]")]
#: lever arms of the minimal campaign, mm (read off the file by hand)
R_B1, R_B2, Z_T2 = 356.3945, 406.4608, 62.2491
ARCSEC = math.pi / 648000.0  # rad per ″, written out so the expectations do not use the package's units


def planned(pattern, setup, mount, repeats, **extra) -> str:
    lines = [f'pattern = "{pattern}"', f'setup = "{setup}"', f'mount = "{mount}"', "planned = true",
             f"repeats = {repeats}"]
    lines += [f"{k} = {v!r}" if isinstance(v, str) else f"{k} = {v}" for k, v in extra.items()]
    return "\n[[ballbar.runs]]\n" + "\n".join(lines).replace("'", '"') + "\n"


DESIGNED = (BASE + planned("CR", "RB2", "C", 2, order=2, minutes=14.5, why="alpha_BT and dy_CZ")
            + planned("BX", "RB1", "B", 3, order=1) + planned("CR", "RB1", "C", 4, order=3)
            + "\n[design]\ntargets = {alpha_BT_arcsec = 2.5, dy_CZ = 1.5}\ncontraction = 0.5\nbudget_min = 240\n"
              "times = {mount = 10, tool_change = 15.5}\n")
PARTLY = MINIMAL + planned("BX", "RB2", "B", 3, why="a second tool length for BX")


@pytest.fixture
def designed(tmp_path):
    path = tmp_path / "designed.toml"
    path.write_text(DESIGNED)
    return path


# --------------------------------------------------------------------------- loading
def test_designed_campaign_loads_in_measuring_order():
    c = parse_campaign(DESIGNED, "d.toml")
    assert c.ballbar.runs == []
    assert [r.label for r in c.ballbar.planned] == ["BX@RB1/B", "CR@RB2/C", "CR@RB1/C"]  # by order, not file
    assert [r.repeats for r in c.ballbar.planned] == [3, 2, 4]
    first, second = c.ballbar.planned[:2]
    assert (second.minutes, second.why, second.order) == (14.5, "alpha_BT and dy_CZ", 2)
    assert (first.minutes, first.why, first.length, first.convention) == (None, "", None, None)
    assert c.design == DesignGoal({"alpha_BT": 2.5, "dy_CZ": 1.5}, 0.5, 240.0, {"mount": 10.0, "tool_change": 15.5})
    assert c.lacking_data() == ["1. BX@RB1/B, 3 repeats", "2. CR@RB2/C, 2 repeats, ~14.5 min (alpha_BT and dy_CZ)",
                                "3. CR@RB1/C, 4 repeats"]


def test_planned_runs_keep_file_order_without_order_keys():
    text = BASE + planned("CR", "RB2", "C", 1) + planned("BX", "RB1", "B", 2) + planned("BY", "RB1", "B", 1)
    c = parse_campaign(text, "p.toml")
    assert [r.label for r in c.ballbar.planned] == ["CR@RB2/C", "BX@RB1/B", "BY@RB1/B"]
    assert all(r.order is None for r in c.ballbar.planned)


def test_a_new_machine_without_runs_loads():
    c = parse_campaign(BASE, "new.toml")
    assert c.ballbar.runs == [] and c.ballbar.planned == [] and c.design is None
    assert set(c.ballbar.setups) == {"RB1", "RB2"} and c.lacking_data() == []


def test_partly_planned_campaign():
    c = parse_campaign(PARTLY, "p.toml")
    assert [r.label for r in c.ballbar.runs] == ["BX@RB1/B", "BY@RB1/B", "CR@RB1/C", "CA@RB1/C", "CR@RB2/C"]
    assert [r.label for r in c.ballbar.planned] == ["BX@RB2/B"]
    assert "BX@RB2/B" in c.lacking_data_note() and "1 planned run" in c.lacking_data_note()


def test_bar_length_of_a_planned_run():
    c = parse_campaign(BASE + planned("BX", "RB1", "B", 1, length_mm=100.0) + planned("BY", "RB1", "B", 1,
                                                                                         length_mm=150.0), "p.toml")
    assert [r.length for r in c.ballbar.planned] == [None, 150.0]  # the campaign's own length is not repeated


def test_positional_construction_still_works():
    bb = Ballbar(100.0, 0.0005, "QC20-W", None, {}, {}, [], "RC-LB", "thesis")
    assert bb.planned == []
    c = Campaign(Machine(), bb, None, {}, {}, None, "x", None, {}, None, 20.0)
    assert c.design is None and c.temperature_C == 20.0


@pytest.mark.parametrize("extra,key,fragment", [
    (planned("BX", "RB1", "B", 3).replace("repeats = 3", "repeats = 2.5"), "ballbar.runs[5].repeats",
     "expected a whole number"),
    (planned("BX", "RB1", "B", 3).replace("repeats = 3", 'repeats = "3"'), "ballbar.runs[5].repeats",
     "expected a whole number"),
    (planned("BX", "RB2", "B", 10001), "ballbar.runs[5].repeats", "from 1 to 10000"),
    (planned("BX", "RB2", "B", 3).replace("repeats = 3\n", ""), "ballbar.runs[5].repeats", "missing"),
    (planned("BX", "RB2", "B", 3, order=0), "ballbar.runs[5].order", "from 1 up"),
    (planned("BX", "RB2", "B", 3, minutes=-1), "ballbar.runs[5].minutes", "must not be negative"),
    (planned("BX", "RB2", "B", 3, length_mm=0), "ballbar.runs[5].length_mm", "must be positive"),
    (planned("BX", "RB2", "B", 3, why=3), "ballbar.runs[5].why", "expected a string"),
    (planned("BX", "RB2", "B", 3).replace("planned = true", 'planned = "yes"'), "ballbar.runs[5].planned",
     "expected true"),
    (planned("BX", "RB2", "B", 3, trace_csv="a.csv"), "ballbar.runs[5].planned", "has data (trace_csv)"),
    (planned("BX", "RB9", "B", 3), "ballbar.runs[5].setup", "not in [ballbar.setups]"),
    (planned("BX", "RB2", "C", 3), "ballbar.runs[5].mount", "R_C"),  # a B pattern on a mount off the C axis
    (planned("BX", "RB2", "B", 3, convention="C0=-Y,C90=+X"), "ballbar.runs[5].convention", "turns the B axis"),
    (planned("BX", "RB2", "B", 3, convention="sideways"), "ballbar.runs[5].convention", "unknown convention"),
    # duplicates across measured and planned runs, and among planned ones
    (planned("CR", "RB2", "C", 3), "ballbar.runs[5]", "repeats ballbar.runs[4] (pattern CR, setup 'RB2'"),
    (planned("BX", "RB2", "B", 3) + planned("BX", "RB2", "B", 1), "ballbar.runs[6]", "repeats ballbar.runs[5]"),
    # order: all or none, each its own
    (planned("BX", "RB2", "B", 3, order=1) + planned("BY", "RB2", "B", 1), "ballbar.runs[6]",
     "give every planned run its order"),
    (planned("BX", "RB2", "B", 3, order=2) + planned("BY", "RB2", "B", 1, order=2), "ballbar.runs[6].order",
     "also the order of ballbar.runs[5]"),
    # [design]
    ("\n[design]\ntargets = {alpha_BT_um = 2}\n", "design.targets.alpha_BT_um", "unknown quantity"),
    ("\n[design]\ntargets = {alpha_BT = 2, alpha_BT_arcsec = 3}\n", "design.targets.alpha_BT_arcsec",
     "a second target for alpha_BT"),
    ("\n[design]\ntargets = {dy_CZ_um = 0}\n", "design.targets.dy_CZ_um", "must be positive"),
    ("\n[design]\ntargets = {dy_CZ_um = nan}\n", "design.targets.dy_CZ_um", "NaN"),
    ("\n[design]\ncontraction = 0\n", "design.contraction", "not a contraction"),
    ("\n[design]\ncontraction = 1\n", "design.contraction", "not a contraction"),
    ("\n[design]\nbudget_min = 0\n", "design.budget_min", "must be positive"),
    ("\n[design]\ntimes = {mount = -1}\n", "design.times.mount", "must not be negative"),
    ("\n[design]\ntimes = {mount = inf}\n", "design.times.mount", "infinite"),
    ("\n[design]\ngoal = 3\n", "design.goal", "unknown key"),
])
def test_bad_planned_runs_and_design(extra, key, fragment):
    with pytest.raises(InputError) as info:
        parse_campaign(MINIMAL + extra, "bad.toml")
    assert info.value.key == key, str(info.value)
    assert fragment in info.value.message, str(info.value)
    assert "\n" not in str(info.value)


def test_measured_run_keeps_its_place_when_filled_in():
    """The engineer fills in a planned run where it stands: no duplicate, no planned key left."""
    text = DESIGNED.replace('repeats = 3\norder = 1\n', 'order = 1\n', 1)
    assert text != DESIGNED
    with pytest.raises(InputError, match="only a planned run"):  # order is a planned run's key
        parse_campaign(text.replace("planned = true\norder = 1", "ex_um = [1.0]\nez_um = [2.0]\norder = 1", 1), "x")
    measured = text.replace("planned = true\norder = 1\n", "ex_um = [1.0]\nez_um = [2.0]\n", 1)
    c = parse_campaign(measured, "x.toml")
    assert [r.label for r in c.ballbar.runs] == ["BX@RB1/B"]
    assert [r.label for r in c.ballbar.planned] == ["CR@RB2/C", "CR@RB1/C"]


# --------------------------------------------------------------------------- saving
def test_round_trip(tmp_path, designed):
    c = load_campaign(designed)
    save_campaign(c, tmp_path / "again.toml")
    again = load_campaign(tmp_path / "again.toml")
    assert again.ballbar.planned == c.ballbar.planned and again.design == c.design
    assert dumps(campaign_to_dict(again)) == dumps(campaign_to_dict(c))
    runs = tomllib.loads((tmp_path / "again.toml").read_text())["ballbar"]["runs"]
    assert [(r["pattern"], r["setup"], r.get("order")) for r in runs] == [("BX", "RB1", 1), ("CR", "RB2", 2),
                                                                          ("CR", "RB1", 3)]
    assert runs[1] == {"pattern": "CR", "setup": "RB2", "mount": "C", "planned": True, "repeats": 2,
                       "minutes": 14.5, "order": 2, "why": "alpha_BT and dy_CZ"}
    design = tomllib.loads((tmp_path / "again.toml").read_text())["design"]
    assert design["targets"] == {"alpha_BT_arcsec": 2.5, "dy_CZ_um": 1.5}


def test_round_trip_of_a_partly_planned_campaign(tmp_path):
    c = parse_campaign(PARTLY + planned("BY", "RB2", "B", 2, length_mm=150.0, convention="machine", minutes=0),
                       "p.toml")
    save_campaign(c, tmp_path / "p.toml")
    again = load_campaign(tmp_path / "p.toml")
    assert again.ballbar.planned == c.ballbar.planned
    assert again.ballbar.planned[1] == PlannedRun("BY", "RB2", "B", 2, "machine", 0.0, "", None, 150.0)
    assert [r.label for r in again.ballbar.runs] == [r.label for r in c.ballbar.runs]
    for a, b in zip(c.ballbar.runs, again.ballbar.runs):
        for comp in a.repeats:
            np.testing.assert_allclose(a.repeats[comp], b.repeats[comp], rtol=1e-12)
    runs = tomllib.loads((tmp_path / "p.toml").read_text())["ballbar"]["runs"]
    assert [r.get("planned", False) for r in runs] == [False] * 5 + [True, True]  # planned after the measured


def test_saving_a_new_machine(tmp_path):
    c = parse_campaign(BASE, "new.toml")
    save_campaign(c, tmp_path / "new.toml")
    assert "runs" not in tomllib.loads((tmp_path / "new.toml").read_text())["ballbar"]
    assert load_campaign(tmp_path / "new.toml").ballbar.runs == []


# --------------------------------------------------------------------------- simulate fills the planned runs
@pytest.fixture
def truth(tmp_path):
    path = tmp_path / "truth.toml"
    path.write_text("[deviations]\nbeta_XB_arcsec = -24.0\nalpha_BT_arcsec = 10.0\ndx_CZ_um = 50.0\n")
    return path


def test_simulate_fills_planned_runs_noise_free(run_cli, tmp_path, designed, truth):
    code, out, err = run_cli("simulate", designed, "--truth", truth, "--model", "linear", "-o", tmp_path / "f.toml")
    assert code == 0, err
    filled = load_campaign(tmp_path / "f.toml")
    assert filled.ballbar.planned == []
    assert [r.label for r in filled.ballbar.runs] == ["BX@RB1/B", "CR@RB2/C", "CR@RB1/C"]  # measuring order
    bx, cr2, _ = filled.ballbar.runs
    assert {c: len(v) for c, v in bx.repeats.items()} == {"ex": 1, "ez": 1}
    # thesis relations (SPEC §3.1): ez_BX = R_B·beta_XB; ex_CR = −dx_CZ − Z_T·beta_XB; ey_CR = Z_T·alpha_BT
    assert bx.repeats["ex"][0] == pytest.approx(0.0, abs=1e-9)
    assert bx.repeats["ez"][0] == pytest.approx(R_B1 * -24.0 * ARCSEC, abs=1e-7)
    assert cr2.repeats["ex"][0] == pytest.approx(-0.050 - Z_T2 * -24.0 * ARCSEC, abs=1e-7)
    assert cr2.repeats["ey"][0] == pytest.approx(Z_T2 * 10.0 * ARCSEC, abs=1e-7)
    assert filled.design == load_campaign(designed).design
    code, _, err = run_cli("identify", tmp_path / "f.toml")  # a normal campaign now
    assert code == 0, err


def test_simulate_with_noise_measures_the_planned_repeats(run_cli, tmp_path, truth):
    path = tmp_path / "partly.toml"
    path.write_text(PARTLY + planned("BY", "RB2", "B", 4))
    code, _, err = run_cli("simulate", path, "--truth", truth, "--noise", "--seed", "5", "-o", tmp_path / "f.toml")
    assert code == 0, err
    filled = load_campaign(tmp_path / "f.toml")
    assert filled.ballbar.planned == []
    assert [r.label for r in filled.ballbar.runs][5:] == ["BX@RB2/B", "BY@RB2/B"]
    assert [len(r.repeats["ex"]) for r in filled.ballbar.runs] == [1, 1, 1, 1, 1, 3, 4]
    bx2 = filled.ballbar.runs[5].repeats["ez"]
    assert np.ptp(bx2) > 0  # scattered repeats
    assert np.mean(bx2) == pytest.approx(R_B2 * -24.0 * ARCSEC, abs=0.004)  # within a few µm of the prediction


def test_simulate_refuses_a_planned_bar_length_of_its_own(run_cli, tmp_path, truth):
    path = tmp_path / "long.toml"
    path.write_text(BASE + planned("BX", "RB1", "B", 1) + planned("BY", "RB1", "B", 1, length_mm=150.0))
    code, out, err = run_cli("simulate", path, "--truth", truth, "-o", tmp_path / "f.toml")
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and str(path) in err and ": ballbar.runs: " in err
    assert "BY@RB1/B" in err and "150" in err
    assert not (tmp_path / "f.toml").exists()


def test_simulate_without_any_run_is_one_line(run_cli, tmp_path, truth):
    path = tmp_path / "new.toml"
    path.write_text(BASE)
    code, out, err = run_cli("simulate", path, "--truth", truth)
    assert code == 2 and out == "" and len(err.splitlines()) == 1 and ": ballbar.runs: " in err


def test_simulate_python_api_fills_planned(designed, truth):
    c = load_campaign(designed)
    sim = mb.simulate(c, truth=truth, model="linear")
    assert len(sim.observations) == 6
    synth = sim.synthetic_campaign()
    assert synth.ballbar.planned == [] and len(synth.ballbar.runs) == 3
    assert c.ballbar.planned and c.ballbar.runs == []  # the campaign itself is left alone


# --------------------------------------------------------------------------- commands that need data
def test_sample_on_a_partly_planned_campaign_names_the_planned_runs(run_cli, tmp_path):
    path = tmp_path / "partly.toml"
    path.write_text(PARTLY)
    code, out, err = run_cli("sample", path, "--sampler", "exact", "--seed", "1", "--quiet")
    assert code == 0, err
    lines = [x for x in err.splitlines() if "planned" in x]
    assert len(lines) == 1, err
    assert "BX@RB2/B" in lines[0] and "lacks data" in lines[0]


NEEDING_DATA = (("identify", "{campaign}"), ("sample", "{campaign}", "-o", "{out}", "--quiet"),
                ("sample", "{campaign}", "--closed-form"), ("report", "{campaign}", "-o", "{out}", "--quiet"),
                ("plan", "{campaign}", "-o", "{out}"), ("instruments", "{campaign}"),
                ("compensate", "{campaign}", "{program}", "-o", "{out}"),
                ("validate", "sbc", "{campaign}", "-o", "{out}", "--quiet"))


@pytest.mark.parametrize("template", NEEDING_DATA, ids=lambda t: "-".join(a for a in t if a[0] not in "-{"))
@pytest.mark.parametrize("kind", ["designed", "new"])
def test_commands_needing_data_refuse_a_campaign_without_measured_runs(run_cli, tmp_path, template, kind):
    path = tmp_path / f"{kind}.toml"
    path.write_text(DESIGNED if kind == "designed" else BASE)
    values = {"campaign": path, "out": tmp_path / "out", "program": data_path("fig4_30a_bx_original.nc")}
    before = sorted(tmp_path.iterdir())
    code, out, err = run_cli(*[a.format(**values) for a in template])
    assert code == 2, err
    assert out == "" and "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"mtmcal-bayes {template[0]}: error: {path}: ballbar.runs: no measured runs"), lines[0]
    if kind == "designed":
        assert "3 planned runs lack data" in lines[0] and "simulate" in lines[0]
    assert sorted(tmp_path.iterdir()) == before


def test_api_identify_refuses_without_measured_runs(designed):
    with pytest.raises(InputError) as info:
        mb.identify(designed)
    assert info.value.key == "ballbar.runs" and info.value.source == str(designed)
    with pytest.raises(InputError):
        mb.closed_form(load_campaign(designed))


def test_the_documented_example_loads():
    import re
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs" / "campaign-format.md").read_text(encoding="utf-8")
    section = doc[doc.index("## Planned runs and `[design]`"):]
    block = re.findall(r"```toml\n(.*?)```", section, re.S)[0]
    c = parse_campaign('format = "mtmcal-campaign/1"\n[ballbar]\nlength_mm = 100.0\naccuracy_um = 0.5\n' + block,
                       "doc.toml")
    assert [r.label for r in c.ballbar.runs] == ["BX@RB1/B"]
    assert [(r.label, r.repeats) for r in c.ballbar.planned] == [("BY@RB1/B", 3)]
    assert c.design.targets == {"alpha_XB": 2.0, "gamma_XB": 2.0, "dy_CZ": 1.5}
