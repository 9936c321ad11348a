"""σ_model learnt by a fleet (docs/fleet.md): each history's likelihood of ln σ, pooled over the machines of one
type in a hierarchy, and the predictive prior of a new machine."""

import datetime
import math

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.fleets.sigma_model import TAU_GRID, TAU_SCALE, U_GRID, V_GRID, history_log_likelihood, pool
from mtmcal_bayes.histories import HistoryModel
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.simulation.history import synthetic_history
from mtmcal_bayes.simulation.simulate import truth_from_vector

def _tables(rows_u: list, rows_v: list | None = None) -> list:
    """History tables on (V_GRID, U_GRID) from log likelihoods of u (and, added, of v = ln κ)."""
    rows_v = rows_v or [np.zeros(len(V_GRID))] * len(rows_u)
    return [(np.asarray(b)[:, None] + np.asarray(a)[None, :]).tolist() for a, b in zip(rows_u, rows_v)]


def test_pooling_integrates_the_hierarchy_exactly():
    """With likelihoods N(u; m_i, s_i²) that do not depend on the drift scale, the marginal of each history given
    (μ, τ) is N(m_i; μ, s_i² + τ²); with μ's prior (the assumed half-normal of σ_model, 2 µm) and τ's, the pooled
    posterior moments of μ and τ and the predictive equal that analytic computation on the same grid (to the grid's
    integration error, 1e-3 in ln σ), and the type's drift scale keeps its prior."""
    m, s = np.array([0.2, 0.5, 0.35]), np.array([0.2, 0.3, 0.25])
    got = pool(_tables([-0.5 * ((U_GRID - mi) / si) ** 2 for mi, si in zip(m, s)]))
    var = s[:, None, None] ** 2 + TAU_GRID[None, None, :] ** 2
    log_marg = -0.5 * (m[:, None, None] - U_GRID[None, :, None]) ** 2 / var - 0.5 * np.log(var)
    mu_prior = -0.5 * (np.exp(U_GRID) / 2.0) ** 2 + U_GRID  # half-normal(2 µm) in σ, as a density of u = ln σ
    lp = log_marg.sum(axis=0) - 0.5 * (TAU_GRID / TAU_SCALE) ** 2 + mu_prior[:, None]
    w = np.exp(lp - lp.max())
    w /= w.sum()
    mu = np.sum(w.sum(axis=1) * U_GRID)
    tau = np.sum(w.sum(axis=0) * TAU_GRID)
    pred_sd = math.sqrt(np.sum(w * (TAU_GRID[None, :] ** 2 + (U_GRID[:, None] - mu) ** 2)))
    assert got["mu"]["mean"] == pytest.approx(mu, abs=1e-3)
    assert got["tau"]["mean"] == pytest.approx(tau, abs=1e-3)
    assert got["log_sd"] == pytest.approx(pred_sd, abs=1e-3)
    assert got["median_um"] == pytest.approx(math.exp(mu), rel=1e-3)
    prior_v = np.diff(_half_cauchy_cells(1.0))
    assert got["drift_scale"]["mean"] == pytest.approx(np.sum(prior_v * V_GRID), abs=1e-9)


def _half_cauchy_cells(scale: float) -> np.ndarray:
    """The half-Cauchy(scale) CDF at the edges of V_GRID's cells (0, the midpoints in ln κ, ∞), by quadrature of its
    density (independently of the package's closed form)."""
    from scipy.integrate import quad

    edges = np.exp(0.5 * (V_GRID[1:] + V_GRID[:-1]))
    dens = lambda k: 2.0 / (math.pi * scale * (1.0 + (k / scale) ** 2))  # noqa: E731
    inner = np.cumsum([quad(dens, a, b)[0] for a, b in zip(np.concatenate([[0.0], edges[:-1]]), edges)])
    return np.concatenate([[0.0], inner, [1.0]])


