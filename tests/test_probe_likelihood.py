"""Touch-probe readings in the likelihood (SPEC §12): the forward model by hand, data selection, the
fused posterior, the consistency check, the DPRNT path, simulation and SBC with probe data."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.inference.analytic import gaussian_posterior
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.campaign_writer import campaign_to_dict
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.models import MODELS, make_model
from mtmcal_bayes.plugins.thesis.probe_runs import record, run_of
from mtmcal_bayes.posterior.consistency import instrument_consistency
from mtmcal_bayes.simulation.simulate import simulated_probe, synthetic_campaign
from mtmcal_bayes.validation import SBCSettings, run_sbc

ARCSEC = units.to_internal(1.0, "arcsec")
UM = units.to_internal(1.0, "um")


def _with_machine_datum():
    """The thesis campaign with the C-axis readings taken as machine coordinates (C axis at axis_xy)."""
    text = mb.datasets.builtin_text("integrex_i200.toml")
    assert text.count('datum = "first"') == 1
    return parse_campaign(text.replace('datum = "first"', 'datum = "machine"'), "<thesis, machine datum>")


@pytest.fixture(scope="module")
def machine_datum():
    return _with_machine_datum()


def _c_centres(campaign, truth: Truth, model: str) -> np.ndarray:
    """Noise-free C-axis sphere centres (a, 3) of ``truth``, mm."""
    return run_of(simulated_probe(campaign, truth, model), "c_axis").centres[0]


@pytest.mark.parametrize("model", MODELS)
def test_dx_CZ_moves_every_c_axis_centre_by_itself(machine_datum, model):
    """dx_CZ = 50 µm shifts the C axis, and with it the sphere at every C angle, by 50 µm along X.

    Hand calculation: the actual C axis is ``A(v) = R(v − h e_z) + h e_z + d`` with d = (dx_CZ, dy_CZ, 0)
    (htm.CAxis); with no tilt R = I, so every sphere centre moves by d.  The stylus is ideal, so the
    commanded point that puts the stylus-ball centre on the sphere moves by d too: ΔX = +50 µm, ΔY = ΔZ = 0
    at C = 0, 90, 180, 270°, in all three models (the linear one is the chain's first order, exact here).
    """
    base = _c_centres(machine_datum, Truth(), model)
    moved = _c_centres(machine_datum, Truth(deviations={"dx_CZ": 50 * UM}), model)
    expected = np.tile([50 * UM, 0.0, 0.0], (len(base), 1))
    np.testing.assert_allclose(moved - base, expected, atol=1e-9)


@pytest.mark.parametrize("model, pivot_height", [("linear", 2.0), ("htm-thesis", 2.0), ("htm-literal", 0.0)])
def test_beta_CZ_tilts_the_c_axis_centres_as_by_hand(machine_datum, model, pivot_height):
    """beta_CZ = 30″ tilts the C axis about Y; the sphere centres move as the hand calculation says.

    Hand calculation: the sphere sits at v = (R_C cos C, R_C sin C, Z_C) in the C frame; the tilt turns it
    about the pivot height h (2·Z_C in htm-thesis and linear, 0 in htm-literal):
    R_y(β)(v − h e_z) + h e_z ≈ v + β((Z_C − h), 0, −R_C cos C).  So
    ΔX = β (Z_C − h) at every angle (−β Z_C = −9.43 µm for htm-thesis, +9.43 µm for htm-literal),
    ΔY = 0 and ΔZ = −β R_C cos C (−14.54 µm at C = 0, +14.54 µm at 180°, 0 at 90° and 270°).
    Second-order terms (β² R_C ≈ 2e-6 mm) are below the 5e-6 mm tolerance.
    """
    c = record(machine_datum.probe).c_axis
    beta = 30 * ARCSEC
    base = _c_centres(machine_datum, Truth(), model)
    moved = _c_centres(machine_datum, Truth(deviations={"beta_CZ": beta}), model)
    C = np.radians(c.angles_deg)
    h = pivot_height * c.Z_C
    expected = np.column_stack([np.full(len(C), beta * (c.Z_C - h)), np.zeros(len(C)), -beta * c.R_C * np.cos(C)])
    np.testing.assert_allclose(moved - base, expected, atol=5e-6)


def test_b_axis_sensitivities_by_hand(thesis):
    """Stylus length error dRS and dz_BT move the B-axis readings along the stylus axis, in opposite senses.

    Hand calculation: the stylus ball's tool point is at R(B)·(0, 0, −(R_B − r + dRS − rS − dz_BT)) from the
    B centre (the htm chain's T-ball vector with the stylus terms); to put it on the fixed sphere the command
    moves by −R(B)·(0, 0, −δ): at B = 0 the reading's Z grows by δ, at B = 90° its X by δ.  So
    ∂(Z at B0, X at B90)/∂dRS = (+1, +1) and ∂/∂dz_BT = (−1, −1): the probe cannot tell dz_BT from the
    stylus length error (their columns are opposite), which is why the thesis' −1804 µm is not a dz_BT.
    """
    model = make_model("linear", thesis, data="probe")
    A, names = model.design, model.space.names
    keys = [k.label for k in model.observations.keys]
    col = lambda n: A[:, names.index(n)]  # noqa: E731
    for stylus in ("short", "long"):
        z0, x90 = keys.index(f"Z@B0/{stylus}"), keys.index(f"X@B90/{stylus}")
        d = col(f"dRS[{stylus}]")
        assert d[z0] == pytest.approx(1.0, abs=1e-6) and d[x90] == pytest.approx(1.0, abs=1e-6)
    rows = [i for i, k in enumerate(model.observations.keys) if k.run == "b_axis"]
    np.testing.assert_allclose(col("dz_BT")[rows], -(col("dRS[short]") + col("dRS[long]"))[rows], atol=1e-6)


def test_probe_data_selection(thesis):
    """--data chooses the likelihood: ball-bar only is today's posterior; probe and both add the probe terms."""
    bb, pr, both = (LogPosterior(thesis, "linear", data=d) for d in ("ballbar", "probe", "both"))
    assert bb.names == LogPosterior(thesis, "linear").names
    assert not any("[short]" in n for n in bb.names) and any("xS[short]" == n for n in pr.names)
    assert not any("xT[" in n for n in pr.names)
    assert len(both.likelihood.y) == len(bb.likelihood.y) + len(pr.likelihood.y)
    assert set(bb.names) | set(pr.names) == set(both.names)
    with pytest.raises(mb.MtmcalError, match="data: unknown data"):
        LogPosterior(thesis, "linear", data="ballbar+probe")


def _synthetic(thesis, seed: int):
    """The thesis design with ball-bar and probe data simulated (noisy) from a known truth (htm-thesis)."""
    c = _with_machine_datum()
    truth = Truth(deviations={"beta_CZ": -25 * ARCSEC, "alpha_CZ": 3 * ARCSEC, "alpha_XB": -20 * ARCSEC,
                              "gamma_XB": 5 * ARCSEC, "beta_XB": -30 * ARCSEC, "dx_CZ": 40 * UM, "dx_BT": 10 * UM,
                              "dy_CZ": -45 * UM, "dz_BT": -50 * UM, "alpha_BT": 10 * ARCSEC})
    return synthetic_campaign(c, truth, "htm-thesis", noise=True, seed=seed), truth


def test_fused_posterior_is_never_wider(thesis):
    """Fused sd ≤ ball-bar-only sd for every quantity, to Monte-Carlo error (3 MCSE of the sd), and clearly
    smaller (≤ 0.5×) for the C-axis tilts the probe's C-axis run measures, on consistent synthetic data."""
    c, _ = _synthetic(thesis, seed=3)
    bb = mb.sample(c, seed=5)
    both = mb.sample(c, seed=5, data="both")
    for q in bb.summary.index:
        tol = 3 * np.hypot(bb.summary.loc[q, "mcse_sd"], both.summary.loc[q, "mcse_sd"])
        assert both.summary.loc[q, "sd"] <= bb.summary.loc[q, "sd"] + tol, q
    for q in ("alpha_CZ", "beta_CZ"):
        assert both.summary.loc[q, "sd"] < 0.5 * bb.summary.loc[q, "sd"], q


def test_consistency_agrees_on_consistent_data_and_flags_a_broken_probe(thesis):
    """On data simulated from one truth the instruments agree; a 150 µm error in one B-axis reading (the size of the thesis data's axial conflict) is caught."""
    c, _ = _synthetic(thesis, seed=4)
    bb, pr = mb.sample(c, seed=2), mb.sample(c, seed=2, data="probe")
    ok = instrument_consistency(bb, pr)
    assert (ok.groups["verdict"] == "agree").all(), ok.to_text()
    bad = copy.deepcopy(c)
    run_of(bad.probe, "b_axis", "long").centres[:, 1, 0] += 150 * UM  # X at B = 90°, long stylus
    flagged = instrument_consistency(mb.sample(bad, seed=2), mb.sample(bad, seed=2, data="probe"))
    verdicts = dict(zip(flagged.groups["group"], flagged.groups["verdict"]))
    assert verdicts["probe B axis, stylus long"] == "disagree", flagged.to_text()


def test_sbc_with_probe_data_linear():
    """validate sbc --data both passes for the linear model: every quantity's ranks uniform (p > 0.001) and its 95 %
    and 50 % HDI coverages inside the 99.9 % binomial bands of N = 400 replicates.

    The exact sampler: what SBC checks here is that the posterior of both instruments (likelihood, priors, the two
    scales) is calibrated against their simulator; that emcee draws that posterior is
    test_emcee_draws_the_exact_posterior_with_both_instruments.  N = 400 makes both sides of each band fail: the
    95 % band is [0.910, 0.9825] (at N = 100 its top was 1.00, so over-coverage could not fail), the 50 % band
    [0.4175, 0.5825].  Power per quantity (binomial), intervals scaled by f: f = 0.8 (95 % coverage 88 %) 0.95,
    f = 1.3 (98.9 %, 50 % coverage 62 %) 0.85 and 0.93, f = 5 (five times too wide) 1.0."""
    c = mb.load_campaign()
    r = run_sbc(c, SBCSettings(n=400, data="both", sampler="exact", workers=1, seed=7))  # one: pytest -n 2 beside
    s = r.summary()
    assert (s["p_uniform"] > 0.001).all(), s["p_uniform"]
    for prob in (0.95, 0.5):
        lo, hi = r.coverage_band(prob, level=0.999)
        assert hi < 1.0
        assert s[f"coverage_{round(100 * prob)}"].between(lo, hi).all(), s[f"coverage_{round(100 * prob)}"]


def test_emcee_draws_the_exact_posterior_with_both_instruments(thesis):
    """emcee (default settings) on the posterior of both instruments, σ_model and σ_model_probe free: each of the
    eight quantities' mean and sd within 4 Monte-Carlo standard errors (ArviZ's, of this run) of the exact
    σ-marginal posterior's; the run reaches its ESS target, so that is at most 4/√1000 = 0.13 posterior sd for a
    mean.  (The sibling on the ball bar alone: test_inference.py::test_sampler_matches_the_exact_sigma_marginal_
    posterior.)"""
    from mtmcal_bayes import IDENTIFIABLE
    from mtmcal_bayes.inference import SamplerSettings, run_ensembles, summarize, to_inference_data

    post = LogPosterior(thesis, "linear", data="both")
    r = run_ensembles(post, SamplerSettings(seed=6))
    assert r.converged and r.approximation.exact
    exact = r.approximation.moments(list(IDENTIFIABLE))
    s = summarize(to_inference_data(r, seed=0), post)
    for n in IDENTIFIABLE:
        m, sd = exact[n]
        assert s.loc[n, "ess_bulk"] >= r.settings.target_ess, n
        assert abs(s.loc[n, "mean"] - m) < 4 * s.loc[n, "mcse_mean"], (n, (s.loc[n, "mean"] - m) / sd)
        assert abs(s.loc[n, "sd"] - sd) < 4 * s.loc[n, "mcse_sd"], (n, s.loc[n, "sd"] / sd - 1)


def _rotated_dprnt(points: np.ndarray, angle_deg: float, axis_xy) -> str:
    a = np.radians(angle_deg)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    xy = (points[:, :2] - axis_xy) @ R.T + axis_xy
    return "\n".join(f"X{x:.4f} Y{y:.4f} Z{z:.4f}" for (x, y), z in zip(xy, points[:, 2])) + "\n"


def test_dprnt_c_axis_run_from_fig_5_13(tmp_path):
    """A C-axis run from DPRNT files: thesis Fig 5.13 as the C = 0° position, the same points turned about the
    C axis for 90°, 180°, 270°.  Each sphere is fitted, its centre covariance enters the likelihood (in its
    principal axes: variances = eigenvalues + repeatability²), and the probe posterior follows."""
    from mtmcal_bayes.datasets import data_path
    from mtmcal_bayes.io.dprnt import read_dprnt
    from mtmcal_bayes.sphere import fit_sphere

    src = data_path("fig5_13_dprnt_output.txt")
    pts = read_dprnt(src).xyz
    (tmp_path / "c0.txt").write_text(src.read_text())
    for a in (90, 180, 270):
        (tmp_path / f"c{a}.txt").write_text(_rotated_dprnt(pts, a, np.array([-490.0, 0.0])))
    thesis_text = mb.datasets.builtin_text("integrex_i200.toml")
    start, end = thesis_text.index("[probe.c_axis]"), thesis_text.index("[probe.b_axis]")
    c_run = ('[probe.c_axis]\nR_C_mm = 100.0\nZ_C_mm = 64.838\naxis_xy_mm = [-490.0, 0.0]\nstylus = "short"\n'
             'angles_deg = [0.0, 90.0, 180.0, 270.0]\ndprnt = ["c0.txt", "c90.txt", "c180.txt", "c270.txt"]\n\n')
    c = parse_campaign(thesis_text[:start] + c_run + thesis_text[end:], str(tmp_path / "c.toml"), tmp_path)
    fit = fit_sphere(pts)
    np.testing.assert_allclose(run_of(c.probe, "c_axis").centres[0, 0], fit.centre)
    assert run_of(c.probe, "c_axis").centre_cov.shape == (1, 4, 3, 3)
    post = LogPosterior(c, "linear", data="probe")
    obs = post.forward.observations
    c0 = [i for i, k in enumerate(obs.keys) if k.run == "c_axis" and k.angle_deg == 0.0]
    assert [obs.keys[i].component for i in c0] == ["u1", "u2", "u3"]
    expected = np.linalg.eigvalsh(fit.centre_cov) + c.probe.repeatability**2
    np.testing.assert_allclose(np.sort(obs.base_var[c0]), np.sort(expected), rtol=1e-9)
    g = gaussian_posterior(post, 0.0)
    sd = units.from_internal(g.linear_combination({"beta_CZ": 1.0})[1], "arcsec")
    assert 0 < sd < 5  # four fitted centres 200 mm apart pin the tilt to arc seconds
    # saving keeps the DPRNT files, relative to the new folder
    text = dumps(campaign_to_dict(c, tmp_path / "out"))
    assert '"../c0.txt"' in text


def test_simulate_writes_probe_readings(thesis, tmp_path, run_cli):
    """simulate -o writes the probe readings of the truth (noise-free: one repeat equal to the model)."""
    truth = tmp_path / "truth.toml"
    truth.write_text("[deviations]\ndx_CZ_um = 50\n\n[probe.short]\nxS_um = 3\n")
    out = tmp_path / "sim.toml"
    code, _, err = run_cli("simulate", "--truth", str(truth), "-o", str(out), "--model", "linear")
    assert code == 0, err
    sim = mb.load_campaign(out)
    assert sim.truth.probe == {"short": {"xS": pytest.approx(3 * UM)}}
    assert run_of(sim.probe, "c_axis").centres.shape == (1, 4, 3)
    model = make_model("linear", sim, data="probe")
    theta = mb.simulation.simulate.truth_vector(model.space, sim.truth.probe_part())
    # the readings' datum is where the first reading of each run puts it, so the truth fits them exactly up to
    # one constant offset per run (its datum nuisance terms)
    resid = (model.observations.mean - model.predict(theta)).reshape(-1, 3)
    runs = np.array([k.run for k in model.observations.keys[::3]])
    for run in ("c_axis", "b_axis"):
        np.testing.assert_allclose(resid[runs == run], resid[runs == run][[0]].repeat((runs == run).sum(), 0),
                                   atol=1e-9)
    assert np.abs(resid[runs == "c_axis"][0]).max() > 40 * UM  # dx_CZ (+ xS) moved the first reading


def test_cli_sample_data_both_json(run_cli):
    code, out, err = run_cli("sample", "--data", "both", "--seed", "1", "--json", "--quiet")
    assert code == 0, err
    import json

    doc = json.loads(out)
    assert doc["data"] == "both"
    code, out, err = run_cli("sample", "--data", "probes", "--quiet")
    assert code == 2 and "--data" in err and len(err.strip().splitlines()) == 1


def test_docs_sensitivity_table_is_the_models(machine_datum):
    """docs/probe.md's sensitivity table is the probe model's, not typed in: the same numbers to 3 decimals."""
    from pathlib import Path

    from mtmcal_bayes.simulation.probe_sensitivity import probe_sensitivity_table

    text = (Path(__file__).parents[1] / "docs" / "probe.md").read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if ln.startswith("| ")]
    head = lines.index(next(ln for ln in lines if ln.startswith("| parameter |")))
    columns = [c.strip() for c in lines[head].strip("|").split("|")][1:]
    table = probe_sensitivity_table(machine_datum).T
    assert columns == list(table.columns)
    rows = lines[head + 1:head + 1 + len(table)]
    for line in rows:
        cells = [c.strip() for c in line.strip("|").split("|")]
        got = np.array([float(c) if c else 0.0 for c in cells[1:]])
        np.testing.assert_allclose(got, table.loc[cells[0]].to_numpy(), atol=6e-4, err_msg=cells[0])
    assert [ln.split("|")[1].strip() for ln in rows] == list(table.index)


def test_identifiability_follows_from_the_design(thesis):
    """The probe alone identifies the C tilts, beta_XB and alpha_XB + gamma_XB, and cannot tell dz_BT from the
    stylus length error or dx_BT from the stylus offset (docs/probe.md)."""
    from mtmcal_bayes.simulation.probe_sensitivity import probe_identifiability

    ident = probe_identifiability(thesis)["identified by the probe alone"]
    assert ident[["alpha_CZ", "beta_CZ", "beta_XB", "alpha_XB + gamma_XB"]].all()
    assert not ident[["dx_BT", "dz_BT", "alpha_BT", "alpha_XB", "gamma_XB", "dx_CZ_minus_dx_BT"]].any()
