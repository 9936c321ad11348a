"""Histories on a kinematic model (``htm-thesis``, ``htm-literal``): each campaign linearised where the machine was.

The history model is linear-Gaussian (:mod:`.model`).  A kinematic forward model enters it through its
first-order expansion: first at the prior centre, which gives the history's estimate of the deviations at each
date; then each campaign again at that estimate (its deviations as measured, at the campaign's temperature;
the set-up offsets at their prior centres), and the history is fitted once more.  The check then draws
parameters around each campaign's point (its deviations from their posterior, the offsets from their priors)
and compares the nonlinear model with its expansion: the largest difference, against the instrument's
accuracy, is stated with the result.
"""

from __future__ import annotations

import numpy as np

from .. import units
from .fit import HistoryFit, fit
from .model import HistoryModel

#: scale draws whose state posterior gives the points of expansion
N_POINT_DRAWS = 50
#: parameter draws per campaign in the check of the expansion
N_CHECK = 200


def estimate_points(hm: HistoryModel, hf: HistoryFit) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per campaign the parameter vector (internal units, the campaign's order) at the history's estimate, and
    the sd (p,) of each parameter there (deviations: their posterior sd; set-up offsets: their prior sd)."""
    q2, s2 = hf.q2[:N_POINT_DRAWS], hf.s2[:N_POINT_DRAWS]
    m, P = hm.augmented_posterior(q2, s2)
    T, d = hm.T, hm.d
    k = T * d
    x = m[:, :k].reshape(-1, T, d)
    kappa = m[:, k + d:k + 2 * d]
    measured = (x + hm.dT[None, :, None] * kappa[:, None, :]).mean(axis=0)  # (T, d)
    var_x = np.diagonal(P[:, :k, :k], axis1=1, axis2=2).reshape(-1, T, d)
    sd_x = np.sqrt(var_x.mean(axis=0) + x.var(axis=0))
    points, sds = [], []
    for t, post in enumerate(hm.posts):
        params = post.space.parameters
        prior = post.priors.priors
        theta = np.array([prior[i].centre for i in range(post.p)], float)
        sd = np.array([prior[i].sd for i in range(post.p)], float)
        names = [p.name for p in params]
        cols = [names.index(n) for n in hm.deviations]
        theta[cols] = measured[t]
        sd[cols] = sd_x[t]
        points.append(theta)
        sds.append(sd)
    return points, sds


def expansion_gap(hm: HistoryModel, points, sds, seed: int = 0) -> float:
    """The largest difference (mm) between each campaign's kinematic model and its expansion at its point, over
    :data:`N_CHECK` parameter draws around it (Gaussian, the sds of :func:`estimate_points`)."""
    from ..inference.analytic import linearisation

    rng = np.random.default_rng(seed)
    gap = 0.0
    for post, theta0, sd in zip(hm.posts, points, sds):
        A, c = linearisation(post, theta0)
        theta = theta0 + sd * rng.standard_normal((N_CHECK, len(theta0)))
        nonlinear = post.forward.predict(theta)  # (n, m)
        gap = max(gap, float(np.max(np.abs(nonlinear - (c + theta @ A.T)))))
    return gap


def linearised_history(campaigns, model: str, *, seed: int, trend: str,
                       data: str | None = None) -> tuple[HistoryModel, HistoryFit, dict]:
    """The history on ``model`` linearised at its own estimate (module docstring); returns the model, the fit and
    the check ``{"model", "points", "max_gap_um", "accuracy_um", "ok"}``."""
    from .quantities import history_quantities

    first = HistoryModel(campaigns, model, data=data)
    names, _ = history_quantities(campaigns, first.posts, first.deviations)
    points, _ = estimate_points(first, fit(first, seed=seed, trend=trend, quantities=names))
    hm = HistoryModel(campaigns, model, points=points, data=data)
    hf = fit(hm, seed=seed, trend=trend, quantities=names)
    points, sds = estimate_points(hm, hf)
    gap = expansion_gap(hm, points, sds, seed=seed)
    accuracy = min(c.ballbar.accuracy for c in campaigns)
    return hm, hf, {"model": model, "points": "each campaign at the history's estimate of its deviations",
                    "max_gap_um": units.from_internal(gap, "um"), "accuracy_um": units.from_internal(accuracy, "um"),
                    "ok": bool(gap <= accuracy)}