def test_the_drift_scale_is_pooled_with_each_machine_half_cauchy_of_the_type():
    """Tables separable in (v, u): the posterior of the type's drift scale κ_T is its half-Cauchy(1) prior times,
    per history, Σ_v P(κ_i in v's cell | κ_T) e^{b_i(v)} — the cells' probabilities from quadrature of the density;
    a drift wanted by the histories (b peaking at κ = 3) moves κ_T up, one refused (b falling beyond κ = 0.01) down."""
    cells = np.diff(np.array([_half_cauchy_cells(k) for k in np.exp(V_GRID)]), axis=1)  # (κ_T, κ_i)
    prior = np.diff(_half_cauchy_cells(1.0))
    flat_u = [-0.5 * ((U_GRID - 0.3) / 0.3) ** 2] * 2
    for centre in (math.log(3.0), math.log(0.01)):
        b = [-0.5 * ((V_GRID - centre) / 1.0) ** 2, -0.5 * ((V_GRID - centre - 0.5) / 1.5) ** 2]
        got = pool(_tables(flat_u, b))["drift_scale"]
        post = prior * np.prod([cells @ np.exp(bi) for bi in b], axis=0)
        post /= post.sum()
        assert got["mean"] == pytest.approx(np.sum(post * V_GRID), abs=1e-6)
        assert got["sd"] == pytest.approx(math.sqrt(np.sum(post * (V_GRID - np.sum(post * V_GRID)) ** 2)), abs=1e-6)
    # the direction, for the reader: a wanted drift raises the type's scale above its prior's, a refused one lowers it
    prior_mean = np.sum(prior * V_GRID)
    up = pool(_tables(flat_u, [-0.5 * ((V_GRID - math.log(3.0)) / 1.0) ** 2] * 2))["drift_scale"]["mean"]
    down = pool(_tables(flat_u, [-0.5 * ((V_GRID - math.log(0.01)) / 1.0) ** 2] * 2))["drift_scale"]["mean"]
    assert down < prior_mean < up


def _gaussian(m, s):
    return _tables([-0.5 * ((U_GRID - m) / s) ** 2])[0]


def test_machines_that_share_sigma_model_give_a_narrow_prior_and_those_that_do_not_a_wide_one():
    """Five histories whose likelihoods of ln σ peak at ln 1.5 µm (sd 0.2) give a new machine a prior far narrower
    than one history does and centred on 1.5 µm; three at 0.5, 1.5 and 4 µm give a wide one (τ large): the
    pooled prior does not pretend the machines agree."""
    same = pool([_gaussian(math.log(1.5) + d, 0.2) for d in (-0.05, 0.02, 0.0, 0.04, -0.01)])
    one = pool([_gaussian(math.log(1.5), 0.2)])
    apart = pool([_gaussian(math.log(x), 0.2) for x in (0.5, 1.5, 4.0)])
    assert abs(math.log(same["median_um"] / 1.5)) < 2 * same["log_sd"]
    assert same["log_sd"] < 0.5 * one["log_sd"]
    assert apart["tau"]["mean"] > 3 * same["tau"]["mean"] and apart["log_sd"] > 3 * same["log_sd"]


def test_a_history_likelihood_of_sigma_model_peaks_near_its_true_value():
    """A 5-campaign history simulated with σ_model = 2 µm and no drift: its likelihood of ln σ without drift (the
    first row of its table, κ = 10⁻³) is highest within a factor 1.6 of 2 µm and falls by more than 4 in log at
    0.2 µm and at 20 µm; a drift scale of the history model's prior (κ = 1) fits its data worse."""
    base = mb.load_campaign()
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(5)]
    camps = synthetic_history(base, Truth(), dates, seed=8, sigma_model=units.to_internal(2.0, "um"))
    table = np.array(history_log_likelihood(HistoryModel(camps)), dtype=float)
    assert table.shape == (len(V_GRID), len(U_GRID)) and table.max() == 0.0
    ll = table[0]
    assert abs(U_GRID[np.argmax(ll)] - math.log(2.0)) < math.log(1.6)
    assert ll[np.argmin(np.abs(U_GRID - math.log(0.2)))] < ll.max() - 4
    assert ll[np.argmin(np.abs(U_GRID - math.log(20)))] < ll.max() - 4
    assert table[np.argmin(np.abs(V_GRID))].max() < ll.max()


def _no_drift_fleet(n: int, sigma_um: float, seed: int) -> list:
    """The campaigns of ``n`` machines, 4 quarterly campaigns each at ``sigma_um`` without drift, deviations drawn
    from their priors (bench/fleet_sigma.py's simulator)."""
    base = mb.load_campaign()
    post = LogPosterior(base, "linear")
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(4)]
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        truth = truth_from_vector(post.space, post.priors.rvs(1, rng)[0][: post.p])
        out.append(synthetic_history(base, Truth(dict(truth.deviations)), dates, seed=int(rng.integers(2**31)),
                                     sigma_model=units.to_internal(sigma_um, "um")))
    return out


