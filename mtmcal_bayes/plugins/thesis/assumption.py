"""The thesis' assumption dx_BT = 0 (Eq 4.2): what it changes in a posterior that does not impose it (beta_XB and
dx_CZ − dx_BT with and without it, closed form), for ``sample``'s notes and the report's section of the thesis
values (``thesis_assumption_dx_BT.csv``)."""

from __future__ import annotations

import pandas as pd

from ... import units
from ...analysis import CampaignAnalysis, analysis_of
from ...inference.analytic import gaussian_posterior
from ...parameters import weights


def assumption_effect(campaign, model: str = "linear", sigma_model_um: float = 0.3,
                      data: str = "ballbar") -> pd.DataFrame:
    """beta_XB and dx_CZ − dx_BT with and without dx_BT = 0, closed form (linearised) at fixed sigma_model.

    Columns: mean and sd of each quantity, by default and with the thesis' Eq 4.2 assumption.  ``campaign`` may
    be a :class:`~mtmcal_bayes.analysis.CampaignAnalysis` (its model and data are then used).
    """
    sigma = units.to_internal(sigma_model_um, "um")
    if isinstance(campaign, CampaignAnalysis):
        model, data = campaign.model, campaign.data
    analysis = analysis_of(campaign, model=model, data=data, sigma_model=sigma)
    rows = {}
    for label, fix in (("default", False), ("dx_BT = 0", True)):
        g = gaussian_posterior(analysis.variant(fix_dx_BT=fix).log_posterior, sigma_model=sigma,
                               allow_non_normal=True)
        b_mean, b_sd = g.linear_combination(weights("beta_XB"))
        d_mean, d_sd = g.linear_combination(weights("dx_CZ_minus_dx_BT", g.names))
        rows[label] = {"beta_XB mean ″": units.from_internal(b_mean, "arcsec"),
                       "beta_XB sd ″": units.from_internal(b_sd, "arcsec"),
                       "dx_CZ_minus_dx_BT mean µm": units.from_internal(d_mean, "um"),
                       "dx_CZ_minus_dx_BT sd µm": units.from_internal(d_sd, "um")}
    return pd.DataFrame(rows).T


def sample_notes(result) -> list[str]:
    """The effect of the thesis assumption dx_BT = 0 (Eq 4.2) on a posterior that does not impose it."""
    post = result.log_posterior
    if post.fix_dx_BT:
        return []
    sigma_um = result.sigma_model_um
    return ["", f"The thesis assumption dx_BT = 0 (Eq 4.2), closed form at sigma_model = {sigma_um:.2f} µm "
            f"({'as fixed' if post.fixed_sigma is not None else 'the posterior median'}; fix_dx_BT, on the command "
            "line --fix-dx-BT, samples it):",
            assumption_effect(post.campaign, post.model_name, sigma_um, post.data).round(2).to_string()]
