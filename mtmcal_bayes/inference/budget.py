"""Uncertainty budget: what share of each quantity's posterior variance comes from which source (GUM budget).

For the linear-Gaussian posterior at a fixed sigma_model the decomposition is exact.  With prior
precision ``P = Σ_g P_g`` (one block per prior group g), noise ``V = Σ_k R_k`` (repeatability,
instrument accuracy, sigma_model², probe readings), posterior covariance ``Σ = (P + AᵀV⁻¹A)⁻¹`` and gain
``K = Σ AᵀV⁻¹``,

    Σ = Σ P Σ + K V Kᵀ = Σ_g Σ P_g Σ + Σ_k K R_k Kᵀ,

so a quantity ``aᵀθ`` has variance ``Σ_g aᵀΣP_gΣa + Σ_k aᵀK R_k Kᵀa``: each term is that source's
contribution, and they add up to the posterior variance.

Each instrument has its own discrepancy scale (``sigma_model`` for the ball bar, ``sigma_model_probe`` for
the touch probe), and each is a source of its own: its ``R_k`` is σ_k² on that instrument's observations.

For sampled scales the law of total variance splits the posterior variance into the average of
these budgets over the scales' posterior and the variance of the conditional mean,
``Var(aᵀθ) = E_σ[Var(aᵀθ | σ)] + Var_σ(E[aᵀθ | σ])``: the last term is ``sigma_model_uncertainty``, what
not knowing the scales adds.  The average runs over :data:`N_SIGMA` quantiles of the posterior draws of
one scale, or :data:`N_SIGMA` posterior draws of several (evenly spaced through the chain).  The kinematic
models are linearised at the posterior mean (the budget is then first order).

The budget states where each sampled scale's prior comes from (:func:`sigma_prior_sources`): *assumed* (the
package's default, or the campaign's ``[priors]``) or *learnt* elsewhere (a fleet of machines of the type,
``--sigma-model-prior``), with the source the prior file names — a share of σ_model then rests on that source.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import units
from ..parameters import SCALE_LABEL, quantity_unit, weights
from .analytic import linearisation, reported
from .log_posterior import LogPosterior

#: quantiles of sigma_model's posterior the budget is averaged over
N_SIGMA = 64
#: the noise sources, in display order (the probe's only with probe data)
NOISE_SOURCES = ("repeatability", "instrument", "probe readings", "R-test readings", "sigma_model",
                 "sigma_model_probe", "sigma_model_rtest")
#: prior groups of the nuisance parameters, by base name (``prior:<group>`` in the budget)
PRIOR_GROUP = {"xT": "T-ball centring", "yT": "T-ball centring", "zT": "T-ball centring", "dRB": "dRB",
               "xW": "W-ball clamping", "yW": "W-ball clamping", "zW": "W-ball clamping",
               "xS": "stylus centring", "yS": "stylus centring", "zS": "stylus centring", "dRS": "dRS", "rS": "rS",
               "xP": "sphere placement", "yP": "sphere placement", "zP": "sphere placement",
               "xD": "reading datum", "yD": "reading datum", "zD": "reading datum",
               "xZR": "R-test zero", "yZR": "R-test zero", "zZR": "R-test zero",
               "xPR": "R-test sphere placement", "yPR": "R-test sphere placement", "zPR": "R-test sphere placement",
               "xNR": "R-test nest centring", "yNR": "R-test nest centring", "zNR": "R-test nest centring",
               "dLR": "R-test nest length"}
#: what each source is, for sentences ("87 % of the variance comes from …")
MEANING = {"repeatability": "the repeatability of the measurements (scatter of the repeats)",
           "instrument": "the ball bar's accuracy", "probe readings": "the touch-probe readings' own noise",
           "sigma_model": "the assumed model-discrepancy scale σ_model of the ball bar",
           "sigma_model_probe": "the assumed model-discrepancy scale of the touch probe, σ_model (probe)",
           "sigma_model_uncertainty": "not knowing σ_model (its prior, which the data barely narrow)",
           "prior:deviations": "the priors of the deviations themselves",
           "prior:T-ball centring": "the T-ball centring prior (±1 µm centring check)",
           "prior:dRB": "the tool-length prior dRB (dial gauge, 10 µm)",
           "prior:W-ball clamping": "the W-ball clamping prior", "prior:stylus centring": "the stylus centring prior",
           "prior:dRS": "the stylus-length prior", "prior:rS": "the stylus-radius (pre-travel) prior",
           "prior:sphere placement": "the sphere-placement prior", "prior:reading datum": "the reading-datum prior",
           "R-test readings": "the R-test readings' own noise",
           "sigma_model_rtest": "the assumed model-discrepancy scale of the R-test, σ_model (R-test)",
           "prior:R-test zero": "the R-test zero prior (broad)",
           "prior:R-test sphere placement": "the R-test sphere-placement prior",
           "prior:R-test nest centring": "the R-test nest-centring prior",
           "prior:R-test nest length": "the R-test nest-length prior"}


def sigma_prior_sources(post: LogPosterior) -> dict[str, dict]:
    """Where the prior of each sampled discrepancy scale comes from: ``{scale: {"source": "assumed" | "learnt",
    "prior": "LogNormal(median 2.7 µm, log sd 0.2)", "from": <the learnt prior's source text> or None}}``; empty when
    the scales are fixed."""
    learnt = post.sigma_prior.scales if post.sigma_prior is not None else {}
    out = {}
    for q in post.priors.priors[post.p:]:
        out[q.name] = {"source": "learnt" if q.name in learnt else "assumed", "prior": q.describe(),
                       "from": post.sigma_prior.source if q.name in learnt else None}
    return out


def sigma_prior_sentence(post: LogPosterior) -> str:
    """One sentence stating each sampled scale's prior and its source (empty when the scales are fixed):
    "σ_model (ball bar) prior: learnt elsewhere, LogNormal(median 2.7 µm, log sd 0.2), from fleet plant/: …"."""
    parts = []
    for name, s in sigma_prior_sources(post).items():
        where = "set in the campaign's [priors]" if name in post.campaign.priors else "the default"
        how = (f"learnt elsewhere, {s['prior']}, from {s['from']}" if s["source"] == "learnt" else
               f"assumed, {s['prior']} ({where}; not learnt from data)")
        parts.append(f"{SCALE_LABEL[name]} prior: {how}")
    return "; ".join(parts) + ("." if parts else "")


def meaning(source: str, post: LogPosterior | None = None) -> str:
    """What a budget source is, for sentences (:data:`MEANING`); a scale whose prior was learnt elsewhere is not
    called assumed."""
    text = MEANING.get(source, source)
    if post is not None and post.sigma_prior is not None and source in post.sigma_prior.scales:
        text = text.replace("the assumed ", "the ") + " (its prior learnt elsewhere)"
    return text


def source_of(parameter) -> str:
    """Budget source of a parameter's prior: ``prior:deviations`` or ``prior:<nuisance group>``."""
    return "prior:deviations" if parameter.group == "deviation" else f"prior:{PRIOR_GROUP[parameter.base]}"


def _weight_matrix(names, space_names) -> np.ndarray:
    """``(q, p)``: each quantity of ``names`` as weights on the parameters ``space_names``."""
    rows = [weights(n, space_names) for n in names]
    return np.array([[w.get(k, 0.0) for k in space_names] for w in rows]).reshape(len(rows), len(space_names))


def _budgets(post: LogPosterior, grid: np.ndarray, names, theta0: np.ndarray | None):
    """The variance contributions at each row of ``grid`` (``(g, s)`` scales, mm) in one batch: ``(sources,
    contributions (g, q, sources), means (g, q))``, internal units (see :func:`conditional_budget`)."""
    p = post.p
    priors = post.priors.priors[:p]
    var0 = np.array([q.sd for q in priors]) ** 2
    mu0 = np.array([q.centre for q in priors])
    A, c = linearisation(post, theta0)
    g, m = len(grid), A.shape[0]
    noise = {k: np.broadcast_to(np.asarray(r, float), (g, m)) for k, r in post.likelihood.noise.items()}
    for k, name in enumerate(post.scales):
        noise[name] = np.where(post.scale_of == k, grid[:, k, None] ** 2, 0.0)  # (g, m)
    V = sum(noise.values())  # (g, m)
    cov = np.linalg.inv(np.diag(1.0 / var0) + np.einsum("mi,gm,mj->gij", A, 1.0 / V, A))  # (g, p, p)
    cov = 0.5 * (cov + cov.transpose(0, 2, 1))
    mean = np.einsum("gij,gj->gi", cov, mu0 / var0 + ((post.likelihood.y - c) / V) @ A)  # (g, p)
    W = _weight_matrix(names, list(post.space.names))  # (q, p)
    H = np.einsum("qi,gij->gqj", W, cov)  # (g, q, p): aᵀΣ
    G = (H @ A.T) / V[:, None, :]  # (g, q, m): aᵀK
    out = {k: np.einsum("gqm,gm->gq", G**2, r) for k, r in noise.items()}
    for j, param in enumerate(post.space.parameters):
        key = source_of(param)
        out[key] = out.get(key, 0.0) + H[:, :, j] ** 2 / var0[j]
    sources = list(out)
    return sources, np.stack([out[k] for k in sources], axis=-1), mean @ W.T


def _scale_grid(post: LogPosterior, sigma_model) -> np.ndarray:
    """``(1, s)``: one value of the discrepancy scales (one for all, or one per scale of ``post.scales``)."""
    return np.broadcast_to(np.asarray(sigma_model, dtype=float), (len(post.scales),))[None, :]


def conditional_budget(post: LogPosterior, sigma_model, names, *,
                       theta0: np.ndarray | None = None) -> tuple[pd.DataFrame, pd.Series]:
    """Variance contributions at fixed discrepancy scales ``sigma_model`` (mm; one value for all, or one per scale of
    ``post.scales``): a DataFrame (quantity × source, internal units²) whose rows sum to the posterior variance, and
    the posterior mean of each quantity (internal units).

    Exact for the ``linear`` model; other models linearised at ``theta0``.  Every prior is taken as a normal
    of its mean and sd (the half-normal/uniform overrides as in the sampler's start)."""
    sources, parts, means = _budgets(post, _scale_grid(post, sigma_model), names, theta0)
    return pd.DataFrame(parts[0], index=list(names), columns=sources), pd.Series(means[0], index=list(names))


def variance_budget(post: LogPosterior, sigma_draws: np.ndarray | None, names=None, *,
                    theta0: np.ndarray | None = None) -> pd.DataFrame:
    """Shares of the posterior variance by source (rows: quantities, columns: sources; rows sum to 1).

    ``sigma_draws`` (mm): posterior draws of the scales, ``(n,)`` or ``(n, s)``, averaged over by the law of total
    variance (adds the ``sigma_model_uncertainty`` column); None when the scales are fixed (``post.fixed_sigma``).
    The :data:`N_SIGMA` conditional budgets are computed in one batch.
    """
    names = [n for n in (names or reported(post)) if weights(n, post.space.names)]
    if sigma_draws is None:
        var, _ = conditional_budget(post, float(post.fixed_sigma or 0.0), names, theta0=theta0)
        var["sigma_model_uncertainty"] = 0.0
    else:
        draws = np.asarray(sigma_draws, float).reshape(len(sigma_draws), -1)
        if draws.shape[1] == 1:
            grid = np.quantile(draws[:, 0], (np.arange(N_SIGMA) + 0.5) / N_SIGMA)[:, None]
        else:  # several scales: their joint draws, evenly spaced through the chain
            grid = draws[np.linspace(0, len(draws) - 1, N_SIGMA).astype(int)]
        sources, parts, means = _budgets(post, grid, names, theta0)
        var = pd.DataFrame(parts.mean(axis=0), index=names, columns=sources)
        var["sigma_model_uncertainty"] = np.var(means, axis=0)
    return var.div(var.sum(axis=1), axis=0)


def dominant(shares: pd.Series) -> tuple[str, float]:
    """The source with the largest share, and the share."""
    return str(shares.idxmax()), float(shares.max())


def linearisation_point(idata, post: LogPosterior) -> np.ndarray | None:
    """Where a kinematic model is linearised for the budget: the posterior mean of its parameters (internal
    units, from ``idata``'s display-unit draws); None for the ``linear`` model, which is linear."""
    if post.model_name == "linear":
        return None
    return np.array([units.to_internal(float(idata.posterior[n].mean()), quantity_unit(n)) for n in post.space.names])


def sd_against_sigma(post: LogPosterior, sigma_grid: np.ndarray, names, *,
                     theta0: np.ndarray | None = None) -> pd.DataFrame:
    """Posterior sd of each quantity (display units) at each fixed sigma_model of ``sigma_grid`` (mm): rows the
    grid, columns ``names``; closed form (kinematic models linearised at ``theta0``), in one batch."""
    names = [n for n in names if weights(n, post.space.names)]
    sigma = np.asarray(sigma_grid, float)
    _, parts, _ = _budgets(post, np.repeat(sigma[:, None], len(post.scales), axis=1), names, theta0)
    sd = np.sqrt(parts.sum(axis=-1))  # (g, q)
    return pd.DataFrame({n: units.from_internal(sd[:, i], quantity_unit(n)) for i, n in enumerate(names)},
                        index=units.from_internal(sigma, "um"))