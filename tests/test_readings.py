"""Reading conventions of ball-bar offsets, the instruments' conflict and what it decides (SPEC §17).

Derivations by hand are in the docstrings; the numbers of the thesis campaign in docs/thesis-notes.md.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from mtmcal_bayes import conventions as cv
from mtmcal_bayes import units
from mtmcal_bayes.plugins.thesis.identification import identify
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.inference.marginal import MarginalPosterior
from mtmcal_bayes.io import load_campaign, parse_campaign
from mtmcal_bayes.io.campaign_writer import campaign_to_dict
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.observations import Observations, with_run_values
from mtmcal_bayes.patterns import B_PATTERNS, PATTERNS
from mtmcal_bayes.posterior.conflict import explain_conflict
from mtmcal_bayes.posterior.instrument_check import check_instruments
from mtmcal_bayes.posterior.misreading import misreading_power
from mtmcal_bayes.validation.criteria import P_MIN

from . import variants

GEO = {"R_B": 356.3945, "Z_C": 65.5348, "L_B": 100.0}
D4 = ("B0=+Z,B90=+X", "B0=+Z,B90=-X", "B0=-Z,B90=+X", "B0=-Z,B90=-X",
      "B0=+X,B90=+Z", "B0=-X,B90=+Z", "B0=+X,B90=-Z", "B0=-X,B90=-Z")


@pytest.fixture(scope="module")
def as_thesis_reads():
    return parse_campaign(variants.thesis_reading(), "thesis_reading.toml")


# --------------------------------------------------------------------------- the conventions
def _thesis_run(pattern: str, convention: str | None = None):
    """One run of thesis ``pattern`` at RB1 (R_B 356.3945 mm) on the thesis campaign's mount for it (B: R_C = 0; C:
    R_C = 50 mm; Z_C 65.5348 mm; L_B 100 mm), with that campaign's ball bar, and the run's frame (from the chain)."""
    from mtmcal_bayes.campaign import Run

    c = load_campaign(None)
    run = Run(pattern, "RB1", "B" if pattern in B_PATTERNS else "C", {}, convention=convention)
    c.ballbar.runs = [run]
    return run, c.ballbar, cv.run_frame(run, c.ballbar)


def _in_order(D: np.ndarray, frame, axes: tuple[str, str]) -> np.ndarray:
    """``D`` (2, 2) of ``frame``'s plane axes, its columns put in the order ``axes``."""
    k = [frame.axes.index(a) for a in axes]
    return D[:, k]


@pytest.mark.parametrize("pattern", PATTERNS)
def test_machine_reading_is_derived_from_the_programmed_motion(pattern):
    """The "machine" convention draws each sample where the programmed position is, seen from the programmed arc's
    centre (Tables 2.2/2.3).  By hand: for ten patterns that is the thesis' reading (B patterns: the B-axis centre
    at R·(sin φ, cos φ) from the T ball, so B = 0° at +Z and B = 90° at +X; C patterns: the position at R·(cos θ,
    sin θ), for CR at (R_C − L_B)·(cos θ, sin θ) with R_C − L_B < 0, i.e. θ + 180°).  BT programs
    R_BT·(sin(φ + a), cos(φ + a)) with a = atan(L_B/R_B), and CT R_CT·(cos(θ + a′), sin(θ + a′)) with
    a′ = atan(L_B/R_C): their samples lead the B/C angle by a, a′.  The frames are the chain's, the expectations
    by hand."""
    _, _, frame = _thesis_run(pattern)
    axes = ("X", "Z") if pattern in B_PATTERNS else ("X", "Y")
    if pattern not in ("BT", "CT"):
        np.testing.assert_allclose(cv.frame_matrix("machine", frame), np.eye(2), atol=1e-12)
        if pattern in B_PATTERNS:  # B = 0° at +Z, B = 90° at +X
            want = [[0.0, 1.0], [1.0, 0.0]]
        else:  # C = 0° at +X, 90° at +Y; CR with its T ball inside the W ball: θ + 180°
            want = [[-1.0, 0.0], [0.0, -1.0]] if pattern == "CR" else [[1.0, 0.0], [0.0, 1.0]]
        np.testing.assert_allclose(_in_order(frame.basis, frame, axes), want, atol=1e-12)
        return
    a = math.atan2(GEO["L_B"], GEO["R_B"] if pattern == "BT" else 50.0)
    D = _in_order(cv.frame_directions("machine", frame), frame, axes)
    if pattern == "BT":  # (X, Z) components; B = 0 at angle a from +Z towards +X
        np.testing.assert_allclose(D, [[math.sin(a), math.cos(a)], [math.cos(a), -math.sin(a)]], atol=1e-12)
    else:  # (X, Y); C = 0 at angle a′ from +X towards +Y
        np.testing.assert_allclose(D, [[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]], atol=1e-12)


