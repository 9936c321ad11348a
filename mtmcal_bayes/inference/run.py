"""One call from a campaign to a posterior with its summary, comparison and diagnostics."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..identify import identify
from ..models import make_model
from ..parameters import IDENTIFIABLE
from ..textfiles import atomic_output
from .analytic import gaussian_posterior
from .posterior import Posterior
from .results import comparison, diagnostics_warnings, not_identified, summarize, to_inference_data
from .sampling import SamplerSettings, SamplingResult, run_ensembles


@dataclass
class PosteriorReport:
    """Everything ``mtmcal-bayes sample`` prints: summary, comparison, diagnostics, the InferenceData."""

    idata: object
    summary: pd.DataFrame
    comparison: pd.DataFrame
    result: SamplingResult
    warnings: list[str] = field(default_factory=list)
    not_identified: list[str] = field(default_factory=list)

    def diagnostics(self) -> dict:
        r = self.result
        ess = self.summary.loc[[n for n in IDENTIFIABLE if n in self.summary.index], "ess_bulk"]
        return {
            "converged": r.converged, "n_ensembles": r.chains.shape[0], "n_walkers": r.chains.shape[2],
            "n_steps": r.n_steps, "burn_in": r.burn, "tau_max_steps": float(r.tau.max()),
            "kept_draws": r.n_draws, "acceptance": r.acceptance.tolist(), "wall_time_s": r.wall_time,
            "min_ess_bulk": float(ess.min()), "ess_bulk_per_second": float(ess.min() / r.wall_time),
            "max_r_hat": float(self.summary["r_hat"].max()), "warnings": self.warnings,
            "not_identified": self.not_identified, "messages": r.messages,
        }


def posterior_report(campaign, model: str = "linear", fix_dx_BT: bool = False, settings: SamplerSettings | None = None,
                     checkpoint=None, progress=None) -> PosteriorReport:
    """Sample the posterior of ``campaign`` and summarise it against the deterministic results."""
    post = Posterior(campaign, model, fix_dx_BT=fix_dx_BT)
    result = run_ensembles(post, settings, checkpoint=checkpoint, progress=progress)
    seed = settings.seed if settings else None
    idata = to_inference_data(result, seed=seed)
    summary = summarize(idata, post)
    comp = comparison(summary, identify(campaign))
    warn = result.messages + linear_model_check(result) + diagnostics_warnings(summary)
    return PosteriorReport(idata, summary, comp, result, warn, not_identified(summary))


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
    gap = float(np.abs(make_model("htm-thesis", post.campaign, post.space).predict(theta)
                       - post.forward.predict(theta)).max())
    accuracy = post.campaign.ballbar.accuracy
    if gap <= accuracy:
        return []
    return [f"the linear model is first order and the deviations found are too large for it: at the posterior "
            f"mean the kinematic model htm-thesis predicts eccentricities up to {units.from_internal(gap, 'um'):.1f} µm "
            f"away from it (instrument accuracy {units.from_internal(accuracy, 'um'):g} µm); use --model htm-thesis"]


def thesis_assumption_effect(campaign, model: str = "linear", sigma_model_um: float = 0.3) -> pd.DataFrame:
    """beta_XB and dx_CZ − dx_BT with and without dx_BT = 0, closed form (linearised) at fixed sigma_model.

    Columns: mean and sd of each quantity, by default and with the thesis' Eq 4.2 assumption.
    """
    rows = {}
    for label, fix in (("default", False), ("dx_BT = 0", True)):
        g = gaussian_posterior(Posterior(campaign, model, fix_dx_BT=fix, sigma_model=sigma_model_um * 1e-3),
                               sigma_model=sigma_model_um * 1e-3, allow_non_normal=True)
        b_mean, b_sd = g.linear_combination({"beta_XB": 1.0})
        w = {"dx_CZ": 1.0} if fix else {"dx_CZ": 1.0, "dx_BT": -1.0}
        d_mean, d_sd = g.linear_combination(w)
        rows[label] = {"beta_XB mean ″": units.from_internal(b_mean, "arcsec"),
                       "beta_XB sd ″": units.from_internal(b_sd, "arcsec"),
                       "dx_CZ_minus_dx_BT mean µm": units.from_internal(d_mean, "um"),
                       "dx_CZ_minus_dx_BT sd µm": units.from_internal(d_sd, "um")}
    return pd.DataFrame(rows).T


def write_netcdf_atomic(idata, path) -> None:
    """Save an InferenceData as NetCDF through a temporary file (nothing half-written)."""
    with atomic_output(path) as tmp:
        idata.to_netcdf(tmp)
