"""Leave-one-out consistency per observation: pointwise elpd_loo and Pareto k (PSIS-LOO)."""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from ..figure_style import COLOURS, new_figure, tight_layout
from ..posterior.loo import ELPD_DROP, K_INFLUENTIAL, LooResult

#: colour of a flagged observation
FLAG = "#D55E00"

CAPTION = (
    "Leave-one-out consistency (PSIS-LOO). Left: for each observed mean, the log predictive density of it under "
    "the posterior of all the other observations (elpd_loo, higher is better), against the median of its kind "
    f"(grey line); beyond the shaded edge, {ELPD_DROP:g} below the median, the other measurements predict it about "
    "as badly as a three-sd residual (orange: check that measurement). Right: Pareto k of the importance "
    f"sampling; above {K_INFLUENTIAL} (orange) the observation is influential — the only one fixing some "
    "parameters — and its elpd_loo is unreliable (optimistic). On a nearly saturated design most observations "
    "lie there without any error in the data."
)


def loo_figure(result: LooResult):
    """Pointwise elpd_loo and Pareto k of every observation of ``result``."""
    t = result.table
    m = len(t)
    y = np.arange(m)[::-1]
    fig, (ax, axk) = new_figure(1, 2, figsize=(11, 0.32 * m + 2.0), sharey=True,
                                gridspec_kw={"width_ratios": [1.6, 1.0]})
    for var in t["variable"].unique():
        rows = (t["variable"] == var).to_numpy()
        med = float(np.median(t.loc[rows, "elpd_loo"]))
        lo, hi = y[rows].min() - 0.4, y[rows].max() + 0.4
        ax.vlines(med, lo, hi, color="0.55", lw=1.0)
        ax.fill_betweenx([lo, hi], med - ELPD_DROP, med - 1e9, color="0.9", zorder=0)
    colour = np.where(t["outlier"], FLAG, COLOURS["posterior"])
    ax.scatter(t["elpd_loo"], y, c=colour, s=28, zorder=3)
    low = float(min(t["elpd_loo"].min(), (t["elpd_loo"] + t["elpd_drop"]).min() - ELPD_DROP))
    high = float(t["elpd_loo"].max())
    pad = 0.08 * (high - low)
    ax.set_xlim(low - pad, high + pad)
    ax.set_yticks(y, list(t.index), fontsize=9)
    ax.set_ylim(-0.7, m - 0.3)
    ax.set_xlabel("pointwise elpd_loo (log density of the observed mean, per µm)")
    ax.grid(axis="x", alpha=0.3)
    axk.axvspan(K_INFLUENTIAL, max(1.5, float(t["pareto_k"].max()) + 0.1), color="0.9", zorder=0)
    axk.axvline(K_INFLUENTIAL, color=FLAG, lw=1.0)
    axk.scatter(t["pareto_k"], y, c=np.where(t["influential"], FLAG, COLOURS["posterior"]), s=28, zorder=3)
    axk.set_xlim(min(-0.1, float(t["pareto_k"].min()) - 0.05), max(1.5, float(t["pareto_k"].max()) + 0.1))
    axk.set_xlabel("Pareto k")
    axk.grid(axis="x", alpha=0.3)
    handles = [Line2D([], [], color=COLOURS["posterior"], marker="o", ls="none", label="no flag"),
               Line2D([], [], color=FLAG, marker="o", ls="none",
                      label=f"elpd_loo ≥ {ELPD_DROP:g} below the median / Pareto k > {K_INFLUENTIAL}"),
               Line2D([], [], color="0.55", lw=1.0, label="median elpd_loo of the kind")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9, frameon=False)
    tight_layout(fig, (0, 0.45 / fig.get_figheight(), 1, 1))
    return fig