@pytest.mark.parametrize("geometry", D4)
@pytest.mark.parametrize("pattern", ["BX", "BY", "CR", "CA"])
def test_a_reading_maps_what_the_software_reports_to_the_machine_frame(geometry, pattern):
    """The defining relation, checked sample by sample: the software reports the offset ``e_r`` whose projection on
    the direction it draws each sample, ``cos(angle)·d0 + sin(angle)·d90``, is the sample's ΔL; the machine frame's
    ``e_m`` gives the same ΔL on ``u_m(angle)``.  Least squares over 0–90° from ΔL alone recovers ``e_r``;
    :func:`machine_repeats` turns it back into ``e_m`` and :func:`reported_values` inverts that."""
    if pattern[0] == "C":
        geometry = geometry.replace("B0", "C0").replace("B90", "C90").replace("Z", "Y")
    run, bb, frame = _thesis_run(pattern, geometry)
    D = cv.frame_directions(geometry, frame)
    U = frame.basis
    rng = np.random.default_rng(3)
    e_m = rng.normal(size=2)
    angle = np.radians(np.linspace(0.0, 90.0, 31))
    u_m = np.outer(np.cos(angle), U[0]) + np.outer(np.sin(angle), U[1])  # sinusoids: fixed by 0° and 90°
    dL = u_m @ e_m
    drawn = np.outer(np.cos(angle), D[0]) + np.outer(np.sin(angle), D[1])
    e_r = np.linalg.lstsq(drawn, dL, rcond=None)[0]
    run.repeats = {c: np.array([v]) for c, v in zip(frame.components, e_r)}
    machine = cv.machine_repeats(run, bb)
    np.testing.assert_allclose([machine[c][0] for c in frame.components], e_m, atol=1e-12)
    back = cv.reported_values(run, bb, machine)
    np.testing.assert_allclose([back[c][0] for c in frame.components], e_r, atol=1e-12)


def test_a_trace_is_read_in_its_convention(tmp_path):
    """A software drawing B = 0° at +X and 90° at +Z exports the sample of B angle φ at the angle ψ its plot shows
    it, measured as the thesis measures B angles (from +Z towards +X): ψ = 90° − φ.  Read with that convention,
    the trace gives back the machine-frame offsets that made it."""
    e_x, e_z = 12.0, -7.0  # µm, machine frame: ΔL(φ) = e_x sin φ + e_z cos φ
    phi = np.linspace(0.0, 90.0, 46)
    dL = e_x * np.sin(np.radians(phi)) + e_z * np.cos(np.radians(phi))
    rows = ["angle_deg,dL_um,direction"] + [f"{90.0 - a:.6f},{v:.6f},{d}" for d in ("CW", "CCW")
                                            for a, v in zip(phi, dL)]
    (tmp_path / "bx.csv").write_text("\n".join(rows) + "\n")
    text = (variants.thesis_reading().replace('ex_um = [-51.4, -52.1, -51.6]\nez_um = [-41.3, -42.0, -41.7]\n',
                                              'convention = "B0=+X,B90=+Z"\ntrace_csv = "bx.csv"\n'))
    (tmp_path / "c.toml").write_text(text)
    c = load_campaign(tmp_path / "c.toml")
    bx = next(r for r in c.ballbar.runs if r.pattern == "BX")
    m = cv.machine_repeats(bx, c.ballbar)
    assert units.from_internal(m["ex"][0], "um") == pytest.approx(e_x, abs=1e-6)
    assert units.from_internal(m["ez"][0], "um") == pytest.approx(e_z, abs=1e-6)


