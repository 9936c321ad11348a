"""σ_model taught by a fleet: machines of one type share a hyper-distribution of their model-discrepancy scale.

A single campaign cannot learn σ_model (most of its interval widths are the assumed scale); a history can, since
the same machine measured again and again is redundant.  Machines of one type (``[machine] type``), measured
the same way, plausibly have similar discrepancies, so the fleet pools what their histories taught:

* **Each history's evidence.** With ``u = ln(σ / µm)``, a history's likelihood ``L_i(u)`` on one grid of u: the
  history model's exact marginal likelihood of its data at each σ, averaged over posterior draws of its drift
  rates (σ scales the scatter within campaigns, the rates the change between them, so the two are nearly
  separate).  Computed from the model, it has the right tails, which the history's own draws of σ — cut by
  the prior they were drawn under — do not.
* **Hierarchy.** ``u_i ~ N(μ, τ²)``: μ is the type's typical scale (its prior the single campaign's assumed
  σ_model prior, half-normal 2 µm, as a density of u), τ (half-normal prior of
  scale :data:`TAU_SCALE`) how much machines of the type differ.  The posterior of (μ, τ) is computed on a grid
  from ``Π_i ∫ L_i(u) N(u; μ, τ²) du``.
* **For a new machine.** Its scale's predictive ``p(u_new) = Σ p(μ, τ | y) N(u_new; μ, τ²)``, summarised as a
  log-normal (median ``e^{E u_new}`` µm, log sd ``sd(u_new)``) in the ``mtmcal-sigma-model-prior/1`` file that
  ``sample --sigma-model-prior`` reads.  When the machines do share σ_model, τ is small and the prior narrow;
  when they do not, τ is large and the prior says so.

Only histories teach: a machine with one campaign contributes nothing (its σ posterior is its prior).
"""

from __future__ import annotations

import math

import numpy as np

from .. import units

#: the grid of u = ln(σ / µm): 0.01 µm to 100 µm
U_GRID = np.linspace(math.log(0.01), math.log(100.0), 185)
#: half-normal scale of τ, the sd of ln σ between machines of one type (0.5: a factor 1.6 typical)
TAU_SCALE = 0.5
TAU_GRID = np.linspace(0.01, 2.5, 125)
#: posterior draws of a history's drift rates its likelihood of σ is averaged over
N_RATE_DRAWS = 20


def history_log_likelihood(hm, q2: np.ndarray) -> list[float]:
    """A history's log likelihood of u = ln(σ/µm) on :data:`U_GRID` (its maximum 0): the exact marginal likelihood of
    the history model (:meth:`~mtmcal_bayes.histories.model.HistoryModel.log_marginal`) at each σ, averaged over
    :data:`N_RATE_DRAWS` of the history's posterior draws of its drift rates ``q2`` (n, d)."""
    pick = q2[np.linspace(0, len(q2) - 1, min(N_RATE_DRAWS, len(q2))).astype(int)]
    s2 = units.to_internal(np.exp(U_GRID), "um") ** 2
    ll = hm.log_marginal(np.repeat(pick, len(s2), axis=0), np.tile(s2, len(pick))).reshape(len(pick), len(s2))
    ll = np.logaddexp.reduce(ll, axis=0)
    ll = ll - np.max(ll[np.isfinite(ll)])
    return [float(x) if np.isfinite(x) else None for x in ll]  # None: no likelihood there (JSON has no −inf)


def pool(log_likelihoods: list[list[float | None]]) -> dict:
    """The type's hyper-posterior and a new machine's predictive from ≥ 1 histories' :func:`history_log_likelihood`.

    Returns ``median_um`` and ``log_sd`` (the predictive's log-normal), ``mu`` and ``tau`` (posterior mean and sd
    of each, ln µm) and ``histories``."""
    L = np.array([[-np.inf if x is None else x for x in row] for row in log_likelihoods])  # (N, G)
    # p(y_i | μ, τ) on (μ = U_GRID, τ = TAU_GRID): Σ_u L_i(u) N(u; μ, τ²) du
    lik = np.exp(L)  # (N, u), each scaled to max 1
    diff = U_GRID[None, :] - U_GRID[:, None]  # (μ, u)
    per = np.stack([lik @ _kernel(diff, t).T for t in TAU_GRID], axis=-1)  # (N, μ, τ)
    with np.errstate(divide="ignore"):
        log_post = np.log(per).sum(axis=0) - 0.5 * (TAU_GRID / TAU_SCALE) ** 2 + _log_mu_prior()[:, None]  # (μ, τ)
    log_post -= np.max(log_post)
    w = np.exp(log_post)
    w /= w.sum()
    mu_m = float(np.sum(w.sum(axis=1) * U_GRID))
    mu_sd = float(math.sqrt(np.sum(w.sum(axis=1) * (U_GRID - mu_m) ** 2)))
    tau_m = float(np.sum(w.sum(axis=0) * TAU_GRID))
    tau_sd = float(math.sqrt(np.sum(w.sum(axis=0) * (TAU_GRID - tau_m) ** 2)))
    # the predictive of a new machine's u: mean μ, variance τ² + the spread of μ
    mean = mu_m
    var = float(np.sum(w * (TAU_GRID[None, :] ** 2 + (U_GRID[:, None] - mu_m) ** 2)))
    return {"median_um": math.exp(mean), "log_sd": math.sqrt(var), "mu": {"mean": mu_m, "sd": mu_sd},
            "tau": {"mean": tau_m, "sd": tau_sd}, "histories": len(log_likelihoods)}


def _log_mu_prior() -> np.ndarray:
    """log prior of μ on :data:`U_GRID`: the single campaign's assumed σ_model prior (half-normal, 2 µm) as a
    density of u = ln(σ/µm).  A flat μ slid towards 0.01 µm wherever the histories only bound σ from above (σ at
    or below the instrument's accuracy), and the new machines' intervals then covered 84 % for 90 %."""
    from scipy import stats

    from ..inference.priors import DEFAULTS

    kind, scale_um, _ = DEFAULTS["sigma_model"]
    return stats.halfnorm(scale=scale_um).logpdf(np.exp(U_GRID)) + U_GRID  # density in σ (µm), times dσ/du = σ


def _kernel(diff: np.ndarray, tau: float) -> np.ndarray:
    """N(u; μ, τ²) on the grid (μ, u), each row summing to 1: a τ narrower than the grid step is the value at μ,
    not a quadrature error."""
    k = np.exp(-0.5 * (diff / tau) ** 2)
    return k / k.sum(axis=1, keepdims=True)


def geometry(machine) -> tuple:
    """What machines of one type must share: their configuration and axis travels."""
    return machine.configuration, tuple(sorted(machine.travel.items()))
