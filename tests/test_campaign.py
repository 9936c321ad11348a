"""Campaign loading, validation, saving."""

import subprocess
import sys

import numpy as np
import pytest

from mtmcal_bayes import InputError, load_campaign, parse_campaign, save_campaign
from mtmcal_bayes.io import campaign_to_dict
from mtmcal_bayes.io.tomlio import dumps

from .conftest import DATA

BAD = DATA / "bad"
EXPECTED = [line.split("\t") for line in (BAD / "expected.tsv").read_text().splitlines()[1:]]


def test_builtin_campaign_contents(thesis):
    bb = thesis.ballbar
    assert [r.pattern for r in bb.runs] == ["BX", "BY", "CR", "CA", "CR"]
    assert bb.setups["RB2"].R_B == pytest.approx(406.4608)
    assert bb.runs[0].repeats["ex"] == pytest.approx([-0.0514, -0.0521, -0.0516])  # mm
    assert thesis.reported["ballbar"]["alpha_CZ"].decimals == 2
    assert thesis.reported["probe"]["alpha_CZ"].decimals == 1
    assert [(r.id, r.stylus, r.centres.shape) for r in thesis.probe.runs] == \
        [("c_axis", "short", (2, 4, 3)), ("b_axis", "short", (2, 2, 3)), ("b_axis", "long", (2, 2, 3))]
    assert set(thesis.probe.styli) == {"short", "long"}


def test_round_trip(thesis, tmp_path):
    path = tmp_path / "c.toml"
    save_campaign(thesis, path)
    again = load_campaign(path)
    assert dumps(campaign_to_dict(again)) == dumps(campaign_to_dict(thesis))
    for a, b in zip(thesis.ballbar.runs, again.ballbar.runs):
        for comp in a.repeats:
            np.testing.assert_allclose(a.repeats[comp], b.repeats[comp], rtol=1e-12)
    for a, b in zip(thesis.probe.runs, again.probe.runs, strict=True):
        np.testing.assert_array_equal(a.centres, b.centres)
    assert {k: v.value for k, v in again.reported["ballbar"].items()} == pytest.approx(
        {k: v.value for k, v in thesis.reported["ballbar"].items()})
    # printed decimals survive: 1.10 stays 1.10
    assert "alpha_CZ_arcsec = 1.10" in path.read_text()


def test_round_trip_priors_and_truth(tmp_path):
    text = (DATA / "minimal_one_repeat.toml").read_text() + """
[priors]
beta_XB = {dist = "normal", sd_arcsec = 30}
xW = {dist = "normal", mean_um = 5, sd_um = 35}
sigma_model = {dist = "halfnormal", sd_um = 2}

[truth.deviations]
beta_XB_arcsec = -24.0
dx_CZ_um = 53.0

[truth.setups.RB1]
xT_um = 0.5
dRB_um = -3

[truth.mounts.C]
yW_um = 40
"""
    c = parse_campaign(text, "t.toml")
    assert c.priors["beta_XB"]["sd"] == pytest.approx(30 * np.pi / 648000)
    assert c.priors["xW"]["mean"] == pytest.approx(0.005)
    assert c.truth.setups["RB1"]["dRB"] == pytest.approx(-0.003)
    save_campaign(c, tmp_path / "t.toml")
    c2 = load_campaign(tmp_path / "t.toml")
    assert dumps(campaign_to_dict(c2)) == dumps(campaign_to_dict(c))
    assert c2.truth.deviations == pytest.approx(c.truth.deviations)


def test_one_repeat_per_component_works(run_cli):
    c = load_campaign(DATA / "minimal_one_repeat.toml")
    assert all(len(v) == 1 for r in c.ballbar.runs for v in r.repeats.values())
    code, out, err = run_cli("identify", DATA / "minimal_one_repeat.toml", "--json")
    assert code == 0, err
    assert "beta_XB" in out


@pytest.mark.parametrize("name,key,fragment", EXPECTED, ids=[e[0] for e in EXPECTED])
def test_bad_campaign_one_line_exit_2(run_cli, name, key, fragment):
    code, out, err = run_cli("identify", BAD / name)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert str(BAD / name) in lines[0]
    if key != "-":
        assert f": {key}: " in lines[0]
    assert fragment in lines[0]
    assert "Traceback" not in err


def test_missing_file(run_cli, tmp_path):
    code, out, err = run_cli("identify", tmp_path / "nope.toml")
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [f"mtmcal-bayes identify: error: {tmp_path / 'nope.toml'}: file not found"]


def test_loader_raises_input_error_with_key():
    with pytest.raises(InputError) as info:
        load_campaign(BAD / "nan_value.toml")
    assert info.value.key == "ballbar.runs[2].ex_um[0]"


def test_bad_prior_and_truth_keys():
    base = (DATA / "minimal_one_repeat.toml").read_text()
    with pytest.raises(InputError, match=r"priors\.beta_XB\.sd_um"):
        parse_campaign(base + '\n[priors]\nbeta_XB = {dist = "normal", sd_um = 3}\n', "p.toml")
    with pytest.raises(InputError, match=r"priors\.beta_XB\.dist: unknown distribution"):
        parse_campaign(base + '\n[priors]\nbeta_XB = {dist = "cauchy", sd_arcsec = 3}\n', "p.toml")
    with pytest.raises(InputError, match=r"truth\.setups\.RB7"):
        parse_campaign(base + '\n[truth.setups.RB7]\nxT_um = 1\n', "t.toml")
    with pytest.raises(InputError, match=r"truth\.deviations\.beta_XB_um"):
        parse_campaign(base + '\n[truth.deviations]\nbeta_XB_um = 1\n', "t.toml")


def test_cli_subprocess_no_traceback():
    """The installed entry point prints one line and exits 2 (checked through a real process)."""
    proc = subprocess.run([sys.executable, "-m", "mtmcal_bayes.cli", "identify", str(BAD / "malformed.toml")],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "malformed TOML" in proc.stderr and "Traceback" not in proc.stderr
