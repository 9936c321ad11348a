"""Checks a posterior owes its reader: does the linear model's first order hold, what dx_BT = 0 would change."""

from __future__ import annotations

import pandas as pd

from .. import units
from ..inference.analytic import gaussian_posterior
from ..inference.log_posterior import LogPosterior
from ..inference.sampling import SamplingResult
from ..models import first_order_gap
from ..parameters import weights


def linear_model_check(result: SamplingResult) -> list[str]:
    """A warning when the linear model's first order does not hold at the deviations found.

    At the posterior mean, the kinematic model ``htm-thesis`` (whose first order is the
    linear model) is compared with the linear model; a difference above the instrument
    accuracy means the deviations are too large for the linear model (thesis
    magnitudes leave 0.06 µm, deviations of a degree millimetres).
    """
    post = result.posterior
    if post.model_name != "linear":
        return []
    theta = result.chains.reshape(-1, result.chains.shape[-1])[:, : post.p].mean(axis=0)
    gap = first_order_gap(post.campaign, theta, post.space)
    accuracy = post.campaign.ballbar.accuracy
    if gap <= accuracy:
        return []
    return [f"the linear model is first order and the deviations found are too large for it: at the posterior "
            f"mean the kinematic model htm-thesis predicts eccentricities up to {units.from_internal(gap, 'um'):.1f} µm "
            f"away from it (instrument accuracy {units.from_internal(accuracy, 'um'):g} µm); use the htm-thesis model"]


def thesis_assumption_effect(campaign, model: str = "linear", sigma_model_um: float = 0.3) -> pd.DataFrame:
    """beta_XB and dx_CZ − dx_BT with and without dx_BT = 0, closed form (linearised) at fixed sigma_model.

    Columns: mean and sd of each quantity, by default and with the thesis' Eq 4.2 assumption.
    """
    sigma = units.to_internal(sigma_model_um, "um")
    rows = {}
    for label, fix in (("default", False), ("dx_BT = 0", True)):
        g = gaussian_posterior(LogPosterior(campaign, model, fix_dx_BT=fix, sigma_model=sigma),
                               sigma_model=sigma, allow_non_normal=True)
        b_mean, b_sd = g.linear_combination(weights("beta_XB"))
        d_mean, d_sd = g.linear_combination(weights("dx_CZ_minus_dx_BT", g.names))
        rows[label] = {"beta_XB mean ″": units.from_internal(b_mean, "arcsec"),
                       "beta_XB sd ″": units.from_internal(b_sd, "arcsec"),
                       "dx_CZ_minus_dx_BT mean µm": units.from_internal(d_mean, "um"),
                       "dx_CZ_minus_dx_BT sd µm": units.from_internal(d_sd, "um")}
    return pd.DataFrame(rows).T
