"""Forest plot: 95 % HDIs of a machine's quantities beside the deterministic values."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from ..figure_style import (
    COLOURS,
    DATA_COLOURS,
    MODEL_COLOURS,
    REFERENCE_LABELS,
    iso_mathtext,
    new_figure,
    symbol,
    tight_layout,
    unit_symbol,
)
from .corner_plot import OFF_SCALE_SD, reference_values
from .widths import IDENTIFICATION_COLOUR

#: what each kind of deterministic value is, in the forest's caption
_REF_MEANING = {
    "ballbar": "ball bar (thesis Eqs 4.10–4.18 recomputed from the campaign)",
    "probe_reported": "touch probe as printed (Table 5.3)",
    "probe_recomputed": "touch probe recomputed (Eqs 5.1–5.19)",
    "least_squares": ("least squares of the first order of the machine's kinematic model (section 'Least-squares "
                      "identification'), for each quantity the campaign determines"),
}


def caption(comparison: pd.DataFrame, names) -> str:
    """The forest's caption for the deterministic values it draws of ``names`` (``comparison``:
    :func:`~mtmcal_bayes.posterior.comparison.comparison`)."""
    refs = reference_values(comparison, names)
    drawn = [_REF_MEANING[k] for k in _REF_STYLE if any(v is not None for v in refs[k])]
    listed = ", ".join(drawn[:-1]) + (" and " if len(drawn) > 1 else "") + (drawn[-1] if drawn else "")
    return ("One row per quantity, each with its own scale (″ for angles, µm for lengths): posterior mean (dot) and "
            "95 % highest-density interval (bar)" + (f", and below it the deterministic values: {listed}. A "
            "deterministic value outside the bar is outside the 95 % HDI. Values more than "
            f"{OFF_SCALE_SD:g} posterior sd away are not drawn to scale: an arrow at the edge gives the value"
            if drawn else "") + ". A red name: the campaign's Jacobian leaves the quantity undetermined (its bar is "
            "set by priors); orange: determined only in a combination with others.")


CAPTION_DATA = (
    "The same quantities from three posteriors of one model: the ball-bar eccentricities only, the touch-probe "
    "readings only, and both (fused). Where the ball-bar-only and probe-only bars do not overlap the instruments "
    "disagree about that quantity; a probe-only bar as wide as its prior means the probe does not inform it."
)

#: how each kind of deterministic value is drawn (:data:`~mtmcal_bayes.posterior.comparison.REFERENCES`, in its
#: order); the least squares as a cross, which reads inside the thesis' hollow markers where the values agree
_REF_STYLE = {"ballbar": dict(marker="o", ms=9, mfc="none", mew=2),
              "probe_reported": dict(marker="s", ms=8, mfc="none", mew=2),
              "probe_recomputed": dict(marker="D", ms=7, mfc="none", mew=1.5),
              "least_squares": dict(marker="x", ms=8, mew=2)}
#: the colour of each reference kind (the least squares in black, apart from the thesis' three)
_REF_COLOUR = {**COLOURS, "least_squares": COLOURS["observed"]}
#: a model the shared palette has no colour for (figure_style.MODEL_COLOURS: the thesis machine's first three)
_MORE_MODEL_COLOURS = {"chain": "#CC79A7"}


def model_colour(label: str) -> str:
    """The colour of a model (or of a posterior's data) in a figure that compares several."""
    return {**_MORE_MODEL_COLOURS, **MODEL_COLOURS, **DATA_COLOURS}.get(label, COLOURS["posterior"])


def _colour(label: str, several: bool) -> str:
    return model_colour(label) if several else COLOURS["posterior"]


def _label_colour(rows) -> str:
    """A quantity's label colour: what the data determine of it (the Jacobian's statement) where every posterior
    drawn says the same, else black."""
    verdicts = {r.get("identification") for r in rows}
    return IDENTIFICATION_COLOUR.get(verdicts.pop(), "black") if len(verdicts) == 1 else "black"


def _legend_height(entries: int) -> float:
    """Inches below the axes for the legend of ``entries`` entries in two columns (0.7 up to two rows, then about
    0.2 per row: a row of 9.5 pt text and its spacing)."""
    return max(0.7, 0.25 + 0.2 * -(-entries // 2))


def forest_figure(summaries: dict[str, pd.DataFrame], comparison: pd.DataFrame | None, names):
    """One row per quantity, one interval per entry of ``summaries`` (label → summary table).

    ``comparison`` (from :func:`~mtmcal_bayes.posterior.comparison.comparison`) supplies the
    reference values; None draws the intervals only.
    """
    names = [n for n in names if all(n in s.index for s in summaries.values())]
    refs = reference_values(comparison, names) if comparison is not None else {}
    k = len(summaries)
    kinds = [key for key in _REF_STYLE if refs and any(v is not None for v in refs[key])]
    legend_in = _legend_height(k + len(kinds))
    fig, axes = new_figure(len(names), 1, figsize=(10, (0.55 + 0.22 * k) * len(names) + 0.6 + legend_in),
                           squeeze=False)
    for i, (ax, n) in enumerate(zip(axes[:, 0], names)):
        rows = {lab: s.loc[n] for lab, s in summaries.items()}
        ys = 1.0 + np.arange(k)[::-1] * 0.6
        for (lab, r), y in zip(rows.items(), ys):
            ax.hlines(y, r["hdi_low"], r["hdi_high"], color=_colour(lab, k > 1), lw=5, alpha=0.85)
            ax.plot(r["mean"], y, "o", color="white", mec=_colour(lab, k > 1), ms=6, mew=1.5)
        lo = min(r["hdi_low"] for r in rows.values())
        hi = max(r["hdi_high"] for r in rows.values())
        mean = np.mean([r["mean"] for r in rows.values()])
        sd = max(r["sd"] for r in rows.values())
        near = [refs[key][i] for key in _REF_STYLE if refs and refs[key][i] is not None
                and abs(refs[key][i] - mean) <= OFF_SCALE_SD * sd]
        lo, hi = min([lo, mean - 4 * sd] + near), max([hi, mean + 4 * sd] + near)
        pad = 0.04 * (hi - lo)
        xlim = (lo - pad, hi + pad)
        beyond = {True: 0, False: 0}  # off-scale values already drawn on each side: the next one further in
        for key, st in _REF_STYLE.items():
            v = refs[key][i] if refs else None
            if v is None:
                continue
            if xlim[0] <= v <= xlim[1]:
                ax.plot(v, 0.0, color=_REF_COLOUR[key], ls="none", **st)
            else:
                right = v > xlim[1]
                row = -0.45 * beyond[right]  # a second one on the same side a row lower
                beyond[right] += 1
                ax.annotate(f"{v:.0f}", xy=(xlim[1] if right else xlim[0], row), xytext=(-30 if right else 30, 0),
                            textcoords="offset points", ha="center", va="center", fontsize=8, color=_REF_COLOUR[key],
                            arrowprops=dict(arrowstyle="->", color=_REF_COLOUR[key]))
        ax.set_xlim(xlim)
        ax.set_ylim(-0.6 - 0.45 * max(0, max(beyond.values()) - 1), ys[0] + 0.6)
        ax.set_yticks([])
        iso = iso_mathtext(n)
        ax.set_ylabel(f"{symbol(n)}\n{iso + chr(10) if iso else ''}[{unit_symbol(n)}]", rotation=0, ha="right",
                      va="center", fontsize=12, color=_label_colour(rows.values()))
        if xlim[0] < 0 < xlim[1]:
            ax.axvline(0, color="0.6", lw=0.8, zorder=0)
        ax.grid(axis="x", alpha=0.3)
        ax.tick_params(axis="x", labelsize=9)
    handles = [Line2D([], [], color=_colour(lab, k > 1), lw=5, marker="o", mfc="white",
                      label=f"{lab}: mean, 95 % HDI" if k > 1 else "posterior: mean, 95 % HDI") for lab in summaries]
    for key in kinds:
        handles.append(Line2D([], [], color=_REF_COLOUR[key], ls="none", label=REFERENCE_LABELS[key],
                              **_REF_STYLE[key]))
    tight_layout(fig, (0, legend_in / fig.get_figheight(), 1, 1), h_pad=0.6)
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=9.5, frameon=False)
    return fig
