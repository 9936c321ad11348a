"""Posterior predictive check of every eccentricity component against the observed repeats."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from .. import units
from ..conventions import machine_repeats
from ..figure_style import COLOURS, new_figure, tight_layout
from ..observations import Observations
from .forest import model_colour

CAPTION = (
    "Posterior predictive check. Left: for each measured eccentricity component (component_pattern@setup/mount), "
    "the 50 % (thick) and 95 % (thin) intervals of the replicated mean of the repeats under the posterior "
    "(model prediction plus the likelihood's noise: repeat scatter, instrument accuracy and σ_model), the "
    "individual repeats (small black dots) and their mean (black diamond). Right: the observed mean minus "
    "the predictive mean in units of the predictive sd; |z| > 2 (shaded band exceeded) means the model "
    "cannot reproduce that measurement with the fitted parameters."
)


def ppc_table(idata, campaign, observations=None) -> pd.DataFrame:
    """One row per observation: observed mean/sd/n (µm), predictive mean, sd, 2.5/25/75/97.5 % and z
    (``observations``: the campaign's ball-bar observations, if already made)."""
    obs = observations or Observations.from_campaign(campaign)
    rep = np.asarray(idata.posterior_predictive["eccentricity"]).reshape(-1, len(obs))
    q = np.quantile(rep, [0.025, 0.25, 0.75, 0.975], axis=0)
    mean, sd = rep.mean(axis=0), rep.std(axis=0)
    observed = units.from_internal(obs.mean, "um")
    df = pd.DataFrame({
        "observation": obs.labels,
        "pattern": [k.pattern for k in obs.keys], "setup": [k.setup for k in obs.keys],
        "mount": [k.mount for k in obs.keys], "component": [k.component for k in obs.keys],
        "observed_mean_um": observed, "repeat_sd_um": units.from_internal(obs.sd, "um"), "n_repeats": obs.n,
        "predictive_mean_um": mean, "predictive_sd_um": sd,
        "predictive_2.5%_um": q[0], "predictive_25%_um": q[1], "predictive_75%_um": q[2], "predictive_97.5%_um": q[3],
        "z": (observed - mean) / sd,
    }).set_index("observation")
    df["inside_95"] = (df["observed_mean_um"] >= df["predictive_2.5%_um"]) & (df["observed_mean_um"] <= df["predictive_97.5%_um"])
    return df


def _repeats_um(campaign) -> list[np.ndarray]:
    bb = campaign.ballbar
    return [units.from_internal(machine_repeats(bb.runs[k.run], bb)[k.component], "um")
            for k in Observations.from_campaign(campaign).keys]


def ppc_figure(tables: dict[str, pd.DataFrame], campaign):
    """Intervals of each entry of ``tables`` (label → :func:`ppc_table`) with the observed repeats."""
    first = next(iter(tables.values()))
    m = len(first)
    y = np.arange(m)[::-1]
    fig, (ax, az_) = new_figure(1, 2, figsize=(12, 0.42 * m + 2.0), sharey=True,
                                  gridspec_kw={"width_ratios": [2.2, 1.0]})
    k = len(tables)
    offsets = np.linspace(0.2, -0.2, k) if k > 1 else np.zeros(1)  # first entry on top
    for (lab, t), dy in zip(tables.items(), offsets):
        colour = model_colour(lab) if k > 1 else COLOURS["posterior"]
        ax.hlines(y + dy, t["predictive_2.5%_um"], t["predictive_97.5%_um"], color=colour, lw=1.5)
        ax.hlines(y + dy, t["predictive_25%_um"], t["predictive_75%_um"], color=colour, lw=5, alpha=0.8)
        az_.plot(t["z"], y + dy, "o", color=colour, ms=5)
    for yi, r in zip(y, _repeats_um(campaign)):
        ax.plot(r, np.full(len(r), yi), ".", color=COLOURS["observed"], ms=4, alpha=0.6)
    ax.plot(first["observed_mean_um"], y, "D", color=COLOURS["observed"], ms=5, mfc="white", mew=1.5)
    ax.set_yticks(y, list(first.index), fontsize=9)
    ax.axvline(0, color="0.6", lw=0.8, zorder=0)
    ax.set_xlabel("eccentricity [µm]")
    ax.grid(axis="x", alpha=0.3)
    az_.axvspan(-2, 2, color="0.9", zorder=0)
    az_.axvline(0, color="0.6", lw=0.8)
    lim = max(3.0, float(np.nanmax([np.abs(t["z"]).max() for t in tables.values()])) * 1.15)
    az_.set_xlim(-lim, lim)
    az_.set_xlabel("(observed − predicted) / predictive sd")
    az_.grid(axis="x", alpha=0.3)
    handles = [Line2D([], [], color=model_colour(lab) if k > 1 else COLOURS["posterior"],
                      lw=4, label=f"{lab}: predictive 50 % / 95 %" if k > 1 else "posterior predictive 50 % / 95 %")
               for lab in tables]
    handles += [Line2D([], [], color=COLOURS["observed"], marker=".", ls="none", label="repeats"),
                Line2D([], [], color=COLOURS["observed"], marker="D", mfc="white", ls="none", label="mean of the repeats")]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 3), fontsize=9, frameon=False)
    tight_layout(fig, (0, 0.5 / fig.get_figheight(), 1, 1))
    return fig
