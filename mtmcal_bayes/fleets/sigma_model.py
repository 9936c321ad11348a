"""σ_model taught by a fleet: machines of one type share a hyper-distribution of their model-discrepancy scale.

A single campaign cannot learn σ_model (most of its interval widths are the assumed scale); a history can, since
the same machine measured again and again is redundant.  Machines of one type (``[machine] type``), measured
the same way, plausibly have similar discrepancies, so the fleet pools what their histories taught:

* **Each history's evidence.** With ``u = ln(σ / µm)`` and ``v = ln κ``, a history's likelihood ``L_i(u, v)`` on
  one grid: the history model's exact marginal likelihood of its data with σ_model ``e^u`` µm and every
  deviation's drift rate ``κ·s_j`` (``s_j`` its half-Cauchy scale in the history model,
  :func:`~mtmcal_bayes.histories.fit.drift_scale`): one drift scale κ per machine, its rates tied.
* **Drift is learnt with σ.** σ scales a discrepancy drawn afresh in every campaign, the drift rates the change
  of the deviations between campaigns, and in a short history the two look alike: integrated against the
  history model's own rate prior (ten independent half-Cauchy rates, 5 per √year each), the likelihood of σ of
  four quarterly campaigns without drift peaks at 0.73 µm for a true 1 µm (1.0 with the rates fixed at 0;
  docs/fleet.md).  Machines of one type drift alike as they err alike, so the type learns its drift scale too:
  each machine's ``κ_i ~ half-Cauchy(κ_T)`` (the heavy tail lets one machine drift more than the others), the
  type's ``κ_T ~ half-Cauchy(1)`` (``κ_T = 1``: each rate half-Cauchy of its own scale, the history model's prior).
* **Hierarchy.** ``u_i ~ N(μ, τ²)``: μ is the type's typical scale (its prior the single campaign's assumed
  σ_model prior, half-normal 2 µm, as a density of u), τ (half-normal prior of scale :data:`TAU_SCALE`) how
  much machines of the type differ.  The posterior of (κ_T, τ, μ) is computed on a grid from
  ``Π_i ∫∫ L_i(u, v) N(u; μ, τ²) p(v | κ_T) du dv``.
* **For a new machine.** Its scale's predictive ``p(u_new) = Σ p(μ, τ | y) N(u_new; μ, τ²)``, summarised as a
  log-normal (median ``e^{E u_new}`` µm, log sd ``sd(u_new)``) in the ``mtmcal-sigma-model-prior/1`` file that
  ``sample --sigma-model-prior`` reads.  When the machines do share σ_model, τ is small and the prior narrow;
  when they do not, τ is large and the prior says so.

Only histories teach: a machine with one campaign contributes nothing (its σ posterior is its prior).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .. import units
from ..io.machine_identity import description_key

#: the grid of u = ln(σ / µm): 0.01 µm to 100 µm
U_GRID = np.linspace(math.log(0.01), math.log(100.0), 185)
#: half-normal scale of τ, the sd of ln σ between machines of one type (0.5: a factor 1.6 typical)
TAU_SCALE = 0.5
TAU_GRID = np.linspace(0.01, 2.5, 125)
#: the grid of v = ln κ, a machine's drift scale as a factor on the history model's rate scales: 10⁻³ (no drift to
#: speak of) to 100 (a crash every quarter); the cells' outer edges are 0 and ∞
V_GRID = np.linspace(math.log(1e-3), math.log(100.0), 41)
#: half-Cauchy scale of the type's drift scale κ_T (1: the history model's own prior of each rate)
DRIFT_TYPE_SCALE = 1.0


def history_log_likelihood(hm) -> list[list[float | None]]:
    """A history's log likelihood ``(len(V_GRID), len(U_GRID))`` of (v = ln κ, u = ln σ/µm), its maximum 0: the
    exact marginal likelihood of the history model (``HistoryModel.log_marginal_grid``) with σ_model ``e^u`` µm
    and the drift rates ``e^v·s`` (``s``: :func:`~mtmcal_bayes.histories.fit.drift_scale`).  ``None`` where there
    is no likelihood (JSON has no −inf)."""
    from ..histories.fit import drift_scale  # the histories are imported when first needed (.units)

    q = np.exp(V_GRID)[:, None] * drift_scale(hm.deviations)[None, :]  # (K, d)
    s2 = units.to_internal(np.exp(U_GRID), "um") ** 2
    ll = hm.log_marginal_grid(q**2, s2)
    ll = ll - np.max(ll[np.isfinite(ll)])
    return [[float(x) if np.isfinite(x) else None for x in row] for row in ll]


def pool(log_likelihoods: list) -> dict:
    """The type's hyper-posterior and a new machine's predictive from ≥ 1 histories' :func:`history_log_likelihood`
    (each ``(len(V_GRID), len(U_GRID))``).

    Returns ``median_um`` and ``log_sd`` (the predictive's log-normal), ``mu`` and ``tau`` (posterior mean and sd
    of each, ln µm), ``drift_scale`` (posterior mean and sd of ln κ_T) and ``histories``."""
    kernels = np.stack([_kernel(U_GRID[None, :] - U_GRID[:, None], t) for t in TAU_GRID])  # (τ, μ, u)
    drift = _half_cauchy_cells(np.exp(V_GRID))  # (κ_T, κ_i): a machine's drift scale given the type's
    with np.errstate(divide="ignore"):
        log_post = (np.log(_half_cauchy_cells(DRIFT_TYPE_SCALE))[:, None, None]
                    - 0.5 * (TAU_GRID / TAU_SCALE)[None, :, None] ** 2 + _log_mu_prior()[None, None, :])  # (κ_T, τ, μ)
    for table in log_likelihoods:
        L = np.array([[-np.inf if x is None else x for x in row] for row in table])  # (κ_i, u), its maximum 0
        # the machine's drift scale integrated given the type's, (κ_T, u), then its σ given (μ, τ): Σ_u L N(u; μ, τ²)
        lik = drift @ np.exp(L)
        with np.errstate(divide="ignore"):
            log_post += np.log(lik @ kernels.reshape(-1, len(U_GRID)).T).reshape(log_post.shape)
    log_post -= np.max(log_post)
    w = np.exp(log_post)
    w /= w.sum()
    mu_m, mu_sd = _moments(w.sum(axis=(0, 1)), U_GRID)
    tau_m, tau_sd = _moments(w.sum(axis=(0, 2)), TAU_GRID)
    v_m, v_sd = _moments(w.sum(axis=(1, 2)), V_GRID)
    # the predictive of a new machine's u: mean μ, variance τ² + the spread of μ
    var = float(np.sum(w.sum(axis=0) * (TAU_GRID[:, None] ** 2 + (U_GRID[None, :] - mu_m) ** 2)))
    return {"median_um": math.exp(mu_m), "log_sd": math.sqrt(var), "mu": {"mean": mu_m, "sd": mu_sd},
            "tau": {"mean": tau_m, "sd": tau_sd}, "drift_scale": {"mean": v_m, "sd": v_sd},
            "histories": len(log_likelihoods)}


def _moments(w: np.ndarray, grid: np.ndarray) -> tuple[float, float]:
    """Mean and sd of a grid's normalised weights."""
    m = float(np.sum(w * grid))
    return m, float(math.sqrt(np.sum(w * (grid - m) ** 2)))


