"""Fit a machine's history: sample the drift rates and σ_model, then every quantity at every date, the changes
between dates, and the forecast against the tolerances.

* **Scales.** emcee (``vectorize=True``) samples ``log q_j`` (one drift rate per deviation, half-Cauchy prior of
  scale :data:`DRIFT_SCALE` per √year: small drift is expected, a crash must stay possible) and ``log σ``
  (σ_model's prior from the campaign) on the exact marginal likelihood of :class:`.model.HistoryModel`.
* **States.** For :data:`N_STATE` scale draws the states' Gaussian posterior is exact; quantities are linear
  combinations, so their means and variances are exact per draw and the posterior is the mixture.
* **Changes.** Between consecutive campaigns, ``P(|Δ| > threshold)`` from the mixture.  A change is flagged
  when that probability exceeds ``1 − α/K`` with K the number of (quantity, interval) pairs examined
  (Bonferroni): under the model the chance that a history with no change raises any flag is at most α.
* **Forecast.** At a future date the state is the last one plus a random-walk step, ``N(m_T, P_T + q²·Δτ)``;
  the probability of being out of tolerance is that mixture's mass outside; "recalibrate by" is the first
  date (daily grid, up to :data:`HORIZON_YEARS`) where it passes :data:`FORECAST_RISK`.
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
from ..parameters import IDENTIFIABLE, quantity_unit, weights
from .model import SECONDS_PER_YEAR, HistoryModel

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
N_STEPS = 1000
BURN = 300
#: the drift rates sampled span e^±LOG_RANGE around their prior scale (e^-2·LOG_RANGE below)
LOG_RANGE = 11.5


@dataclass(frozen=True)
class HistoryFit:
    """Draws of the scales, and per scale draw the mean (n, T, k) and sd (n, T, k) of each quantity."""

    model: HistoryModel
    quantities: list[str]
    q2: np.ndarray  # (n, d) drift rates², internal units per year
    s2: np.ndarray  # (n,) σ_model², mm²
    mean: np.ndarray  # (n, T, k) display units
    sd: np.ndarray  # (n, T, k)
    last_var: np.ndarray  # (n, k) variance at the last date, display units²
    walk_var: np.ndarray  # (n, k) random-walk variance per year of each quantity, display units²
    delta_mean: np.ndarray  # (n, T-1, k) change between consecutive campaigns
    delta_sd: np.ndarray  # (n, T-1, k)
    acceptance: float
    tau_max: float


def _log_prob_factory(hm: HistoryModel):
    scale = np.array([units.to_internal(DRIFT_SCALE[quantity_unit(n)], quantity_unit(n)) for n in hm.deviations])
    sig = hm.sigma_prior

    def log_prob(z: np.ndarray) -> np.ndarray:
        z = np.atleast_2d(z)
        q = np.exp(z[:, :-1])
        s = np.exp(z[:, -1])
        lp = np.sum(np.log(2.0 / (math.pi * scale)) - np.log1p((q / scale) ** 2) + z[:, :-1], axis=1)
        lp = lp + sig.frozen().logpdf(s) + z[:, -1]
        out = np.full(len(z), -np.inf)
        # a drift of 10⁵ times the prior scale or a σ_model of a millimetre is no machine: outside the support
        ok = np.isfinite(lp) & (z[:, :-1] < np.log(scale) + LOG_RANGE).all(axis=1) & (z[:, :-1] > np.log(scale) - 2 * LOG_RANGE).all(axis=1)
        ok &= (s < units.to_internal(1.0, "mm")) & (s > units.to_internal(1e-4, "um"))
        if ok.any():
            out[ok] = lp[ok] + hm.log_marginal(q[ok] ** 2, s[ok] ** 2)
        return out

    return log_prob, scale


def fit(hm: HistoryModel, *, seed: int = 1, quantities=IDENTIFIABLE) -> HistoryFit:
    """Sample the scales and condition the states on them (see the module docstring)."""
    log_prob, scale = _log_prob_factory(hm)
    dim = hm.d + 1
    walkers = WALKERS_PER_DIM * dim + (WALKERS_PER_DIM * dim) % 2
    rng = np.random.default_rng(seed)
    s0 = hm.sigma_prior.sd
    start = np.column_stack([np.log(scale * 0.3) + rng.normal(0, 0.5, (walkers, hm.d)),
                             math.log(s0) + rng.normal(0, 0.3, walkers)])
    sampler = emcee.EnsembleSampler(walkers, dim, log_prob, vectorize=True,
                                    moves=[(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)])
    sampler.random_state = np.random.RandomState(rng.integers(2**32 - 1)).get_state()
    sampler.run_mcmc(start, N_STEPS, progress=False)
    chain = sampler.get_chain(discard=BURN, flat=True)
    if not np.isfinite(sampler.get_log_prob(discard=BURN)).all():
        raise MtmcalError("the history's scale sampler left the support: the campaigns are inconsistent")
    emcee_log = logging.getLogger("emcee")
    level, emcee_log.level = emcee_log.level, logging.ERROR  # the chain-length advice goes into the diagnostics
    try:
        tau = float(np.nanmax(sampler.get_autocorr_time(discard=BURN, quiet=True)))
    finally:
        emcee_log.setLevel(level)
    pick = chain[np.linspace(0, len(chain) - 1, N_STATE).astype(int)]
    q2, s2 = np.exp(2 * pick[:, :-1]), np.exp(2 * pick[:, -1])
    names = [n for n in quantities if weights(n, hm.deviations)]
    W = np.array([[weights(n, hm.deviations).get(k, 0.0) for k in hm.deviations] for n in names])  # (k, d)
    disp = np.array([units.from_internal(1.0, quantity_unit(n)) for n in names])  # display per internal
    m, P = hm.state_posterior(q2, s2)  # (n, T, d), (n, Td, Td)
    T, d = hm.T, hm.d
    Pb = P.reshape(len(P), T, d, T, d)
    mean = np.einsum("ntd,kd->ntk", m, W) * disp
    var_t = np.einsum("kd,ntde,ke->ntk", W, Pb[:, np.arange(T), :, np.arange(T), :].transpose(1, 0, 2, 3), W)
    sd = np.sqrt(np.maximum(var_t, 0.0)) * disp
    cross = np.einsum("kd,ntde,ke->ntk", W, Pb[:, np.arange(T - 1), :, np.arange(1, T), :].transpose(1, 0, 2, 3), W)
    dvar = var_t[:, 1:] + var_t[:, :-1] - 2 * cross
    walk = np.einsum("kd,nd->nk", W**2, q2) * disp**2
    return HistoryFit(hm, names, q2, s2, mean, sd, var_t[:, -1] * disp**2, walk,
                      mean[:, 1:] - mean[:, :-1], np.sqrt(np.maximum(dvar, 0.0)) * disp,
                      float(np.mean(sampler.acceptance_fraction)), tau)


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
    m = hf.mean[:, -1, k][:, None]
    sd = np.sqrt(hf.last_var[:, k][:, None] + hf.walk_var[:, k][:, None] * years[None, :])
    p = prob_outside(m, sd, low, high)
    hit = np.nonzero(p > FORECAST_RISK)[0]
    return None if len(hit) == 0 else last + datetime.timedelta(days=int(days[hit[0]]))


def check_history(campaigns) -> None:
    """A history needs two or more campaigns of one machine, each dated, on different dates."""
    if len(campaigns) < 2:
        raise ParameterError("campaigns", "a history needs at least two campaigns")
    undated = [c.source for c in campaigns if c.date is None]
    if undated:
        raise MtmcalError(f"{undated[0]}: date: missing (a campaign of a history needs its top-level date = YYYY-MM-DD)")
    serials = sorted({c.machine.serial for c in campaigns})
    if len(serials) > 1:
        raise MtmcalError(f"the campaigns are of {len(serials)} machines ([machine] serial: {', '.join(map(repr, serials))});"
                          " a history is one machine's")
    dates = [c.date for c in campaigns]
    if len(set(dates)) < len(dates):
        raise MtmcalError("two campaigns of the history have the same date")
