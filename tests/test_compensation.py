"""Compensation: G-code round trip, ncgen of Fig 4.30(a), exact inversion, the thesis' double correction."""

import json

import numpy as np
import pytest

from mtmcal_bayes.compensation.inverse import invert
from mtmcal_bayes.plugins.thesis.compensation.kinematics import ModelFrameKinematics, tool_point
from mtmcal_bayes.plugins.thesis.compensation.printed_method import compensate_thesis
from mtmcal_bayes.plugins.thesis.compensation.values import ballbar_values
from mtmcal_bayes.plugins.thesis.compensation.verify import resimulate
from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.io.gcode import parse_program, read_program, rewrite
from mtmcal_bayes.plugins.thesis.htm import Geometry
from mtmcal_bayes.parameters import DEVIATIONS

FIG = data_path("fig4_30a_bx_original.nc")


def test_ncgen_reproduces_fig_4_30a(run_cli):
    code, out, err = run_cli("ncgen", "BX", "--R-B-mm", "356.3945", "--x0", "-390", "--z0", "-112.2605",
                             "--step-deg", "0.2777777778", "--feed", "2000", "-n", "10")
    assert code == 0, err
    expected = [line for line in FIG.read_text().splitlines() if line.startswith("G01")]
    assert out.splitlines() == expected


def test_gcode_round_trip_and_modal_axes():
    text = FIG.read_text()
    prog = parse_program(text, "fig")
    assert rewrite(prog, prog.positions()[:, :3]) == text  # byte for byte
    modal = "%\nO1000 (test)\nG90 G01 X1.000 Y2.000 Z3.000 B0 C0 F500\nX1.500 ; modal\nM05\n%\n"
    prog = parse_program(modal, "modal")
    pos = prog.positions()
    assert pos.shape == (2, 5) and pos[1, 1] == 2.0  # Y carried over
    new = pos[:, :3] + np.array([0.0, 0.001, 0.0])
    out = rewrite(prog, new).splitlines()
    assert out[0] == "%" and out[1] == "O1000 (test)" and out[4] == "M05"
    assert out[2] == "G90 G01 X1.000 Y2.001 Z3.000 B0 C0 F500"
    assert out[3] == "X1.500 Y2.001 ; modal"  # the modal Y now moves: its word is added


@pytest.mark.parametrize("text, where, what", [
    ("G01 X1. Y2. Z3. B0 C0\nG01 X- Y2. Z3.\n", "line 2", "has no number"),
    ("G01 X1. Y2. Z3. B0\n", "line 1", "axis C not known"),  # every axis of the machine, rotary too
    ("G91 G01 X1. Y2. Z3.\n", "line 1", "G91"),
    ("G01 X1. Y2. B0 C0\n", "line 1", "axis Z not known"),
    ("G02 X1. Y2. Z3. I1 J0\n", "line 1", "circular"),
])
def test_malformed_programs_name_the_line(run_cli, tmp_path, text, where, what):
    f = tmp_path / "bad.nc"
    f.write_text(text)
    code, out, err = run_cli("compensate", f, "-o", tmp_path / "out.nc")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "bad.nc" in err and where in err and what in err
    assert not (tmp_path / "out.nc").exists()


def test_compensating_fig_4_30a_keeps_b_c_and_other_blocks(run_cli, tmp_path):
    out = tmp_path / "comp.nc"
    code, stdout, err = run_cli("compensate", FIG, "-o", out, "--json")
    assert code == 0, err
    before, after = FIG.read_text().splitlines(), out.read_text().splitlines()
    assert len(before) == len(after)
    for a, b in zip(before, after):
        if not a.startswith("G01"):
            assert a == b
        else:
            keep = lambda s: [w for w in s.split() if w[0] in "GBCF"]  # noqa: E731
            assert keep(a) == keep(b) and a != b
    data = json.loads(stdout)
    names = [r["name"] for r in data["not_compensable"]]
    assert "alpha_BT" in names  # the tool tilt X/Y/Z cannot correct, reported by name
    assert data["residual_um"]["p95_max"] > data["residual_um"]["mean_max"] > 0


