"""What a history learns beyond its campaigns (docs/history.md): a drift rate where the data show one and none where
they do not, thermal sensitivities from the campaigns' temperatures (results referred to 20 °C), kinematic models
linearised per campaign and checked."""

import datetime
import json

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Tolerance, Truth
from mtmcal_bayes.histories import HistoryModel, fit_history
from mtmcal_bayes.histories.model import THERMAL_SCALE
from mtmcal_bayes.simulation.history import drift_from_display, synthetic_history, thermal_from_display

DATES = [datetime.datetime(2026, 1, 5) + datetime.timedelta(days=91 * i) for i in range(6)]
SWING = [18.0, 23.5, 20.0, 24.5, 17.5, 21.0]  # °C: a workshop without climate control, summer and winter
KAPPA = {"alpha_XB": 1.5, "dy_CZ": -2.0}  # ″/°C, µm/°C


@pytest.fixture(scope="module")
def base():
    return mb.load_campaign()


@pytest.fixture(scope="module")
def thermal_history(base):
    camps = synthetic_history(base, Truth(), DATES, temperatures=SWING,
                              thermal=[thermal_from_display(n, k) for n, k in KAPPA.items()], seed=5)
    return camps, fit_history(camps, seed=0)


def test_augmented_posterior_is_the_stacked_gaussian_with_trend_and_temperature(base):
    """The joint posterior of (states, drift rates, thermal sensitivities) equals brute-force Gaussian conditioning
    of the stacked system written out independently: x_t = x_0 + r·τ_t + w_t, y_t = A_t (x_t + κ ΔT_t) + …"""
    camps = synthetic_history(base, Truth(), DATES[:3], temperatures=[18.0, 22.0, 25.0], seed=4)
    hm = HistoryModel(camps)
    d, T = hm.d, hm.T
    vr = np.linspace(1.0, 2.0, d) * units.to_internal(10.0, "arcsec") ** 2
    hm.set_trend(vr)
    q2 = np.full((1, d), units.to_internal(3.0, "arcsec") ** 2)
    s2 = np.array([units.to_internal(0.5, "um") ** 2])
    mean, cov = hm.augmented_posterior(q2, s2)
    # independent construction: Z = (x0 (d), w_1..w_T (T·d), r (d), κ (d)); x_t = x0 + τ_t r + w_t
    n_z = d + T * d + 2 * d
    prior = np.zeros(n_z)
    prior[:d] = hm.mu0
    tmin = np.minimum.outer(hm.tau, hm.tau)
    S = np.zeros((n_z, n_z))
    S[:d, :d] = np.diag(hm.var0)
    for j in range(d):
        idx = d + np.arange(T) * d + j
        S[np.ix_(idx, idx)] = q2[0, j] * tmin
    S[d + T * d:d + T * d + d, d + T * d:d + T * d + d] = np.diag(vr)
    S[-d:, -d:] = np.diag(hm.thermal_var)
    X = np.zeros((T * d + 2 * d, n_z))  # (x_1..x_T, r, κ) from Z
    for t in range(T):
        rows = t * d + np.arange(d)
        X[rows, np.arange(d)] = 1.0
        X[rows, d + t * d + np.arange(d)] = 1.0
        X[rows, d + T * d + np.arange(d)] = hm.tau[t]
    X[T * d:, d + T * d:] = np.eye(2 * d)
    blocks = [hm.H[:, t * d:(t + 1) * d] for t in range(T)]
    Hz = sum(blocks[t] @ (X[t * d:(t + 1) * d] + hm.dT[t] * X[T * d + d:]) for t in range(T))
    y = hm.resid + hm.H @ np.tile(hm.mu0, T)
    noise = hm.R + s2[0] * np.eye(hm.M)
    gain = S @ Hz.T @ np.linalg.inv(Hz @ S @ Hz.T + noise)
    post_mean = prior + gain @ (y - Hz @ prior)
    post_cov = S - gain @ Hz @ S
    assert np.allclose(mean[0], X @ post_mean, rtol=1e-6, atol=1e-10)
    assert np.allclose(cov[0], X @ post_cov @ X.T, rtol=1e-5, atol=1e-14)


