"""What every interval rests on: the uncertainty budget as stacked bars, and the posterior sds against sigma_model."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.patches import Patch

from .. import units
from ..figure_style import COLOURS, figure, label, new_figure, symbol
from ..inference.budget import linearisation_point, meaning, sd_against_sigma
from ..parameters import SCALE_LABEL

#: colour of each budget source (Okabe–Ito and greys; priors in warm colours, noise in cool ones)
SOURCE_COLOURS = {"repeatability": "#56B4E9", "instrument": "#0072B2", "probe readings": "#009E73",
                  "sigma_model": "#E69F00", "sigma_model_probe": "#B8860B", "sigma_model_uncertainty": "#F0E442",
                  "prior:deviations": "#999999", "prior:T-ball centring": "#D55E00", "prior:dRB": "#CC79A7",
                  "prior:W-ball clamping": "#882255", "prior:stylus centring": "#117733", "prior:dRS": "#44AA99",
                  "prior:rS": "#AA4499", "prior:sphere placement": "#332288", "prior:reading datum": "#DDDDDD",
                  "R-test readings": "#88CCEE", "sigma_model_rtest": "#DDCC77", "prior:R-test zero": "#661100",
                  "prior:R-test sphere placement": "#6699CC", "prior:R-test nest centring": "#999933",
                  "prior:R-test nest length": "#AA4466"}

BUDGET_CAPTION = (
    "Uncertainty budget: the share of each quantity's posterior variance that comes from each source — the "
    "repeatability and accuracy of the measurements, the model-discrepancy scale σ_model (with touch-probe or R-test data: "
    "each instrument's own), not knowing σ_model (law of total variance), and the priors (of the deviations, the T-ball centring, the tool length dRB, the "
    "W-ball clamping). Exact for the linear model at each σ_model (Σ = Σ_g ΣP_gΣ + Σ_k K R_k Kᵀ), averaged over "
    "σ_model's posterior; kinematic models linearised at the posterior mean. Table: summary.csv, budget:* columns."
)
def sigma_caption(names) -> str:
    """The caption of :func:`sigma_figure` drawn for ``names``."""
    return (f"Posterior sd of each of the {units.in_words(len(names))} quantities if σ_model were known, from 0 to "
            "4 µm (closed form), and beneath, σ_model's prior (line) and posterior (histogram). Where the posterior is "
            "the prior, the data do not choose σ_model: the intervals then rest on the assumed prior, and this figure "
            "shows how much. The dashed line is σ_model's posterior median (or its fixed value).")



def budget_figure(summary: pd.DataFrame):
    """One horizontal stacked bar per quantity (the reported ones), segments by source, in % of the variance."""
    cols = [c for c in summary.columns if c.startswith("budget:")]
    s = summary.loc[summary[cols].notna().any(axis=1), cols].fillna(0.0)
    cols = [c for c in cols if (s[c] >= 0.005).any()]
    names = list(s.index)
    fig, ax = new_figure(figsize=(10, 0.42 * len(names) + 2.2))
    y = np.arange(len(names))[::-1]
    left = np.zeros(len(names))
    for c in cols:
        src = c.split(":", 1)[1]
        width = 100.0 * s[c].to_numpy()
        ax.barh(y, width, left=left, color=SOURCE_COLOURS.get(src, "#BBBBBB"), edgecolor="white", linewidth=0.5)
        for yi, l0, w in zip(y, left, width):
            if w >= 8:
                ax.text(l0 + w / 2, yi, f"{w:.0f}", ha="center", va="center", fontsize=8)
        left += width
    ax.set_yticks(y, [label(n) for n in names], fontsize=10)
    ax.set_xlim(0, 100)
    ax.set_xlabel("share of the posterior variance (%)")
    handles = [Patch(color=SOURCE_COLOURS.get(c.split(":", 1)[1], "#BBBBBB"), label=c.split(":", 1)[1]) for c in cols]
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.08 - 0.3 / max(len(names), 1)),
              ncol=4, fontsize=9, frameon=False)
    fig.tight_layout()
    return fig


def sigma_contraction(rep) -> float:
    """How much the data narrowed the first discrepancy scale (the ball bar's sigma_model, else the probe's):
    1 − posterior/prior variance, from the draws (nan when fixed)."""
    post = rep.log_posterior
    if post.fixed_sigma is not None:
        return float("nan")
    draws = units.to_internal(np.asarray(rep.idata.posterior[post.scales[0]], float).ravel(), "um")
    return float(1.0 - np.var(draws) / post.priors.priors[post.p].sd ** 2)


def sigma_figure(rep, names):
    """Posterior sd against a fixed sigma_model (0–4 µm) for each of ``names``, σ_model's prior and posterior beneath."""
    post = rep.log_posterior
    grid = units.to_internal(np.linspace(0.0, 4.0, 17), "um")  # every 0.25 µm: the curves are smooth
    curves = sd_against_sigma(post, grid, names, theta0=linearisation_point(rep.idata, post))
    names = list(curves.columns)
    rows = max(1, -(-len(names) // 4))  # four curves a row, σ_model's prior and posterior beneath
    fig = figure(figsize=(12, 2.7 * rows + 2.2))
    gs = fig.add_gridspec(rows + 1, 4, height_ratios=[1] * rows + [0.8])
    here = rep.sigma_model_um
    fixed = f"{SCALE_LABEL[post.scales[0]]} fixed at [µm]" if len(post.scales) == 1 else "every σ_model fixed at [µm]"
    for i, n in enumerate(names):
        ax = fig.add_subplot(gs[i // 4, i % 4])
        ax.plot(curves.index, curves[n], color=COLOURS["posterior"], lw=2)
        ax.axvline(here, color="0.3", ls="--", lw=1)
        ax.set_title(symbol(n), fontsize=11)
        ax.set_ylim(0, None)
        ax.set_ylabel(f"posterior sd [{units.SYMBOL[rep.summary.loc[n, 'unit']]}]", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.25)
        if i + 4 >= len(names):  # the lowest curve of its column
            ax.set_xlabel(fixed, fontsize=8)
    ax = fig.add_subplot(gs[rows, :])
    scale = post.scales[0]  # with both instruments every scale is fixed at the abscissa; the ball bar's is shown
    top = 4.0
    if post.fixed_sigma is None:
        prior = post.priors.priors[post.p]
        draws = np.asarray(rep.idata.posterior[scale]).ravel()
        learnt = post.sigma_prior is not None and scale in post.sigma_prior.scales
        if learnt:  # a learnt prior may sit beyond the assumed one's range: show its bulk
            top = max(top, float(np.quantile(draws, 0.995)),
                      units.from_internal(float(prior.frozen().ppf(0.995)), "um"))
        xs = np.linspace(0.0, top, 200)
        pdf = prior.frozen().pdf(units.to_internal(xs, "um")) * units.to_internal(1.0, "um")
        ax.plot(xs, pdf, color=COLOURS["prior"], lw=2,
                label=f"prior ({prior.describe()}, {'learnt elsewhere' if learnt else 'assumed'})")
        ax.hist(draws, bins=np.linspace(0, max(top, float(np.quantile(draws, 0.995))), 50), density=True,
                histtype="stepfilled", color=COLOURS["posterior"], alpha=0.45, label="posterior")
        ax.text(0.99, 0.9, f"contraction 1 − var_post/var_prior = {sigma_contraction(rep):.2f}", transform=ax.transAxes,
                ha="right", fontsize=9)
    else:
        ax.text(0.5, 0.5, f"σ_model fixed at {here:g} µm (--sigma-model-um)", transform=ax.transAxes, ha="center")
    ax.axvline(here, color="0.3", ls="--", lw=1)
    ax.set_xlim(0, top)
    ax.set_xlabel(f"{SCALE_LABEL[scale]} [µm]")
    ax.set_ylabel("density [1/µm]", fontsize=9)
    ax.legend(fontsize=9, loc="upper right", bbox_to_anchor=(1.0, 0.88))  # under the contraction, over the tail
    fig.tight_layout()
    return fig


def dominant_sentence(summary: pd.DataFrame, names, *, post=None) -> str:
    """For each quantity of ``names``, the source that dominates its variance, grouped by source: "σ_model …
    dominates the variance of alpha_CZ (89 %), …" (``post``, the log posterior: a σ_model prior learnt elsewhere
    is said so)."""
    by_source: dict[str, list[str]] = {}
    for n in names:
        if n not in summary.index:
            continue
        row = summary.loc[n, [c for c in summary.columns if c.startswith("budget:")]].dropna()
        if not row.empty:
            src = str(row.idxmax()).split(":", 1)[1]
            by_source.setdefault(src, []).append(f"{n} ({100 * row.max():.0f} %)")
    parts = [f"{meaning(src, post)} dominates the variance of {', '.join(qs)}" for src, qs in by_source.items()]
    text = "; ".join(parts) + "."
    return text[0].upper() + text[1:]