def test_compensate_names_the_deviations_resting_on_the_choice_of_reading(thesis):
    """The built-in campaign's B runs were read by choice.  The deviations compensate marks are those it uses whose
    estimate moves by more than its sd between its posterior (the closed form, σ_model 2 µm) and the same posterior
    of the campaign read in its recorded alternative (exact draws of both, built from the file's text); the
    compensated program is the one of the campaign without the record."""
    import mtmcal_bayes as mb
    from . import variants

    res = mb.compensate(FIG, campaign=thesis)
    chosen, alt = (mb.sample(mb.parse_campaign(t), sampler="exact", seed=1, sigma_model_um=2).summary
                   for t in (variants.without_reading_choice(), variants.alternative_reading()))
    used = [n for n in res.info["deviations"] if n in chosen.index]
    moved = {n for n in used if abs(alt.loc[n, "mean"] - chosen.loc[n, "mean"]) > chosen.loc[n, "sd"]}
    choice = res.reading_choice
    assert set(choice["rests_on_choice"]) == moved and {"alpha_XB", "alpha_BT"} <= moved
    text = res.to_text()
    summary = next(ln for ln in text.splitlines() if "rests on the campaign's choice of reading (†): " in ln)
    for n in moved:
        d = choice["deviations"][n]
        assert d["alternative"] == pytest.approx(alt.loc[n, "mean"], abs=0.05 * chosen.loc[n, "sd"])
        assert f"{n} {d['value']:.2f}" in summary and f"† {d['alternative']:.2f}" in summary
    tilted = {r["name"] for r in res.not_compensable}
    for ln in text.splitlines():
        name = ln.split()[0] if ln.startswith("    ") else None
        if name in tilted:
            assert ln.split()[1].startswith("†") == (name in moved), ln
    assert "B0=+X,B90=-Z" in text and json.dumps(res.to_json())
    plain = mb.compensate(FIG, campaign=mb.parse_campaign(variants.without_reading_choice()))
    assert plain.text == res.text and plain.reading_choice is None and "†" not in plain.to_text()


def test_exact_compensation_removes_the_eccentricities(thesis):
    """Thesis deviations, htm-thesis: BY, CR and CA re-simulated after compensation are below 0.5 µm."""
    table = resimulate(thesis, ballbar_values(thesis), model="htm-thesis", method="exact", point="tcp")
    for label, row in table.iterrows():
        if label.split("_")[1].split("@")[0] in ("BY", "CR", "CA"):
            assert abs(row["after_um"]) < 0.5, (label, row["after_um"])
    assert abs(table.loc["ey_CR@RB1/C", "before_um"]) > 20  # there was something to remove
    # compensating the spindle nose instead (the thesis' reference) leaves the tool tilts times Z_T at the ball
    nose = resimulate(thesis, ballbar_values(thesis), model="htm-thesis", method="exact", point="nose")
    assert abs(nose.loc["ey_CR@RB1/C", "after_um"]) > 5


def test_newton_reaches_the_programmed_point(thesis):
    """The engine's Newton through the thesis' models in their model frame (the program's NC frame shifted by its
    origin, written out here): the compensated commands put the tool point of ``tool_point``, the models' own
    function with B and C in degrees, on the nominal one."""
    geo = Geometry(356.3945, 112.2877, 490.0, 65.5348, 50.0)
    origin = np.array([490.0, 0.0, 65.5348 + 356.3945 + 112.2877])
    pos = read_program(FIG).positions()
    xyz = pos[:, :3] + origin
    theta = ballbar_values(thesis)
    q = {"X": pos[:, 0], "Y": pos[:, 1], "Z": pos[:, 2], "B": np.radians(pos[:, 3]), "C": np.radians(pos[:, 4])}
    for model in ("htm-thesis", "htm-literal"):
        x_c, miss = invert(ModelFrameKinematics(geo, model, point="tcp", origin=origin), q, dict(zip(DEVIATIONS, theta)))
        assert miss < 1e-9  # mm
        actual = tool_point(theta[None], geo, x_c + origin, pos[:, 3:], model=model)[0]
        nominal = tool_point(np.zeros((1, 13)), geo, xyz, pos[:, 3:], model=model)[0]
        assert np.abs(actual - nominal).max() < 1e-9
        assert np.abs(actual - tool_point(theta[None], geo, xyz, pos[:, 3:], model=model)[0]).max() > 1e-3


def test_thesis_method_corrects_twice(thesis):
    """Eqs 3.4–3.13 as printed: the error after is the error before with its sign turned."""
    d = dict(zip(DEVIATIONS, ballbar_values(thesis)))
    pos = read_program(FIG).positions()
    _, before, after = compensate_thesis(d, pos[:, :3], pos[:, 3:])
    assert np.abs(before).max() > 0.01  # mm
    np.testing.assert_allclose(after, -before, rtol=1e-9, atol=1e-12)
    _, _, fixed = compensate_thesis(d, pos[:, :3], pos[:, 3:], corrected=True)
    assert np.abs(fixed).max() < 1e-9
    # in the kinematic model the CR errors flip too (radial and tangential within 5 %)
    table = resimulate(thesis, ballbar_values(thesis), model="htm-thesis", method="thesis")
    for label in ("ey_CR@RB1/C", "ex_CR@RB2/C", "ey_CR@RB2/C"):
        assert table.loc[label, "after_um"] == pytest.approx(-table.loc[label, "before_um"], rel=0.05)


def test_the_chain_of_the_thesis_machine_compensates_as_htm_literal(thesis):
    """``--model chain`` names the machine's chain on every machine; on the thesis machine that is Eq 2.10 as
    printed (``htm-literal``): the same program and residuals, and not ``htm-thesis``'s."""
    import mtmcal_bayes as mb

    chain, literal, pivots = (mb.compensate(FIG, campaign=thesis, model=m) for m in ("chain", "htm-literal",
                                                                                      "htm-thesis"))
    assert chain.text == literal.text
    np.testing.assert_array_equal(chain.error_before_um, literal.error_before_um)
    assert chain.text != pivots.text