def test_fleets_without_drift_learn_their_sigma_model_unbiased():
    """Ten fleets of four machines, each machine 4 quarterly campaigns at σ_model = 1 µm without drift (the set-up of
    bench/fleet_sigma.py): the mean over the fleets of ln(pooled median / 1 µm) lies within ±0.16, and every fleet
    learns that its type hardly drifts (ln κ_T < ln 0.3).

    On the bench's 200 such fleets ln median was −0.05 ± 0.11 (mean ± sd of one fleet), so the mean of ten has an
    sd of 0.036 and the band's edge is three of them from −0.05; the largest ln κ_T of the 200 was −1.6.  Under the
    old evidence (the likelihood of σ averaged over posterior draws of ten independent drift rates, each half-Cauchy
    of 5 per √year) these very histories give a mean of −0.28, outside the band (and 40 fleets pooled to 0.74 µm,
    the new machines' 90 % intervals covering 86 %): the rates took up part of the fresh-per-campaign discrepancy."""
    tables = [history_log_likelihood(HistoryModel(c)) for c in _no_drift_fleet(40, 1.0, seed=35)]
    pooled = [pool(tables[i:i + 4]) for i in range(0, 40, 4)]
    assert abs(np.mean([math.log(p["median_um"]) for p in pooled])) < 0.16, pooled
    assert all(p["drift_scale"]["mean"] < math.log(0.3) for p in pooled), pooled


def _plant(root, base, *, sigmas_um, single_type="MTX-200", travel=None):
    """Machines of type MTX-200, one history of 3 campaigns each with its own simulated σ_model, and one machine
    with a single campaign (its type ``single_type``, its axis travels ``travel`` if given)."""
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(3)]
    for k, s in enumerate(sigmas_um):
        serial = f"T-{k + 1}"
        (root / serial).mkdir(parents=True)
        for c in synthetic_history(base, Truth(), dates, serial=serial, seed=40 + k,
                                   sigma_model=units.to_internal(s, "um")):
            c.machine.type = "MTX-200"
            mb.save_campaign(c, root / serial / f"{c.date.date()}.toml")
    (root / "NEW").mkdir()
    new = synthetic_history(base, Truth(), dates[:1], serial="NEW", seed=60, sigma_model=units.to_internal(1.5, "um"))[0]
    new.machine.type = single_type
    if travel is not None:
        new.machine.travel = travel
    mb.save_campaign(new, root / "NEW" / "2025-01-06.toml")
    return root / "NEW" / "2025-01-06.toml"


# a fleet that teaches a new machine its σ_model: tests/test_fleet_latest.py (its plant is of one type)


def test_a_type_shared_by_machines_of_another_geometry_is_one_line(tmp_path, run_cli):
    base = mb.load_campaign()
    _plant(tmp_path / "plant", base, sigmas_um=(1.5,), travel={"X": 700.0, "Y": 250.0, "Z": 1077.0})
    code, out, err = run_cli("fleet", str(tmp_path / "plant"), "-o", str(tmp_path / "out"), "--sampler", "exact")
    assert code == 2 and "machine.type" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def test_the_command_line_process_samples_under_a_learnt_prior(tmp_path):
    """The real command (a process of its own, where Dask's array and distributed modules are hidden from xarray)
    samples and writes its NetCDF under a learnt log-normal prior, whose density SciPy computes."""
    import subprocess
    import sys
    from pathlib import Path

    from mtmcal_bayes.io.sigma_prior_file import write_sigma_model_prior
    from mtmcal_bayes.sigma_prior import SigmaModelPrior

    prior = tmp_path / "prior.toml"
    write_sigma_model_prior(prior, SigmaModelPrior({"sigma_model": (1.0, 0.2)}, "a test"))
    exe = Path(sys.executable).with_name("mtmcal-bayes")
    done = subprocess.run([str(exe), "sample", "--sampler", "exact", "--sigma-model-prior", str(prior), "-o",
                           str(tmp_path / "post.nc"), "--quiet"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "post.nc").stat().st_size > 0 and "learnt" in done.stdout
