"""Kinematic (HTM) models against the thesis relations, the literal chain, and the simulator round trip."""

import copy
import json

import numpy as np
import pytest

from mtmcal_bayes import LinearModel, load_campaign, units
from mtmcal_bayes.campaign import Run
from mtmcal_bayes.models import jacobian, make_model
from mtmcal_bayes.plugins.thesis.kinematic import HTMModel
from mtmcal_bayes.plugins.thesis.linear import LEFT_OUT
from mtmcal_bayes.patterns import B_PATTERNS, C_PATTERNS, COMPONENTS, fit_eccentricity
from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands

from .conftest import DATA

ARCSEC = units.ARCSEC


def all_patterns(campaign, setup="RB1"):
    c = copy.deepcopy(campaign)
    c.ballbar.runs = [Run(p, setup, "B" if p in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[p]})
                      for p in B_PATTERNS + C_PATTERNS]
    return c


def scaled(J, space):
    """Jacobian in µm per display unit (″ or µm)."""
    return J * space.display_scale() * 1e3


def test_htm_thesis_jacobian_equals_linear(thesis):
    """Acceptance: FD Jacobian of htm-thesis at zero = linear coefficients within 1e-3 relative,
    for every deviation of the thesis relations and every nuisance term, on BX, BY, CR, CA and CR'."""
    lin = LinearModel(thesis)
    htm = HTMModel(thesis, "htm-thesis")
    J = scaled(jacobian(htm), htm.space)
    L = scaled(lin.design, lin.space)
    assert [k.label for k in lin.observations.keys][-2:] == ["ex_CR@RB2/C", "ey_CR@RB2/C"]
    for j, p in enumerate(lin.space.parameters):
        if p.name in LEFT_OUT:
            continue
        for i, label in enumerate(lin.observations.labels):
            assert abs(J[i, j] - L[i, j]) <= 1e-3 * max(abs(L[i, j]), 1.0), (label, p.name, J[i, j], L[i, j])


def test_linear_axis_squareness_is_outside_the_thesis_relations(thesis):
    """The thesis drops gamma_XY, alpha_YZ, beta_YZ (Sec 2.5.3); the kinematic model keeps them."""
    lin = LinearModel(thesis)
    J = scaled(jacobian(HTMModel(thesis, "htm-thesis")), lin.space)
    for name in LEFT_OUT:
        j = lin.space.index(name)
        assert not lin.design[:, j].any()
        assert np.abs(J[:, j]).max() > 0.2, name  # e.g. beta_YZ: −R_B per rad on ez_BX


def literal_relations(d, s, m):
    """First-order response of Eq 2.10 as printed (SPEC §3.2), ``d`` by base name, mm and rad."""
    return {
        "ex_BX": d["dz_BT"] + d["zT"] - d["dRB"],
        "ez_BX": d["dx_BT"] + d["xT"] - s.R_B * d["beta_XB"],
        "ex_BY": -s.R_B * d["gamma_XB"],
        "ez_BY": s.R_B * d["alpha_XB"],
        "ex_CR": d["dx_BT"] + d["xT"] - s.R_B * d["beta_XB"] - d["dx_CZ"] - m.Z_C * d["beta_CZ"],
        "ey_CR": d["yT"] - d["dy_CZ"] + s.R_B * (d["alpha_XB"] + d["alpha_BT"]) + m.Z_C * d["alpha_CZ"],
        "ex_CA": m.R_C * d["beta_CZ"],
        "ey_CA": -m.R_C * d["alpha_CZ"],
    }


def test_htm_literal_first_order_is_the_literal_relations(thesis):
    htm = HTMModel(thesis, "htm-literal")
    J = jacobian(htm)
    bb = thesis.ballbar
    for j, p in enumerate(htm.space.parameters):
        if p.name in LEFT_OUT or p.group == "mount":
            continue
        for i, key in enumerate(htm.observations.keys):
            d = {q.base: 0.0 for q in htm.space.parameters}
            if p.owner in (None, key.setup):
                d[p.base] = 1.0
            want = literal_relations(d, bb.setups[key.setup], bb.mounts[key.mount])[f"{key.component}_{key.pattern}"]
            assert J[i, j] == pytest.approx(want, abs=1e-6 * max(1.0, abs(want))), (key.label, p.name)
    # no gamma_XB in CR, lever R_B instead of Z_T for alpha_XB
    i = htm.observations.labels.index("ey_CR@RB1/C")
    assert abs(J[i, htm.space.index("gamma_XB")]) < 1e-6


