"""Fit a machine's history: sample the drift rates and σ_model, then every quantity at every date, the changes
between dates, and the forecast against the tolerances.

* **Scales.** emcee (``vectorize=True``) samples ``log q_j`` (one drift rate per deviation, half-Cauchy prior of
  scale :data:`DRIFT_SCALE` per √year: small drift is expected, a crash must stay possible) and ``log σ_i``
  (the discrepancy scale of each instrument the data use, its prior from the campaign) on the exact marginal
  likelihood of :class:`.model.HistoryModel`.
* **States.** For :data:`N_STATE` scale draws the states' Gaussian posterior is exact; quantities are linear
  combinations, so their means and variances are exact per draw and the posterior is the mixture.
* **Changes.** Between consecutive campaigns, ``P(|Δ| > threshold)`` from the mixture.  A change is flagged
  when that probability exceeds ``1 − α/K`` with K the number of (quantity, interval) pairs examined
  (Bonferroni): under the model the chance that a history with no change raises any flag is at most α.
* **Trend.** Each deviation's drift rate (:mod:`.model`) is kept when the data want it: the Bayes factor of
  "random walk + trend" against "random walk" for that deviation, ``E[p(y | θ, trend) / p(y | θ)]`` over the
  random-walk posterior of the scales θ (exact identity, the same scale prior in both), must pass
  :data:`TREND_BAYES_FACTOR`.  A flat quantity stays flat: the rate's prior (sd :data:`TREND_SCALE` per year)
  costs an Occam factor the data must pay back.  With trends kept, the scales are sampled again.
* **Temperature.** With every campaign's ``temperature_C`` the thermal sensitivities (prior sd
  :data:`THERMAL_SCALE` per °C) are conditioned jointly with the drift; a sensitivity whose posterior sd is not
  below :data:`IDENTIFIED_SD_RATIO` of its prior sd is reported as prior-only.
* **Forecast.** At a future date the state (at 20 °C) is the last one plus the rate times the time plus a
  random-walk step, ``N(m_T + m_r·Δτ, P_T + 2Δτ·P_Tr + Δτ²·P_r + q²·Δτ)``; the probability of being out of
  tolerance is that mixture's mass outside; "recalibrate by" is the first date (daily grid, up to
  :data:`HORIZON_YEARS`) where it passes :data:`FORECAST_RISK`.
"""

from __future__ import annotations

import datetime
import logging
import math
from dataclasses import dataclass

import emcee
import numpy as np
from scipy.stats import norm

from .. import units
from ..errors import MtmcalError, ParameterError
from ..inference.priors import PriorSet
from ..parameters import quantity_unit, weights
from .model import SECONDS_PER_YEAR, THERMAL_SCALE, HistoryModel  # noqa: F401 - THERMAL_SCALE re-exported for the docs

#: half-Cauchy scale of each drift rate, display units per √year
DRIFT_SCALE = {"arcsec": 5.0, "um": 5.0}
#: a change smaller than this is not worth flagging (display units), unless a tolerance says otherwise
PRACTICAL_MINIMUM = {"arcsec": 5.0, "um": 5.0}
#: family-wise false-alarm rate of the change flags (Bonferroni over quantities × intervals)
ALPHA = 0.05
#: probability of nonconformance at which the forecast says "recalibrate by"
FORECAST_RISK = 0.05
HORIZON_YEARS = 5.0
N_STATE = 400
WALKERS_PER_DIM = 2
#: steps and burn-in of the scale sampler (22 walkers for 10 deviations; the largest autocorrelation time of a
#: 5-campaign history is about 35 steps: 550 kept steps are 15 of them)
N_STEPS = 800
BURN = 250
#: steps and burn-in of the second run, with the trends kept, started from the first run's walkers
RESAMPLE_STEPS = 500
RESAMPLE_BURN = 100
#: the drift rates sampled span e^±LOG_RANGE around their prior scale (e^-2·LOG_RANGE below)
LOG_RANGE = 11.5
#: prior sd of a deviation's drift rate where it has a trend, display units per year
TREND_SCALE = {"arcsec": 10.0, "um": 10.0}
#: Bayes factor a trend must reach against the random walk alone to be kept ("positive" evidence, Kass & Raftery)
TREND_BAYES_FACTOR = 3.0
#: a thermal sensitivity is learnt when its posterior sd is below this share of its prior sd (else prior-only)
IDENTIFIED_SD_RATIO = 0.5
#: scale draws conditioned at once (bounds the (n, K, K) covariances in memory)
CHUNK = 50
#: ``trend`` choices of :func:`fit`
TREND_CHOICES = ("auto", "off")