def _half_cauchy_cells(scale) -> np.ndarray:
    """P(κ in each cell of :data:`V_GRID`) under half-Cauchy(``scale``), cells between the grid's midpoints, the first
    from 0, the last to ∞: ``(len(V_GRID),)`` for one scale, ``(len(scale), len(V_GRID))`` for an array of them."""
    edges = np.concatenate([[0.0], np.exp(0.5 * (V_GRID[1:] + V_GRID[:-1])), [np.inf]])
    return np.diff(stats.halfcauchy.cdf(edges / np.asarray(scale, float)[..., None]), axis=-1)


def _log_mu_prior() -> np.ndarray:
    """log prior of μ on :data:`U_GRID`: the single campaign's assumed σ_model prior (half-normal, 2 µm) as a
    density of u = ln(σ/µm).  Where the histories bound σ mainly from above (σ at the instrument's accuracy) it keeps
    μ off the grid's floor: with a flat μ, fleets at 0.5 µm pooled to 0.29 µm (log sd 0.79), with it to 0.40 µm
    (0.59); the new machines' coverage was the same within its noise (bench/fleet_sigma.py, docs/fleet.md)."""
    from ..inference.priors import DEFAULTS

    kind, scale_um, _ = DEFAULTS["sigma_model"]
    return stats.halfnorm(scale=scale_um).logpdf(np.exp(U_GRID)) + U_GRID  # density in σ (µm), times dσ/du = σ


def _kernel(diff: np.ndarray, tau: float) -> np.ndarray:
    """N(u; μ, τ²) on the grid (μ, u), each row summing to 1: a τ narrower than the grid step is the value at μ,
    not a quadrature error."""
    k = np.exp(-0.5 * (diff / tau) ** 2)
    return k / k.sum(axis=1, keepdims=True)


def geometry(machine) -> tuple:
    """What machines of one type must share: their description (its key), configuration and axis travels."""
    return description_key(machine), machine.configuration, tuple(sorted(machine.travel.items()))