def test_w_ball_offsets(thesis):
    """W offsets: no first-order effect on BX, BY, BZ, CR, CT, CA; they move BR, BT, CX, CY.
    BA and CZ are the same motions as BY and CA (thesis Sec 2.3.2) and so are unaffected too."""
    c = all_patterns(thesis)
    htm = HTMModel(c, "htm-thesis")
    J = scaled(jacobian(htm), htm.space)
    w_cols = [j for j, p in enumerate(htm.space.parameters) if p.group == "mount"]
    for pattern in B_PATTERNS + C_PATTERNS:
        rows = [i for i, k in enumerate(htm.observations.keys) if k.pattern == pattern]
        effect = np.abs(J[np.ix_(rows, w_cols)]).max()
        if pattern in ("BR", "BT", "CX", "CY"):
            assert effect > 0.5, pattern
        else:
            assert effect < 1e-6, (pattern, effect)


def thesis_truth(space):
    values = {"alpha_CZ": 1.10, "beta_CZ": -25.16, "alpha_XB": -20.89, "beta_XB": -24.11, "gamma_XB": 5.63,
              "alpha_BT": 9.63}
    theta = space.vector({k: v * ARCSEC for k, v in values.items()})
    theta[space.index("dx_CZ")] = 0.05313
    theta[space.index("dy_CZ")] = -0.04563
    return theta


def test_nonlinear_minus_linear_at_thesis_magnitudes(thesis):
    """Table 4.5 values, W offsets of 60 µm in random directions: |htm-thesis − linear| < 0.1 µm."""
    lin, htm = LinearModel(thesis), HTMModel(thesis, "htm-thesis")
    rng = np.random.default_rng(7)
    theta = np.tile(thesis_truth(lin.space), (50, 1))
    for mount in ("B", "C"):
        v = rng.normal(size=(50, 3))
        v *= 0.060 / np.linalg.norm(v, axis=1, keepdims=True)
        for k, b in enumerate("xyz"):
            theta[:, lin.space.index(f"{b}W[{mount}]")] = v[:, k]
    diff = np.abs(htm.predict(theta) - lin.predict(theta)) * 1e3
    assert diff.max() < 0.1, diff.max()


@pytest.mark.parametrize("model", ["htm-literal", "htm-thesis"])
def test_zero_deviations_zero_eccentricities(thesis, model):
    c = all_patterns(thesis)
    htm = make_model(model, c)
    assert np.abs(htm.predict(np.zeros(len(htm.space)))).max() < 1e-12
    for psi, dL in htm.traces(np.zeros((1, len(htm.space)))):
        assert np.abs(dL).max() < 1e-12


def test_cr_geometries_agree_to_first_order(thesis):
    other = copy.deepcopy(thesis)
    other.ballbar.cr_geometry = "RC+LB"
    J1 = jacobian(HTMModel(thesis, "htm-thesis"))
    J2 = jacobian(HTMModel(other, "htm-thesis"))
    np.testing.assert_allclose(J1, J2, atol=1e-9)


def test_batch_equals_per_draw_loop(thesis):
    htm = HTMModel(thesis, "htm-literal")
    rng = np.random.default_rng(2)
    theta = rng.normal(size=(5, len(htm.space))) * htm.space.display_scale() * 30
    batch = htm.predict(theta)
    for i in range(5):
        np.testing.assert_allclose(batch[i], htm.predict(theta[i]), rtol=0, atol=1e-13)  # mm: round-off only


