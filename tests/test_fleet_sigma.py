"""σ_model learnt by a fleet (docs/fleet.md): each history's likelihood of ln σ, pooled over the machines of one
type in a hierarchy, and the predictive prior of a new machine."""

import datetime
import math

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.fleets.sigma_model import TAU_GRID, TAU_SCALE, U_GRID, history_log_likelihood, pool
from mtmcal_bayes.histories import fit_history
from mtmcal_bayes.simulation.history import synthetic_history

def test_pooling_integrates_the_hierarchy_exactly():
    """With Gaussian likelihoods N(u; m_i, s_i²) the marginal of each history given (μ, τ) is N(m_i; μ, s_i² + τ²);
    with μ's prior (the assumed half-normal of σ_model, 2 µm) and τ's, the pooled posterior moments of μ and τ and the predictive equal that analytic computation on the same grid
    (to the grid's integration error, 1e-3 in ln σ)."""
    m, s = np.array([0.2, 0.5, 0.35]), np.array([0.2, 0.3, 0.25])
    rows = [(-0.5 * ((U_GRID - mi) / si) ** 2).tolist() for mi, si in zip(m, s)]
    got = pool(rows)
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


def _gaussian(m, s):
    return (-0.5 * ((U_GRID - m) / s) ** 2).tolist()


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
    """A 5-campaign history simulated with σ_model = 2 µm: its likelihood of ln σ (from the history model itself)
    is highest within a factor 1.6 of 2 µm, and falls by more than 4 in log at 0.2 µm and at 20 µm."""
    base = mb.load_campaign()
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(5)]
    camps = synthetic_history(base, Truth(), dates, seed=8, sigma_model=units.to_internal(2.0, "um"))
    r = fit_history(camps, seed=2, trend="off")
    ll = np.array(history_log_likelihood(r.fit.model, r.fit.q2))
    assert abs(U_GRID[np.argmax(ll)] - math.log(2.0)) < math.log(1.6)
    assert ll[np.argmin(np.abs(U_GRID - math.log(0.2)))] < -4 and ll[np.argmin(np.abs(U_GRID - math.log(20)))] < -4


def _plant(root, base, *, sigmas_um, single_type="MTX-200", config=None):
    """Machines of type MTX-200, one history of 3 campaigns each with its own simulated σ_model, and one machine
    with a single campaign (its type ``single_type``, its configuration ``config`` if given)."""
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
    if config is not None:
        new.machine.configuration = config
    mb.save_campaign(new, root / "NEW" / "2025-01-06.toml")
    return root / "NEW" / "2025-01-06.toml"


# a fleet that teaches a new machine its σ_model: tests/test_fleet_latest.py (its plant is of one type)


def test_a_type_shared_by_machines_of_another_geometry_is_one_line(tmp_path, run_cli):
    base = mb.load_campaign()
    _plant(tmp_path / "plant", base, sigmas_um=(1.5,), config="another build")
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