@pytest.fixture
def first_stage_once(monkeypatch):
    """The histories' scale sampling (``histories.fit._sample_scales``) remembered by everything it depends on: the
    generator's state, the history's residuals and static covariance, its trend variances and the step counts.  The
    random-walk fit (``trend="off"``) of a history whose ``trend="auto"`` fit came first is that fit's first stage
    (the same model, the same seeded generator): it gets those very draws, bit for bit, and the generator left as
    sampling them left it, instead of drawing them again.  A stage begun from given walkers (the resampling once
    a trend is kept) is always sampled.  Yields the number of stages taken from memory."""
    from importlib import import_module

    fit_module = import_module("mtmcal_bayes.histories.fit")  # the module: the package's ``fit`` is its function
    real, made, taken = fit_module._sample_scales, {}, []

    def sample_scales(hm, rng, *, start=None, **steps):
        if start is not None:
            return real(hm, rng, start=start, **steps)
        key = (repr(rng.bit_generator.state), hm.resid.tobytes(), hm.C0.tobytes(), hm.trend_var.tobytes(),
               tuple(sorted(steps.items())))
        if key in made:
            taken.append(key)
        else:
            made[key] = real(hm, rng, **steps), rng.bit_generator.state
        out, after = made[key]
        rng.bit_generator.state = after
        return tuple(np.copy(x) if isinstance(x, np.ndarray) else x for x in out)

    monkeypatch.setattr(fit_module, "_sample_scales", sample_scales)
    return taken


def test_a_ramp_is_extrapolated_and_warns_closer_to_the_crossing(base, first_stage_once):
    """Acceptance: alpha_XB ramps by 8″ a year against ±10″ (true crossing 1.25 years after the first of 5
    campaigns, one a quarter).  The docs promise "recalibrate by" before the true crossing in at least 90 % of
    cases: 10 seeded histories, at least 9.  The data choose the trend in most of them (more than half: 7 of 10
    with these seeds; a year of five campaigns is short evidence against a random walk) and then find the rate
    (within 3 of its sd of 8″/year); on average the warning comes closer to the crossing than the random walk's
    alone, which warns by the growth of its band (with these seeds 45 against 66 days early).
    The random-walk run is the first stage of the same seeded fit, so where no trend is kept it is the same; where
    one is kept, the random-walk fit takes that first stage's draws instead of sampling them again
    (``first_stage_once``: one for each history that kept its trend)."""
    dates = DATES[:5]
    tol = {"alpha_XB": Tolerance("alpha_XB", units.to_internal(-10, "arcsec"), units.to_internal(10, "arcsec"))}
    crossing = dates[0] + datetime.timedelta(days=365.25 * 10 / 8)
    early, chosen, lead = 0, 0, {"auto": [], "off": []}
    for seed in range(10):
        camps = synthetic_history(base, Truth(), dates, drifts=[drift_from_display("alpha_XB", "ramp", 8.0, dates[0])],
                                  seed=200 + seed)
        auto = fit_history(camps, seed=seed, tolerances=tol)
        t = auto.trend()["alpha_XB"]
        kept = t["model"] == "trend"
        off = fit_history(camps, seed=seed, tolerances=tol, trend="off") if kept else auto
        for name, r in (("auto", auto), ("off", off)):
            when = r.forecast[0]["recalibrate_by"]
            assert when is not None and when >= dates[-1]
            lead[name].append((crossing - when).days)
        early += auto.forecast[0]["recalibrate_by"] < crossing
        chosen += kept
        if kept:
            assert abs(t["rate_mean"] - 8.0) < 3 * t["rate_sd"], t
    assert early >= 9, lead
    assert chosen > 5, lead
    assert np.mean(lead["auto"]) < np.mean(lead["off"]), lead
    assert len(first_stage_once) == chosen


# a flat history keeps random walks (no drift at all: no deviation gets a drift rate): checked on the 12 seeded
# histories without a change of tests/test_history.py::test_false_alarm_rate_without_change, the same five dates


def test_thermal_sensitivity_is_recovered_within_its_interval(thermal_history):
    """Acceptance: a history over an 18–24.5 °C swing with known sensitivities (alpha_XB 1.5″/°C, dy_CZ −2 µm/°C,
    the rest 0) recovers each within 3 posterior sd, reports them as learnt, and the 20 °C values of alpha_XB are
    flat while the values as measured follow the temperature."""
    camps, r = thermal_history
    th = r.thermal()
    for q, t in th.items():
        truth = KAPPA.get(q, 0.0)
        assert abs(t["mean"] - truth) < 3 * t["sd"], (q, t)
    assert th["alpha_XB"]["identified"] and th["dy_CZ"]["identified"]
    assert th["alpha_XB"]["sd"] < 0.2 * th["alpha_XB"]["prior_sd"]
    at20 = r.summary_20C.xs("alpha_XB", level="quantity")["mean"].to_numpy()
    measured = r.summary.xs("alpha_XB", level="quantity")["mean"].to_numpy()
    slope = np.polyfit(np.array(SWING) - 20.0, measured, 1)[0]
    assert abs(slope - 1.5) < 0.3 and np.ptp(at20) < 0.3 * np.ptp(measured)