def test_extractor_recovers_eccentricity_and_reports_residual():
    psi = np.deg2rad(np.linspace(0, 90, 50))
    dL = 0.002 + 0.010 * np.sin(psi) - 0.004 * np.cos(psi)
    fit = fit_eccentricity("BX", psi, dL)
    assert fit.component("ex") == pytest.approx(0.010) and fit.component("ez") == pytest.approx(-0.004)
    assert fit.rms < 1e-15
    bumpy = fit_eccentricity("BX", psi, dL + 0.001 * np.sin(8 * psi))
    assert bumpy.rms > 1e-4


def test_cr_polar_angle_table_2_3():
    cmd = pattern_commands("CR", R_B=356.0, Z_C=65.0, R_C=50.0, L_B=100.0)
    np.testing.assert_allclose(cmd.psi - np.deg2rad(np.arange(0, 360, 5.0)), np.pi)  # R_C − L_B < 0
    cmd = pattern_commands("CR", R_B=356.0, Z_C=65.0, R_C=50.0, L_B=100.0, cr_geometry="RC+LB")
    np.testing.assert_allclose(cmd.psi, np.deg2rad(np.arange(0, 360, 5.0)))


def write_trace(path, pattern, psi_offset, ea, eb, r0=0.003):
    angles = np.arange(0.0, 360.0, 2.0) if pattern in C_PATTERNS else np.linspace(0, 90, 46)
    psi = np.deg2rad(angles) + psi_offset
    ua, ub = (np.sin(psi), np.cos(psi)) if pattern in B_PATTERNS else (np.cos(psi), np.sin(psi))
    lines = ["angle_deg,dL_um,direction"]
    for d, bias in (("CW", 0.3), ("CCW", -0.3)):  # CW/CCW differ by ±0.3 µm in ea
        dl = (r0 + (ea + bias * 1e-3) * ua + eb * ub) * 1e3
        lines += [f"{a:.3f},{v:.6f},{d}" for a, v in zip(angles, dl)]
    path.write_text("\n".join(lines) + "\n")


def test_trace_csv_runs(tmp_path):
    text = (DATA / "minimal_one_repeat.toml").read_text()
    text = text.replace('ex_um = [-47.9]\ney_um = [25.4]', 'trace_csv = ["cr1.csv", "cr2.csv"]')
    write_trace(tmp_path / "cr1.csv", "CR", np.pi, -0.0479, 0.0254)
    write_trace(tmp_path / "cr2.csv", "CR", np.pi, -0.0481, 0.0260)
    (tmp_path / "c.toml").write_text(text)
    c = load_campaign(tmp_path / "c.toml")
    run = c.ballbar.runs[2]
    np.testing.assert_allclose(run.repeats["ex"], [-0.0479, -0.0481], atol=1e-9)
    np.testing.assert_allclose(run.repeats["ey"], [0.0254, 0.0260], atol=1e-9)
    assert set(run.trace_rms[0]) == {"CW", "CCW"}


@pytest.mark.parametrize("content,fragment", [
    ("", "empty file"),
    ("a,b,c\n", "header"),
    ("angle_deg,dL_um,direction\n0,1,UP\n", "CW or CCW"),
    ("angle_deg,dL_um,direction\n0,nan,CW\n", "NaN"),
    ("angle_deg,dL_um,direction\n0,x,CW\n", "not a number"),
    ("angle_deg,dL_um,direction\n0,1,CW\n10,1,CW\n", "too short"),
])
def test_bad_trace_csv(tmp_path, run_cli, content, fragment):
    text = (DATA / "minimal_one_repeat.toml").read_text().replace('ex_um = [-47.9]\ney_um = [25.4]', 'trace_csv = "t.csv"')
    (tmp_path / "t.csv").write_text(content)
    (tmp_path / "c.toml").write_text(text)
    code, out, err = run_cli("identify", tmp_path / "c.toml")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert fragment in err and "t.csv" in err


TRUTH = """
[deviations]
alpha_CZ_arcsec = 1.10
beta_CZ_arcsec = -25.16
alpha_XB_arcsec = -20.89
beta_XB_arcsec = -24.11
gamma_XB_arcsec = 5.63
alpha_BT_arcsec = 9.63
dx_CZ_um = 53.13
dy_CZ_um = -45.63
"""


