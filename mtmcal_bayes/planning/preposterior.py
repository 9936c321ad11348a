"""Monte-Carlo preposterior check of the closed-form plan (SPEC §6).

:func:`realised_sd` simulates the data of a candidate from the current
posterior predictive (``sigma_model`` and the parameters drawn from the
posterior given the measured data, under σ_model's prior — learnt elsewhere where the planner
has one), runs the exact inference of
:class:`~mtmcal_bayes.inference.marginal.MarginalPosterior` on the campaign
plus the simulated run, and returns the root-mean-square posterior sd of each
target: what the candidate actually delivers on average, with ``sigma_model``
learnt from the data rather than fixed as in the closed form.
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..inference.marginal import MarginalPosterior
from .design import Planner


def current_posterior(planner: Planner) -> MarginalPosterior:
    """The exact σ-marginal posterior of the planner's campaign today (one scale, σ_model's prior — learnt elsewhere
    where the planner has one, :meth:`Planner.sigma_prior`), from which :func:`realised_sd` simulates: one for every
    candidate checked, so that its grid is factored once."""
    return MarginalPosterior(planner.A, planner.V - planner.sigma_model**2, planner.prior_var, planner.sigma_prior())


def realised_sd(planner: Planner, candidate_index: int, *, n_sim: int = 400, seed: int | None = 0,
                now: MarginalPosterior | None = None) -> dict:
    """Monte-Carlo preposterior of one candidate: current and realised target sds (display units).

    Returns ``{"sd_now": (t,), "sd_realised": (t,), "sd_realised_spread": (t,)}``: the exact
    posterior sd today, the root mean square of the realised posterior sd over ``n_sim``
    simulated outcomes, and the standard deviation of the realised sd across them.  ``now``: the planner's
    :func:`current_posterior`, when several candidates are checked (made here otherwise).
    """
    c = planner.candidates[candidate_index]
    if c.repeat_of is not None:
        raise ValueError("the Monte-Carlo check covers new runs; repeats change an existing run's noise only")
    rng = np.random.default_rng(seed)
    now = current_posterior(planner) if now is None else now
    base_var = planner.V - planner.sigma_model**2
    y = planner.observations.mean
    A_c, _ = planner.candidate_rows([c])[0]
    base_c = np.full(len(A_c), planner.noise_var(c.repeats) - planner.sigma_model**2)
    theta, sigma = now.draw(y, n_sim, rng)
    y_c = theta @ A_c.T + rng.normal(size=(n_sim, len(A_c))) * np.sqrt(base_c[None] + sigma ** 2)
    after = MarginalPosterior(np.vstack([planner.A, A_c]), np.concatenate([base_var, base_c]), planner.prior_var,
                              planner.sigma_prior())
    y_all = np.hstack([np.broadcast_to(y, (n_sim, len(y))), y_c])
    _, sd_after = after.target_moments(y_all, planner.T)
    _, sd_now = now.target_moments(y[None], planner.T)
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    return {"sd_now": sd_now[0] * scale, "sd_realised": np.sqrt(np.mean(sd_after**2, axis=0)) * scale,
            "sd_realised_spread": sd_after.std(axis=0) * scale}


__all__ = ["current_posterior", "realised_sd"]