@dataclass(frozen=True)
class HistoryFit:
    """Draws of the scales, and per scale draw the mean and sd of each quantity at each date (at 20 °C), as
    measured (at the campaign's temperature), its drift rate and thermal sensitivity; display units."""

    model: HistoryModel
    quantities: list[str]
    q2: np.ndarray  # (n, d) drift rates², internal units per year
    s2: np.ndarray  # (n, S) the discrepancy scales², mm² (``model.scales``)
    mean: np.ndarray  # (n, T, k) display units, at 20 °C
    sd: np.ndarray  # (n, T, k)
    last_var: np.ndarray  # (n, k) variance at the last date, display units²
    walk_var: np.ndarray  # (n, k) random-walk variance per year of each quantity, display units²
    delta_mean: np.ndarray  # (n, T-1, k) change between consecutive campaigns
    delta_sd: np.ndarray  # (n, T-1, k)
    acceptance: float
    tau_max: float
    measured_mean: np.ndarray  # (n, T, k) at each campaign's temperature (= mean without temperatures)
    measured_sd: np.ndarray  # (n, T, k)
    rate_mean: np.ndarray  # (n, k) drift rate per year (0 where no trend)
    rate_var: np.ndarray  # (n, k)
    last_rate_cov: np.ndarray  # (n, k) covariance of the last state and the rate
    thermal_mean: np.ndarray  # (n, k) per °C
    thermal_var: np.ndarray  # (n, k)
    thermal_prior_sd: np.ndarray  # (k,)
    trend: dict  # {deviation: log10 Bayes factor of trend against random walk}; "trended": the deviations kept


def drift_scale(deviations) -> np.ndarray:
    """The half-Cauchy scale of each deviation's drift rate (:data:`DRIFT_SCALE`), internal units per √year, (d,)."""
    return _internal_scale(DRIFT_SCALE, deviations)


def _log_prob_factory(hm: HistoryModel):
    scale = drift_scale(hm.deviations)
    sig = PriorSet(hm.sigma_priors)  # plain numpy: scipy's frozen logpdf was a seventh of the fit
    d = hm.d

    def log_prob(z: np.ndarray) -> np.ndarray:
        z = np.atleast_2d(z)
        q = np.exp(z[:, :d])
        s = np.exp(z[:, d:])  # (n, S)
        lp = np.sum(np.log(2.0 / (math.pi * scale)) - np.log1p((q / scale) ** 2) + z[:, :d], axis=1)
        lp = lp + sig.logpdf(s) + z[:, d:].sum(axis=1)
        out = np.full(len(z), -np.inf)
        # a drift of 10⁵ times the prior scale or a σ_model of a millimetre is no machine: outside the support
        ok = np.isfinite(lp) & (z[:, :d] < np.log(scale) + LOG_RANGE).all(axis=1) & (z[:, :d] > np.log(scale) - 2 * LOG_RANGE).all(axis=1)
        ok &= (s < units.to_internal(1.0, "mm")).all(axis=1) & (s > units.to_internal(1e-4, "um")).all(axis=1)
        if ok.any():
            out[ok] = lp[ok] + hm.log_marginal(q[ok] ** 2, s[ok] ** 2)
        return out

    return log_prob, scale


def _internal_scale(table: dict, names) -> np.ndarray:
    return np.array([units.to_internal(table[quantity_unit(n)], quantity_unit(n)) for n in names])