def test_constant_temperature_leaves_the_sensitivity_to_its_prior(base):
    """Acceptance: every campaign at 20.4 °C: the sensitivity is confounded with the deviation itself, so its
    posterior sd stays at the prior's and it is reported as prior-only."""
    r = fit_history(synthetic_history(base, Truth(), DATES[:4], temperatures=[20.4] * 4, seed=7), seed=1)
    for q, t in r.thermal().items():
        assert not t["identified"] and t["sd"] > 0.9 * t["prior_sd"], (q, t)
    assert THERMAL_SCALE["arcsec"] == pytest.approx(r.thermal()["alpha_CZ"]["prior_sd"], rel=0.05)


def test_history_json_gains_trend_thermal_and_20C(thermal_history, tmp_path):
    """The interface scripts rely on: "trend" {quantity: {model, rate_mean, rate_sd, unit}}, "thermal"
    {quantity: {mean, sd, unit, identified}}, "summary_20C" beside "summary" when temperatures are given."""
    camps, r = thermal_history
    doc = json.loads(json.dumps(r.to_json(), default=str))
    assert set(doc["trend"]) == set(r.fit.quantities)
    assert {"model", "rate_mean", "rate_sd", "unit"} <= set(doc["trend"]["alpha_XB"])
    assert doc["trend"]["alpha_XB"]["unit"] == "″/year"
    assert {"mean", "sd", "unit", "identified"} <= set(doc["thermal"]["dy_CZ"]) and doc["thermal"]["dy_CZ"]["unit"] == "µm/°C"
    assert set(doc["summary_20C"]) == set(doc["summary"]) == set(doc["dates"])
    files = r.write(tmp_path / "out")
    assert {"thermal.csv", "history_summary_20C.csv", "trend.csv", "trend.png"} <= set(files)


def test_history_without_temperatures_has_no_20C_summary(base):
    r = fit_history(synthetic_history(base, Truth(), DATES[:3], seed=8), seed=2)
    doc = r.to_json()
    assert "summary_20C" not in doc and doc["thermal"] == {} and set(doc["trend"]) == set(r.fit.quantities)


def test_some_temperatures_missing_is_one_line(run_cli, tmp_path, base):
    camps = synthetic_history(base, Truth(), DATES[:3], temperatures=[19.0, 21.0, 22.0], seed=9)
    camps[1].temperature_C = None
    for i, c in enumerate(camps):
        mb.save_campaign(c, tmp_path / f"{i}.toml")
    code, out, err = run_cli("history", str(tmp_path))
    assert code == 2 and "temperature_C: missing" in err and "1.toml" in err and len(err.strip().splitlines()) == 1


def test_kinematic_history_is_linearised_and_checked(base):
    """``history --model htm-thesis``: each campaign linearised at the history's estimate; on thesis-sized
    deviations the expansion is within the instrument accuracy (stated), and the estimates agree with the linear
    history's within a tenth of their sd (the linear model is the kinematic model's first order)."""
    camps = synthetic_history(base, Truth(), DATES[:3], seed=10, model="htm-thesis")
    kin = fit_history(camps, seed=3, model="htm-thesis", trend="off")
    lin = fit_history(camps, seed=3, model="linear", trend="off")
    check = kin.to_json()["linearisation"]
    assert check["model"] == "htm-thesis" and check["ok"] and check["max_gap_um"] < check["accuracy_um"]
    a, b = kin.summary, lin.summary
    assert (np.abs(a["mean"] - b["mean"]) < 0.1 * b["sd"]).all()
    assert "linearised at the history's estimate" in kin.to_text().lower()


def test_fleet_model_reaches_the_histories(base):
    """``fleet --model htm-thesis`` is honoured for histories, never silently replaced by the linear model: the
    history unit fits the kinematic history and its cache key names the model."""
    from mtmcal_bayes.fleets.units import FleetSettings, history_unit, unit_key

    camps = synthetic_history(base, Truth(), DATES[:2], seed=12, model="htm-thesis")
    payload = history_unit(camps, 5, False, "htm-thesis")
    assert "error" not in payload, payload
    assert payload["result"]["model"] == "htm-thesis" and payload["result"]["linearisation"]["ok"]
    keys = {m: unit_key("history", ["a", "b"], FleetSettings(model=m)) for m in ("linear", "htm-thesis")}
    assert keys["linear"] != keys["htm-thesis"]