def test_simulate_then_identify_returns_the_truth(tmp_path, run_cli):
    """Acceptance: Table 4.5 as truth (dx_BT = 0) under htm-thesis, noise-free; identify within 0.2″ / 0.15 µm."""
    (tmp_path / "truth.toml").write_text(TRUTH)
    code, _, err = run_cli("simulate", "--truth", tmp_path / "truth.toml", "--model", "htm-thesis",
                           "-o", tmp_path / "syn.toml")
    assert code == 0, err
    code, out, err = run_cli("identify", tmp_path / "syn.toml", "--json")
    assert code == 0, err
    got = json.loads(out)["ballbar_in_convention"]  # written as the built-in campaign reads BX and BY
    want = {"alpha_CZ": 1.10, "beta_CZ": -25.16, "alpha_XB": -20.89, "beta_XB": -24.11, "gamma_XB": 5.63,
            "alpha_BT": 9.63, "dx_CZ_minus_dx_BT": 53.13, "dy_CZ": -45.63}
    for name, v in want.items():
        tol = 0.15 if got[name]["unit"] == "um" else 0.2
        assert abs(got[name]["value"] - v) <= tol, (name, got[name]["value"], v)


def test_simulate_json_and_noise(tmp_path, run_cli):
    (tmp_path / "truth.toml").write_text(TRUTH + "\n[setups.RB1]\nxT_um = 0.5\n[mounts.C]\nyW_um = 40\n")
    code, out, err = run_cli("simulate", "--truth", tmp_path / "truth.toml", "--json")
    assert code == 0, err
    recs = json.loads(out)["eccentricities"]
    assert len(recs) == 10 and set(recs[0]) == {"pattern", "setup", "mount", "component", "value_um"}
    cr2 = [r for r in recs if r["pattern"] == "CR" and r["setup"] == "RB2" and r["component"] == "ey"][0]
    assert cr2["value_um"] == pytest.approx(28.5, abs=0.1)  # Table 4.4 ey'_CR
    paths = []
    for i in range(2):
        p = tmp_path / f"n{i}.toml"
        assert run_cli("simulate", "--truth", tmp_path / "truth.toml", "-o", p, "--noise", "--seed", "5")[0] == 0
        paths.append(p)
    assert paths[0].read_text() == paths[1].read_text()  # seeded
    c = load_campaign(paths[0])
    assert c.truth.deviations["beta_XB"] == pytest.approx(-24.11 * ARCSEC)
    assert c.truth.mounts["C"]["yW"] == pytest.approx(0.040)
    assert all(len(v) == 3 for r in c.ballbar.runs for v in r.repeats.values())
    assert c.probe.runs[0].centres.shape == (2, 4, 3) and not c.reported  # probe readings simulated too, 2 repeats


def test_simulate_bad_truth(tmp_path, run_cli):
    (tmp_path / "t.toml").write_text("[deviations]\nbeta_XB_um = 3\n")
    code, out, err = run_cli("simulate", "--truth", tmp_path / "t.toml")
    assert code == 2 and "deviations.beta_XB_um" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "t.toml").write_text("[setups.RB9]\nxT_um = 3\n")
    code, out, err = run_cli("simulate", "--truth", tmp_path / "t.toml")
    assert code == 2 and "setups.RB9" in err


def test_linear_rows_for_other_patterns_come_from_htm_thesis(thesis):
    c = all_patterns(thesis)
    lin, htm = LinearModel(c), HTMModel(c, "htm-thesis")
    J = jacobian(htm)
    keep = [j for j, p in enumerate(lin.space.parameters) if p.name not in LEFT_OUT]
    np.testing.assert_allclose(lin.design[:, keep], J[:, keep], atol=1e-6)


def test_sensitivity_docs_in_sync(run_cli):
    from pathlib import Path

    code, out, _ = run_cli("sensitivity", "--markdown")
    assert code == 0
    doc = (Path(__file__).parents[1] / "docs" / "sensitivity.md").read_text()
    assert out.strip() in doc, "docs/sensitivity.md is stale: regenerate with `mtmcal-bayes sensitivity --markdown`"