def _sample_scales(hm: HistoryModel, rng: np.random.Generator, *, start: np.ndarray | None = None,
                   steps: int = N_STEPS, burn: int = BURN) -> tuple[np.ndarray, float, float, np.ndarray]:
    """N_STATE draws (n, d + S) of (log q, log σ), the acceptance fraction, the largest autocorrelation time and
    the walkers' last positions (``start``: where the walkers begin, default spread around the prior scales)."""
    log_prob, scale = _log_prob_factory(hm)
    dim = hm.d + len(hm.scales)
    walkers = WALKERS_PER_DIM * dim + (WALKERS_PER_DIM * dim) % 2
    s0 = np.array([p.sd for p in hm.sigma_priors])
    if start is None:
        start = np.column_stack([np.log(scale * 0.3) + rng.normal(0, 0.5, (walkers, hm.d)),
                                 np.log(s0) + rng.normal(0, 0.3, (walkers, len(s0)))])
    sampler = emcee.EnsembleSampler(walkers, dim, log_prob, vectorize=True,
                                    moves=[(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)])
    sampler.random_state = np.random.RandomState(rng.integers(2**32 - 1)).get_state()
    sampler.run_mcmc(start, steps, progress=False)
    chain = sampler.get_chain(discard=burn, flat=True)
    if not np.isfinite(sampler.get_log_prob(discard=burn)).all():
        raise MtmcalError("the history's scale sampler left the support: the campaigns are inconsistent")
    emcee_log = logging.getLogger("emcee")
    level, emcee_log.level = emcee_log.level, logging.ERROR  # the chain-length advice goes into the diagnostics
    try:
        tau = float(np.nanmax(sampler.get_autocorr_time(discard=burn, quiet=True)))
    finally:
        emcee_log.setLevel(level)
    pick = chain[np.linspace(0, len(chain) - 1, N_STATE).astype(int)]
    return pick, float(np.mean(sampler.acceptance_fraction)), tau, sampler.get_chain()[-1]


def trend_bayes_factors(hm: HistoryModel, q2: np.ndarray, s2: np.ndarray) -> np.ndarray:
    """log10 Bayes factor (d,) of "random walk + trend" against the model as it is, per deviation, from draws
    ``q2`` (n, d), ``s2`` (n, S) of the scales' posterior under the model as it is (module docstring)."""
    base = hm.log_marginal(q2, s2)
    var = _internal_scale(TREND_SCALE, hm.deviations) ** 2
    out = np.empty(hm.d)
    for j in range(hm.d):
        diff = hm.log_marginal_with_trend(q2, s2, j, var[j]) - base
        out[j] = (np.logaddexp.reduce(diff) - math.log(len(diff))) / math.log(10.0)
    return out


