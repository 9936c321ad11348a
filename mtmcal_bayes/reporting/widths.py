"""What the data taught: prior against posterior width of each quantity."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from ..figure_style import COLOURS, label, new_figure
from ..inference.analytic import NOT_IDENTIFIED_GROWTH, WIDEN
from ..inference.identifiability import DETERMINED, IN_COMBINATION, UNDETERMINED

CAPTION = (
    "Prior sd (grey) and posterior sd (blue) of each quantity on a logarithmic axis, with the ratio "
    "posterior/prior written beside it: a ratio near 1 means the data taught nothing about that quantity. "
    "What the data determine is the campaign's Jacobian's statement (nuisance terms included): red labels mark "
    "quantities it leaves undetermined, so their width reflects priors, not the measurement; orange labels those "
    "determined only in a combination with others (named in the summary). 'Rests on xT prior' is a "
    f"separate diagnostic: the quantity's sd grows more than {NOT_IDENTIFIED_GROWTH:g}× when the nuisance priors "
    f"(T-ball centring, tool length, W-ball clamping) are widened {WIDEN:g}×, so its interval states that set-up "
    "knowledge as much as the machine (docs/metrology.md)."
)


#: colour of a quantity's label by what the data determine of it (the Jacobian's statement)
IDENTIFICATION_COLOUR = {DETERMINED: "black", IN_COMBINATION: "#B25E00", UNDETERMINED: "#C00000", None: "black"}


def widths_figure(summary: pd.DataFrame, names):
    names = [n for n in names if n in summary.index]
    s = summary.loc[names]
    y = np.arange(len(names))[::-1]
    fig, ax = new_figure(figsize=(9, 0.55 * len(names) + 1.6))
    ax.hlines(y, s["sd"], s["prior_sd"], color="0.75", lw=2, zorder=1)
    ax.plot(s["prior_sd"], y, "o", color=COLOURS["prior"], ms=8, zorder=2)
    ax.plot(s["sd"], y, "o", color=COLOURS["posterior"], ms=8, zorder=3)
    ax.set_xscale("log")
    lo, hi = float(min(s["sd"].min(), s["prior_sd"].min())), float(max(s["sd"].max(), s["prior_sd"].max()))
    ax.set_xlim(lo / 3, hi * 6)
    for yi, (n, r) in zip(y, s.iterrows()):
        note = {UNDETERMINED: "  not identified", IN_COMBINATION: "  only in combination"}.get(r["identification"], "")
        through = r.get("identified_through")  # the prior-sensitivity diagnostic, in short
        note += f"  rests on {through} prior{'s' if ',' in through else ''}" if isinstance(through, str) and through else ""
        ax.text(max(r["prior_sd"], r["sd"]) * 1.25, yi, f"× {r['sd_ratio']:.3g}" + note, va="center", fontsize=9,
                color=IDENTIFICATION_COLOUR[r["identification"]])
    ax.set_yticks(y, [label(n) for n in names], fontsize=11)
    for tick, n in zip(ax.get_yticklabels(), names):
        tick.set_color(IDENTIFICATION_COLOUR[s.loc[n, "identification"]])
    ax.set_xlabel("standard deviation (″ for angles, µm for lengths; log scale)")
    ax.grid(axis="x", which="both", alpha=0.25)
    ax.legend(handles=[Line2D([], [], color=COLOURS["prior"], marker="o", ls="none", label="prior sd"),
                       Line2D([], [], color=COLOURS["posterior"], marker="o", ls="none", label="posterior sd")],
              loc="lower left", fontsize=9)
    fig.tight_layout()
    return fig