def test_identify_keeps_the_thesis_reproduction_and_reads_the_campaign(thesis):
    """Table 4.5 stays reproduced from the offsets as entered (the thesis' reading).  Read as the built-in campaign
    reads them (BX: B = 90° at −X; BY: the same and the bar at −Y), by hand: ez_BY = +36.10 µm, so Eq 4.12 gives
    alpha_XB = 36.10 µm / 356.3945 mm = +20.89″; ex_BY stays −9.73 µm, gamma_XB = 5.63″ (Eq 4.14); ez_BX stays
    −41.67 µm, beta_XB = −24.11″ (Eq 4.13); Eq 4.17: (28.50 − 25.77) µm / (62.2491 − 112.2877) mm − 20.89″ =
    −11.27″ − 20.89″ = −32.16″ for alpha_BT; dy_CZ (Eq 4.18 through ex_BY) stays −45.63 µm."""
    ident = identify(thesis)
    assert all(i.reproduced for i in ident.ballbar.values())
    own = {n: i.display for n, i in ident.ballbar_in_convention.items()}
    assert own["alpha_XB"] == pytest.approx(20.89, abs=0.01)
    assert own["gamma_XB"] == pytest.approx(5.63, abs=0.01)
    assert own["beta_XB"] == pytest.approx(-24.11, abs=0.01)
    assert own["alpha_BT"] == pytest.approx(-32.16, abs=0.01)
    assert own["dy_CZ"] == pytest.approx(-45.63, abs=0.01)


# --------------------------------------------------------------------------- two discrepancy scales
def test_two_scale_grid_evidence_and_moments_match_an_independent_quadrature(thesis):
    """Fused linear model of the thesis campaign: the grid's log evidence and the scales' posterior means against
    Gauss–Legendre quadrature (80 × 80 nodes over ±8 posterior sd) of scipy.stats.multivariate_normal over
    (σ_ball bar, σ_probe), within 0.005 nats and 0.01 of a posterior sd."""
    post = LogPosterior(thesis, "linear", data="both")
    pri = post.priors.priors
    A, b, y = post.forward.design, post.likelihood.base_var, post.likelihood.y
    v0 = np.array([q.sd for q in pri[: post.p]]) ** 2
    hn = [q.frozen() for q in pri[post.p:]]
    mp = MarginalPosterior(A, b, v0, hn, groups=post.scale_of, y=y)
    S0 = (A * v0) @ A.T
    mean, sd = mp.sigma_moments(y)
    nodes, wts = np.polynomial.legendre.leggauss(80)
    axes = []
    for m, s in zip(mean, sd):
        lo, hi = max(0.0, m - 8 * s), m + 8 * s
        axes.append((0.5 * (hi - lo) * nodes + 0.5 * (hi + lo), 0.5 * (hi - lo) * wts))
    (xb, wb), (xp, wp) = axes
    logf = np.array([[stats.multivariate_normal(cov=S0 + np.diag(b + np.where(post.scale_of == 0, sb, sp) ** 2))
                      .logpdf(y) + hn[0].logpdf(sb) + hn[1].logpdf(sp) for sp in xp] for sb in xb])
    top = logf.max()
    f = np.exp(logf - top) * np.outer(wb, wp)
    z = f.sum()
    assert mp.log_evidence(y) == pytest.approx(top + math.log(z), abs=0.005)
    assert abs(mean[0] - (f.sum(axis=1) @ xb) / z) < 0.01 * sd[0]
    assert abs(mean[1] - (f.sum(axis=0) @ xp) / z) < 0.01 * sd[1]


# --------------------------------------------------------------------------- the thesis campaign
def test_the_probe_decides_the_reading_of_the_B_runs(as_thesis_reads, thesis):
    """As the thesis reads Table 4.4, the instruments disagree on the B axis and the fused posterior blames the ball
    bar (σ_model 14 µm); the built-in campaign's reading (BX mirrored, BY also reversed) with the stylus length
    known to 0.3 mm wins by more than 60 nats, makes every group agree (p ≥ 0.01) and leaves both scales near
    their priors.  A reading that only explains the stylus length keeps the BY conflict."""
    given = check_instruments(as_thesis_reads, explain=False)
    assert given.scales["sigma_model"][0] > 10.0 and given.scales["sigma_model_probe"][0] < 2.0
    assert {"alpha_XB", "gamma_XB", "beta_XB"} <= set(given.disputed)
    analysis = explain_conflict(as_thesis_reads)
    by_name = {c.name: c for c in analysis.candidates}
    chosen = by_name["B0=+Z,B90=-X, BY bar at −Y; stylus length ±0.3 mm"]
    assert chosen.log_evidence - analysis.given.log_evidence > 60.0
    assert chosen.consistency is not None and (chosen.consistency["verdict"] == "agree").all()
    stylus_only = by_name["stylus length ±0.3 mm"]
    assert chosen.log_evidence - stylus_only.log_evidence > 20.0
    built_in = check_instruments(thesis, explain=False)
    assert built_in.agree
    assert all(m < 4.0 for m, _ in built_in.scales.values())


def test_compensate_refuses_a_disputed_deviation(run_cli, tmp_path):
    """Exit 2 and one line naming the deviations, the verdict and the way out; with the flag it runs and warns."""
    (tmp_path / "c.toml").write_text(variants.thesis_reading())
    program = "mtmcal_bayes/datasets/fig4_30a_bx_original.nc"
    code, out, err = run_cli("compensate", tmp_path / "c.toml", program, "-o", tmp_path / "out.nc")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--accept-disagreement" in err and "alpha_XB" in err and "χ²" in err
    assert not (tmp_path / "out.nc").exists()
    code, out, err = run_cli("compensate", tmp_path / "c.toml", program, "-o", tmp_path / "out.nc",
                             "--accept-disagreement")
    assert code == 0, err
    assert "WARNING: compensated although" in err and (tmp_path / "out.nc").exists()


def test_instruments_command(run_cli):
    code, out, err = run_cli("instruments", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["agree"] is True and doc["disputed"] == {}
    assert set(doc["scales_um"]) == {"sigma_model", "sigma_model_probe"}
    assert doc["explanations"] is None  # nothing to explain when they agree


def test_identification_through_nuisance_priors_is_not_identified(run_cli):
    """dz_BT, confounded with the tool-length error, is not determined (``identified`` false, ``identification``
    "not identified"); the prior-sensitivity diagnostic names the priors it rests on."""
    code, out, err = run_cli("sample", "--sampler", "exact", "--json", "--seed", "1")
    assert code == 0, err
    s = json.loads(out)["summary"]
    assert s["dz_BT"]["identified"] is False and s["dz_BT"]["identification"] == "not identified"
    assert set(s["dz_BT"]["identified_through"]) == {"dRB", "zT"}
    assert s["dz_BT"]["prior_sensitivity"] == "rests on the nuisance priors dRB and zT"
    assert s["alpha_XB"]["identified"] is True and s["alpha_XB"]["identification"] == "data"


# --------------------------------------------------------------------------- the acceptance
def _sbc_through_files(campaign, n: int, seed: int):
    """SBC of the fused exact posterior, the ball bar's offsets written to a campaign file in its reading and read
    back from the file: truth from the fused prior, data from the likelihood (the probe's readings enter as
    simulated means), the truth ranked among 99 exact draws.  Returns ranks (n, q) and the q names."""
    post = LogPosterior(campaign, "linear", data="both")
    obs = Observations.from_campaign(campaign)
    m_bb = len(obs)
    spread = [cv.machine_repeats(campaign.ballbar.runs[k.run], campaign.ballbar)[k.component] - mean
              for k, mean in zip(obs.keys, obs.mean)]
    priors = post.priors.priors
    mp = MarginalPosterior(post.forward.design, post.likelihood.base_var, np.array([q.sd for q in priors[: post.p]]) ** 2,
                           [q.frozen() for q in priors[post.p:]], groups=post.scale_of)
    rng = np.random.default_rng(seed)
    ranks = []
    for _ in range(n):
        theta = post.priors.rvs(1, rng)
        y = post.likelihood.replicate(post.forward.predict(theta[:, : post.p]), post.sigma(theta), rng)[0]
        written = with_run_values(campaign, obs.keys, [v + s for v, s in zip(y[:m_bb], spread)])
        back = parse_campaign(dumps(campaign_to_dict(written)), "written.toml")
        y_read = np.concatenate([Observations.from_campaign(back).mean, y[m_bb:]])
        np.testing.assert_allclose(y_read[:m_bb], y[:m_bb], atol=1e-9)  # the file keeps what was written
        t, s = mp.draw(y_read, 99, rng)
        draws = np.column_stack([t, s])
        ranks.append((draws < theta).sum(axis=0))
    return np.array(ranks), post.names


@pytest.mark.parametrize("reading", ["built-in", "thesis", "B0=+X,B90=+Z"])
def test_sbc_of_the_fused_posterior_with_each_reading_written_to_file(thesis, reading):
    """N = 100 per reading, ranks among 99 exact draws in 10 bins: uniform by a χ² test for every deviation and
    both scales at the family-wise level of validate sbc's criterion, p > 0.01 / 12 (Bonferroni over the twelve
    ranked quantities) — the reading written into the file and read from it is the one the model sees."""
    camp = thesis if reading == "built-in" else parse_campaign(
        variants.thesis_reading() if reading == "thesis" else
        variants.thesis_reading().replace('pattern = "BX"             # B axis, X-direction measurement (step 1)\n',
                                          'pattern = "BX"\nconvention = "B0=+X,B90=+Z"\n')
        .replace('pattern = "BY"             # B axis, Y-direction measurement (step 2)\n',
                 'pattern = "BY"\nconvention = "B0=+X,B90=+Z"\n'), "reading.toml")
    ranks, names = _sbc_through_files(camp, 100, seed=11)
    ranked = [i for i, n in enumerate(names) if "[" not in n]  # the deviations and the two scales
    for i in ranked:
        counts = np.bincount(ranks[:, i] * 10 // 100, minlength=10)
        assert stats.chisquare(counts).pvalue > P_MIN / len(ranked), (names[i], counts)


def test_the_check_catches_the_thesis_reading_of_the_built_in_data(thesis):
    """Data written as the built-in campaign reads its B runs, read as the thesis does: the check flags 80–98 % of
    100 simulated campaigns (prior deviations; bench/readings.py gives 200 and thesis-sized deviations), the false
    alarms with the right reading stay near the eight 1 % tests' 8 % (at most 20 % of 100 here)."""
    built = {r.pattern: r.convention for r in thesis.ballbar.runs if r.convention}
    wrong = misreading_power(thesis, written=built, read="thesis", n=100, seed=5)
    assert wrong.interval[0] > 0.75, (wrong.rate, wrong.interval)
    right = misreading_power(thesis, written=built, read=built, n=100, seed=5)
    assert right.rate <= 0.2, right.rate


# --------------------------------------------------------------------------- probe runs as candidates
def test_a_probe_run_at_45_degrees_separates_alpha_and_gamma(thesis):
    """By hand, the Chapter 2 chain: the stylus ball sits at R·(α cos φ − γ sin φ) in Y at B = φ, the reading of a
    fixed sphere moves the other way, so Y(φ) − Y(0) = R·(α (1 − cos φ) + γ sin φ): at 90° R·(α + γ), the sum only;
    at 45° R·(0.2929 α + 0.7071 γ).  The candidate's rows show exactly those ratios, and with the probe's data
    alone alpha_XB goes from prior-wide to a few arc seconds."""
    from mtmcal_bayes.planning.design import Planner
    from mtmcal_bayes.planning.probe_catalogue import probe_catalogue

    cands = [c for c in probe_catalogue(thesis) if c.angles_deg == (0.0, 45.0, 90.0)]
    assert [c.axis for c in cands] == ["B"] * 3  # the short stylus, a longer one, the sphere higher
    planner = Planner(thesis, cands, ["alpha_XB", "gamma_XB"], data="probe")
    A, _ = planner.candidate_rows()[0]  # the short stylus
    Y = A[[1, 4, 7]]  # X, Y, Z per angle: the Y readings at 0°, 45°, 90°
    step = lambda col: Y[:, planner.space.index(col)] - Y[0, planner.space.index(col)]  # noqa: E731
    assert step("alpha_XB")[1] / step("alpha_XB")[2] == pytest.approx(1 - math.cos(math.pi / 4), rel=1e-6)
    assert step("gamma_XB")[1] / step("gamma_XB")[2] == pytest.approx(math.sin(math.pi / 4), rel=1e-6)
    ev = planner.evaluate()
    before, after = ev.sd_before[0], ev.sd_after[:, 0]
    assert before > 30.0 and after.max() < 5.0, (before, after)


def test_plan_ranks_probe_runs(run_cli):
    code, out, err = run_cli("plan", "--data", "both", "--target", "alpha_CZ", "--json")
    assert code == 0, err
    doc = json.loads(out)
    probe = [c for c in doc["candidates"] if c["kind"] == "probe"]
    # C and B, each with the short stylus, a longer one and the sphere higher; C indexed leads for alpha_CZ
    assert sorted(c["pattern"] for c in probe) == ["probe B"] * 3 + ["probe C"] * 3
    assert doc["candidates"][0]["pattern"] == "probe C" and all(c["feasible"] for c in probe)
    assert probe[0]["targets"]["alpha_CZ"]["sd_after"] < probe[0]["targets"]["alpha_CZ"]["sd_before"]
