"""Figures of the measurement plan: the ranking and the tool-length sweep."""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Rectangle
from matplotlib.ticker import ScalarFormatter

from ..figure_style import label, new_figure, symbol, tight_layout

RANKING_CAPTION = (
    "Candidate measurements ranked by the expected information they give about the targets "
    "(½·log₂ of the ratio of the target covariance determinants before and after, in bits; closed form "
    "for the linear model). Feasible candidates only, best first, coloured by kind; beside each bar the "
    "targets it narrows most, expected posterior sd today → after. Candidates that change no target sd by 1 % "
    "or more are left out (see plan.csv)."
)
SWEEP_CAPTION = (
    "Expected posterior sd of each target against the tool-length difference of an extra run of the "
    "swept pattern (extension bar on the primary tool setup, Z_T following). Dashed: the sd today; "
    "red crosses: differences at which the run leaves the target not identified (its sd still follows "
    "the prior), such as a zero difference; grey band: beyond the axis travels."
)
#: one colour per kind of candidate (Okabe-Ito); another W-ball placement is one colour whatever the format calls it
KIND_COLOURS = {"tool length": "#0072B2", "existing setup": "#56B4E9", "repeats": "#999999",
                "other pattern": "#E69F00", "other R_C": "#009E73", "other placement": "#009E73",
                "held axes": "#F0E442", "bar length": "#CC79A7", "probe": "#000000", "user": "#D55E00"}
MAX_BARS = 20
#: width of the ranking's axes, inches (the 11 in figure less the candidates' names): what its texts fit in
ANNOTATED_AXES_WIDTH_IN = 7.5


def ranking_figure(result):
    t = result.table
    t = t[t["feasible"] & t["informative"]].head(MAX_BARS)
    n = max(len(t), 1)
    fig, ax = new_figure(figsize=(11, 0.38 * n + 1.6))
    y = np.arange(len(t))[::-1]
    ax.barh(y, t["eig_bits"], color=[KIND_COLOURS.get(k, "0.5") for k in t["kind"]])
    ax.set_yticks(y, t["name"], fontsize=9)
    right = float(t["eig_bits"].max()) if len(t) else 1.0
    sym = {"arcsec": "″", "um": "µm"}
    limit = right * 1.1
    for yi, (_, r) in zip(y, t.iterrows()):
        ratio = {tg: r[f"{tg} sd_after"] / r[f"{tg} sd_before"] for tg in result.targets}
        best = sorted(ratio, key=ratio.get)[:2]  # the two targets it helps most
        text = ", ".join(f"{tg} {r[f'{tg} sd_before']:.3g}→{r[f'{tg} sd_after']:.3g}"
                         f"{sym[result.target_units[result.targets.index(tg)]]}" for tg in best)
        ax.text(r["eig_bits"] + 0.01 * right, yi, text, va="center", fontsize=8)
        # room for the text after its bar, from its length (an 8 pt character is about 0.075 in wide)
        share = min(0.6, len(text) * 0.075 / ANNOTATED_AXES_WIDTH_IN)
        limit = max(limit, float(r["eig_bits"]) / (0.96 - share))
    ax.set_xlim(0, limit)
    ax.set_xlabel("expected information gain about the targets [bits]")
    kinds = list(dict.fromkeys(t["kind"]))
    if kinds:  # no bar, no legend (matplotlib refuses an empty one)
        ax.legend(handles=[Rectangle((0, 0), 1, 1, color=KIND_COLOURS.get(k, "0.5")) for k in kinds], labels=kinds,
                  loc="lower right", fontsize=8)
    if not len(t):
        ax.text(0.5, 0.5, "no feasible candidate improves the targets", transform=ax.transAxes, ha="center")
    ax.set_title(f"targets: {', '.join(result.targets)}\nbeside each bar the (at most two) targets it "
                 "narrows most, sd before→after", fontsize=9)
    fig.tight_layout()
    return fig


def sweep_figure(result):
    s = result.sweep
    k = len(result.targets)
    ncols = min(k, 2)
    nrows = int(np.ceil(k / ncols))
    fig, axes = new_figure(nrows, ncols, figsize=(6.2 * ncols, 3.6 * nrows), squeeze=False)
    x = s["extension_mm"].to_numpy()
    for ax, t in zip(axes.ravel(), result.targets):
        ax.plot(x, s[f"{t} sd_after"], color="#0072B2", lw=2, label=f"after {result.sweep_pattern} at R_B + Δ")
        ax.axhline(s[f"{t} sd_before"].iloc[0], color="0.3", ls="--", lw=1, label="today")
        bad = ~s[f"{t} identified"].to_numpy()
        if bad.any():
            ax.plot(x[bad], s.loc[bad, f"{t} sd_after"], "x", color="#C00000", ms=7, mew=2,
                    label="not identified")
        infeasible = ~s["feasible"].to_numpy()
        if infeasible.any():
            ax.axvspan(x[infeasible].min(), x.max(), color="0.85", zorder=0, label="beyond the travels")
        values = s[f"{t} sd_after"].to_numpy()
        if values.max() / values.min() > 3:  # log scale only for a wide range: it hides small changes
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(ScalarFormatter(useOffset=False))
            ax.yaxis.set_minor_formatter(ScalarFormatter(useOffset=False))
            ax.tick_params(axis="y", which="minor", labelsize=7)
        else:  # from zero, so that a change of a fraction of a per cent looks like one
            ax.set_ylim(0, 1.12 * max(values.max(), s[f"{t} sd_before"].iloc[0]))
        ax.set_xlabel("tool-length difference Δ [mm]")
        ax.set_ylabel(f"sd of {label(t)}")
        ax.set_title(symbol(t))
        ax.grid(alpha=0.3, which="both")
    for ax in axes.ravel()[k:]:
        ax.set_visible(False)
    shown = {}  # one legend for every panel: each kind of line once, in the order first drawn
    for ax in axes.ravel()[:k]:
        for handle, text in zip(*ax.get_legend_handles_labels()):
            shown.setdefault(text, handle)
    fig.legend(shown.values(), shown.keys(), loc="lower center", ncol=len(shown), fontsize=9, frameon=False)
    tight_layout(fig, (0, 0.4 / fig.get_figheight(), 1, 1))
    return fig
