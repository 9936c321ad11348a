"""Figures of the measurement plan: the ranking and the tool-length sweep."""

from __future__ import annotations

import numpy as np
import matplotlib
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from ..figure_style import new_figure, symbol

RANKING_CAPTION = (
    "Candidate measurements ranked by the expected information they give about the targets "
    "(½·log₂ of the ratio of the target covariance determinants before and after, in bits; closed form "
    "for the linear model). Feasible candidates only, best first, coloured by kind; beside each bar the "
    "targets it narrows most, expected posterior sd today → after. Candidates that change no target sd by 1 % "
    "or more are left out (see plan.csv)."
)
SWEEP_CAPTION = (
    "Expected posterior sd of each target after an extra run of the swept pattern at the tool-length difference Δ "
    "(extension bar on the primary tool setup, Z_T following), as a fraction of its sd today (dashed line: today; "
    "the legend gives today's sd, and says 'unchanged' where no Δ moves it by 1 % or more). Crosses: differences "
    "at which the run leaves the target not identified (its sd still follows the prior), such as a zero "
    "difference; grey band: beyond the axis travels. The sds themselves are in plan_sweep.csv."
)
#: one colour per kind of candidate (Okabe-Ito); another W-ball placement is one colour whatever the format calls it
KIND_COLOURS = {"tool length": "#0072B2", "existing setup": "#56B4E9", "repeats": "#999999",
                "other pattern": "#E69F00", "other R_C": "#009E73", "other placement": "#009E73",
                "held axes": "#F0E442", "bar length": "#CC79A7", "probe": "#000000", "user": "#D55E00"}
MAX_BARS = 20
#: a target whose sd no Δ moves by this fraction is said to be unchanged in the sweep's legend
UNCHANGED = 0.01
#: display unit symbols of the targets' units
UNIT_SYMBOLS = {"arcsec": "″", "um": "µm"}
#: line styles of the sweep's targets beyond the ten colours
LINE_STYLES = ("-", "--", ":")
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
    """Every target's expected sd after the swept run against Δ, relative to its sd today, on one axes."""
    s = result.sweep
    x = s["extension_mm"].to_numpy()
    fig, ax = new_figure(figsize=(11, 5.4))
    colours = matplotlib.colormaps["tab10"].colors
    top = 1.0
    for i, (t, unit) in enumerate(zip(result.targets, result.target_units)):
        before = float(s[f"{t} sd_before"].iloc[0])
        ratio = s[f"{t} sd_after"].to_numpy() / before
        top = max(top, float(np.nanmax(ratio)))
        unchanged = bool(np.all(np.abs(ratio - 1.0) < UNCHANGED))
        text = f"{symbol(t)}: today {before:.3g}{'' if unit == 'arcsec' else ' '}{UNIT_SYMBOLS[unit]}"
        ax.plot(x, ratio, color=colours[i % 10], ls=LINE_STYLES[i // 10 % len(LINE_STYLES)], lw=2,
                label=text + (", unchanged" if unchanged else ""))
        bad = ~s[f"{t} identified"].to_numpy()
        if bad.any():
            ax.plot(x[bad], ratio[bad], "x", color=colours[i % 10], ms=7, mew=2)
    ax.axhline(1.0, color="0.3", ls="--", lw=1)
    infeasible = ~s["feasible"].to_numpy()
    if infeasible.any():
        ax.axvspan(x[infeasible].min(), x.max(), color="0.85", zorder=0, label="beyond the travels")
    handles, labels = ax.get_legend_handles_labels()
    if any((~s[f"{t} identified"]).any() for t in result.targets):
        handles.append(Line2D([], [], ls="none", marker="x", color="0.2", ms=7, mew=2))
        labels.append("not identified")
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
    ax.set_ylim(0, 1.08 * top)
    ax.set_xlabel("tool-length difference Δ [mm]")
    ax.set_ylabel("expected sd after / sd today")
    ax.set_title(f"after {result.sweep_pattern} at R_B + Δ", fontsize=11)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig
