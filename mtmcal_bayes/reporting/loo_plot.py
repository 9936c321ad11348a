"""Leave-one-out consistency per observation: pointwise elpd_loo and Pareto k (PSIS-LOO)."""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from ..figure_style import COLOURS, new_figure, tight_layout
from ..posterior.loo import ELPD_DROP, K_INFLUENTIAL, LooResult

#: colour of a flagged observation
FLAG = "#D55E00"
#: most observations drawn one labelled row each; a campaign with more is drawn in the compact form (each observation
#: a point at its number, only the flagged ones named: 148 labelled rows made a figure five screens tall)
ROWS_LABELLED = 40
#: most flagged observations named in the compact form (loo.csv names every one)
NAMED_MAX = 12
#: each kind of observation in the compact form
KIND_WORDS = {"eccentricity": "ball bar", "probe_reading": "probe", "rtest_reading": "R-test"}

CAPTION = (
    "Leave-one-out consistency (PSIS-LOO). Left: for each observed mean, the log predictive density of it under "
    "the posterior of all the other observations (elpd_loo, higher is better), against the median of its kind "
    f"(grey line); beyond the shaded edge, {ELPD_DROP:g} below the median, the other measurements predict it about "
    "as badly as a three-sd residual (orange: check that measurement). Right: Pareto k of the importance "
    f"sampling; above {K_INFLUENTIAL} (orange) the observation is influential — the only one fixing some "
    "parameters — and its elpd_loo is unreliable (optimistic). On a nearly saturated design most observations "
    "lie there without any error in the data."
)


COMPACT_CAPTION = (
    "Leave-one-out consistency (PSIS-LOO), one point per observed mean in the campaign's order (loo.csv names "
    "each). Top: the log predictive density of it under the posterior of all the other observations (elpd_loo, "
    "higher is better), against the median of its kind (grey line); below the shaded edge, "
    f"{ELPD_DROP:g} below the median, the other measurements predict it about as badly as a three-sd residual "
    f"(orange, named: check that measurement). Bottom: Pareto k of the importance sampling; above {K_INFLUENTIAL} "
    "(orange) the observation is influential — the only one fixing some parameters — and its elpd_loo is "
    "unreliable (optimistic)."
)


def caption(result: LooResult) -> str:
    """The caption of :func:`loo_figure` of ``result`` (the compact form's beyond :data:`ROWS_LABELLED` rows)."""
    return CAPTION if len(result.table) <= ROWS_LABELLED else COMPACT_CAPTION


def loo_figure(result: LooResult):
    """Pointwise elpd_loo and Pareto k of every observation of ``result``: one labelled row each, or the compact
    form (:func:`compact_figure`) beyond :data:`ROWS_LABELLED` observations."""
    t = result.table
    m = len(t)
    if m > ROWS_LABELLED:
        return compact_figure(result)
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
    return _finished(fig)


def compact_figure(result: LooResult):
    """Pointwise elpd_loo (top) and Pareto k (bottom) of every observation of ``result`` against its number in the
    campaign's order, each kind of observation in a band of its own, the flagged ones named (at most
    :data:`NAMED_MAX`)."""
    t = result.table
    x = np.arange(1, len(t) + 1)
    fig, (ax, axk) = new_figure(2, 1, figsize=(11, 6.4), sharex=True, gridspec_kw={"height_ratios": [1.6, 1.0]})
    kinds = t["variable"].to_numpy()
    starts = [0] + [i for i in range(1, len(t)) if kinds[i] != kinds[i - 1]] + [len(t)]
    low = float(min(t["elpd_loo"].min(), (t["elpd_loo"] + t["elpd_drop"]).min() - ELPD_DROP))
    high = float(t["elpd_loo"].max())
    pad = 0.08 * (high - low)
    for a, b in zip(starts[:-1], starts[1:]):
        med = float(np.median(t["elpd_loo"].iloc[a:b]))
        ax.hlines(med, a + 0.5, b + 0.5, color="0.55", lw=1.0)
        ax.fill_between([a + 0.5, b + 0.5], low - pad, med - ELPD_DROP, color="0.9", zorder=0)
        for axis in (ax, axk):
            if a:
                axis.axvline(a + 0.5, color="0.35", lw=0.8)
        ax.text((a + b + 1) / 2, 1.01, KIND_WORDS.get(kinds[a], kinds[a]), transform=ax.get_xaxis_transform(),
                ha="center", va="bottom", fontsize=10)
    ax.scatter(x, t["elpd_loo"], c=np.where(t["outlier"], FLAG, COLOURS["posterior"]), s=14, zorder=3)
    ax.set_ylim(low - pad, high + pad)
    ax.set_ylabel("pointwise elpd_loo\n(per µm)")
    ax.grid(axis="y", alpha=0.3)
    top = max(1.5, float(t["pareto_k"].max()) + 0.1)
    axk.axhspan(K_INFLUENTIAL, top, color="0.9", zorder=0)
    axk.axhline(K_INFLUENTIAL, color=FLAG, lw=1.0)
    axk.scatter(x, t["pareto_k"], c=np.where(t["influential"], FLAG, COLOURS["posterior"]), s=14, zorder=3)
    axk.set_ylim(min(-0.1, float(t["pareto_k"].min()) - 0.05), top)
    axk.set_ylabel("Pareto k")
    axk.set_xlim(0.5, len(t) + 0.5)
    axk.set_xlabel("observation (in the campaign's order; loo.csv names each)")
    axk.grid(axis="y", alpha=0.3)
    flagged = np.flatnonzero(t["outlier"].to_numpy() | t["influential"].to_numpy())
    worst = flagged[np.argsort(-t["elpd_drop"].to_numpy()[flagged], kind="stable")][:NAMED_MAX]
    per_pt = len(t) / (0.86 * 72 * fig.get_figwidth())  # observations per point of the axes' width
    for panel, axis, values, (y0, y1) in (("outlier", ax, t["elpd_loo"], ax.get_ylim()),
                                          ("influential", axk, t["pareto_k"], axk.get_ylim()[::-1])):
        rows: list[float] = []  # each row of names: where its last name ends (in observations)
        for i in sorted(i for i in worst if t[panel].iloc[i]):
            name = str(t.index[i])
            left = x[i] + 10 * per_pt  # each name begins right of its point
            r = next((k for k, end in enumerate(rows) if left > end), len(rows))
            rows[r:r + 1] = [left + (len(name) * 4.8 + 6) * per_pt]  # 8-point names, about 4.8 points a letter
            # the names in rows along the panel's far edge from the data (the bottom for elpd, the top for k)
            at = y0 + (0.06 + 0.09 * r) * (y1 - y0)
            axis.annotate(name, (x[i], values.iloc[i]), xytext=(left, at), textcoords="data", fontsize=8,
                          color=FLAG, ha="left", va="center",
                          arrowprops={"arrowstyle": "-", "color": FLAG, "lw": 0.6, "shrinkA": 0, "shrinkB": 3})
    return _finished(fig)


def _finished(fig):
    """``fig`` with the legend of the flags beneath, laid out."""
    handles = [Line2D([], [], color=COLOURS["posterior"], marker="o", ls="none", label="no flag"),
               Line2D([], [], color=FLAG, marker="o", ls="none",
                      label=f"elpd_loo ≥ {ELPD_DROP:g} below the median / Pareto k > {K_INFLUENTIAL}"),
               Line2D([], [], color="0.55", lw=1.0, label="median elpd_loo of the kind")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9, frameon=False)
    tight_layout(fig, (0, 0.45 / fig.get_figheight(), 1, 1))
    return fig