def fit(hm: HistoryModel, *, quantities, seed: int = 1, trend: str = "auto") -> HistoryFit:
    """Sample the scales, choose the trends (``trend="auto"``; ``"off"``: random walks only) and condition the
    states on the scales (see the module docstring) of ``quantities`` (the machine's names)."""
    if trend not in TREND_CHOICES:
        raise ParameterError("trend", f"{trend!r} (expected {' or '.join(TREND_CHOICES)})")
    rng = np.random.default_rng(seed)
    pick, acceptance, tau, last = _sample_scales(hm, rng)
    bf = {}
    if trend == "auto":
        log10_bf = trend_bayes_factors(hm, np.exp(2 * pick[:, :hm.d]), np.exp(2 * pick[:, hm.d:]))
        bf = dict(zip(hm.deviations, log10_bf.tolist()))
        keep = log10_bf > math.log10(TREND_BAYES_FACTOR)
        if keep.any():
            hm.set_trend(np.where(keep, _internal_scale(TREND_SCALE, hm.deviations) ** 2, 0.0))
            # the scales move little when a rate is added: the walkers go on from where they are, burn-in shorter
            pick, acceptance, tau, _ = _sample_scales(hm, rng, start=last, steps=RESAMPLE_STEPS, burn=RESAMPLE_BURN)
    q2, s2 = np.exp(2 * pick[:, :hm.d]), np.exp(2 * pick[:, hm.d:])
    names = [n for n in quantities if weights(n, hm.deviations)]
    W = np.array([[weights(n, hm.deviations).get(k, 0.0) for k in hm.deviations] for n in names])  # (k, d)
    disp = np.array([units.from_internal(1.0, quantity_unit(n)) for n in names])  # display per internal
    parts = [_condition(hm, q2[i:i + CHUNK], s2[i:i + CHUNK], W) for i in range(0, len(q2), CHUNK)]
    c = {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
    d1, d2 = disp, disp**2
    walk = np.einsum("kd,nd->nk", W**2, q2) * d2
    prior_k = np.sqrt(np.einsum("kd,d->k", W**2, hm.thermal_var)) * disp
    trend_info = {**bf, "trended": [n for n, v in zip(hm.deviations, hm.trend_var) if v > 0]}
    return HistoryFit(hm, names, q2, s2, c["mean"] * d1, np.sqrt(c["var"]) * d1, c["var"][:, -1] * d2, walk,
                      c["delta_mean"] * d1, np.sqrt(c["delta_var"]) * d1, acceptance, tau,
                      c["meas_mean"] * d1, np.sqrt(c["meas_var"]) * d1, c["rate_mean"] * d1, c["rate_var"] * d2,
                      c["last_rate_cov"] * d2, c["kappa_mean"] * d1, c["kappa_var"] * d2, prior_k, trend_info)


def _condition(hm: HistoryModel, q2: np.ndarray, s2: np.ndarray, W: np.ndarray) -> dict:
    """Per scale draw, the moments of the quantities ``W`` (k, d) of the augmented state, internal units."""
    m, P = hm.augmented_posterior(q2, s2)
    T, d = hm.T, hm.d
    k = T * d
    n = len(q2)
    mx = m[:, :k].reshape(n, T, d)
    Px = P[:, :k, :k].reshape(n, T, d, T, d)
    t = np.arange(T)
    block = Px[:, t, :, t, :].transpose(1, 0, 2, 3)  # (n, T, d, d): Cov(x_t, x_t)
    var = np.maximum(np.einsum("kd,ntde,ke->ntk", W, block, W), 0.0)
    cross = np.einsum("kd,ntde,ke->ntk", W, Px[:, t[:-1], :, t[1:], :].transpose(1, 0, 2, 3), W)
    r, kap = slice(k, k + d), slice(k + d, k + 2 * d)
    P_r, P_k = P[:, r, r], P[:, kap, kap]
    P_xk = P[:, :k, kap].reshape(n, T, d, d)  # Cov(x_t, κ)
    P_xr_last = P[:, (T - 1) * d:k, r]  # Cov(x_T, r)
    kappa_var = np.maximum(np.einsum("kd,nde,ke->nk", W, P_k, W), 0.0)
    x_k_cov = np.einsum("kd,ntde,ke->ntk", W, P_xk, W)
    dT = hm.dT[None, :, None]
    kappa_mean = np.einsum("nd,kd->nk", m[:, kap], W)
    mean = np.einsum("ntd,kd->ntk", mx, W)
    return {"mean": mean, "var": var,
            "delta_mean": mean[:, 1:] - mean[:, :-1],
            "delta_var": np.maximum(var[:, 1:] + var[:, :-1] - 2 * cross, 0.0),
            "meas_mean": mean + dT * kappa_mean[:, None, :],
            "meas_var": np.maximum(var + dT**2 * kappa_var[:, None, :] + 2 * dT * x_k_cov, 0.0),
            "rate_mean": np.einsum("nd,kd->nk", m[:, r], W),
            "rate_var": np.maximum(np.einsum("kd,nde,ke->nk", W, P_r, W), 0.0),
            "last_rate_cov": np.einsum("kd,nde,ke->nk", W, P_xr_last, W),
            "kappa_mean": kappa_mean, "kappa_var": kappa_var}


def forecast_moments(hf: HistoryFit, k: int, years: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and sd (n, len(years)) of quantity ``k`` (at 20 °C) ``years`` after the last campaign, per scale draw."""
    y = np.asarray(years, float)[None, :]
    mean = hf.mean[:, -1, k][:, None] + hf.rate_mean[:, k][:, None] * y
    var = (hf.last_var[:, k][:, None] + 2 * y * hf.last_rate_cov[:, k][:, None] + y**2 * hf.rate_var[:, k][:, None]
           + hf.walk_var[:, k][:, None] * y)
    return mean, np.sqrt(np.maximum(var, 0.0))


def prob_outside(mean: np.ndarray, sd: np.ndarray, low: float, high: float) -> np.ndarray:
    """Mixture probability (averaged over the first axis) of lying below ``low`` or above ``high``."""
    sd = np.maximum(sd, 1e-300)
    p = norm.cdf((low - mean) / sd) + norm.sf((high - mean) / sd)
    return p.mean(axis=0)


def changes(hf: HistoryFit, dates, thresholds: dict[str, float]) -> list[dict]:
    """Every (quantity, interval) with ``P(|Δ| > threshold)``; ``flagged`` where it passes ``1 − α/K``."""
    K = len(hf.quantities) * (len(dates) - 1)
    level = 1.0 - ALPHA / max(K, 1)
    out = []
    for i in range(len(dates) - 1):
        for k, n in enumerate(hf.quantities):
            thr = thresholds[n]
            p = float(prob_outside(hf.delta_mean[:, i, k], hf.delta_sd[:, i, k], -thr, thr))
            out.append({"quantity": n, "date": dates[i + 1], "probability": p,
                        "delta": float(hf.delta_mean[:, i, k].mean()), "threshold": thr, "flagged": p > level,
                        "level": level})
    return out


def recalibrate_by(hf: HistoryFit, k: int, low: float, high: float, *,
                   last: datetime.datetime) -> datetime.datetime | None:
    """First day (from the last campaign on) when the forecast probability of being outside [low, high] passes
    :data:`FORECAST_RISK`; None within :data:`HORIZON_YEARS`."""
    days = np.arange(0, int(HORIZON_YEARS * 365.25) + 1)
    years = days * 86400.0 / SECONDS_PER_YEAR
    m, sd = forecast_moments(hf, k, years)
    p = prob_outside(m, sd, low, high)
    hit = np.nonzero(p > FORECAST_RISK)[0]
    return None if len(hit) == 0 else last + datetime.timedelta(days=int(days[hit[0]]))


def check_history(campaigns) -> None:
    """A history needs two or more campaigns of one machine, each dated, on different dates."""
    if len(campaigns) < 2:
        got = f"; given one, {campaigns[0].source}" if campaigns else ""
        raise ParameterError("campaigns", f"a history needs at least two campaigns{got}")
    undated = [c.source for c in campaigns if c.date is None]
    if undated:
        raise MtmcalError(f"{undated[0]}: date: missing (a campaign of a history needs its top-level date = YYYY-MM-DD)")
    serials = sorted({c.machine.serial for c in campaigns})
    if len(serials) > 1:
        raise MtmcalError(f"the campaigns are of {len(serials)} machines ([machine] serial: {', '.join(map(repr, serials))});"
                          " a history is one machine's")
    from ..io.machine_identity import description_key

    keys = {}
    for c in campaigns:
        keys.setdefault(description_key(c.machine), c.source)
    if len(keys) > 1:
        raise MtmcalError(f"the campaigns of machine {serials[0]!r} describe {len(keys)} different machines "
                          f"({', '.join(keys.values())}); a history is one machine's, on one description")
    dates = [c.date for c in campaigns]
    if len(set(dates)) < len(dates):
        raise MtmcalError("two campaigns of the history have the same date")


def check_temperatures(campaigns) -> None:
    """Temperatures are modelled when every campaign has one; a history where only some have is an error naming
    the first campaign without (a missing reading is not 20 °C)."""
    have = [c.temperature_C is not None for c in campaigns]
    if any(have) and not all(have):
        first = next(c for c, h in zip(campaigns, have) if not h)
        raise MtmcalError(f"{first.source}: temperature_C: missing, while {sum(have)} of the history's "
                          f"{len(campaigns)} campaigns have one (give every campaign its temperature, or none)")
