"""The trend figure of a machine's history: each quantity at each date with its 95 % band, the forecast, the
tolerances and the flagged changes."""

from __future__ import annotations

import datetime

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..figure_style import COLOURS, figure, label, tight_layout
from .fit import HORIZON_YEARS, forecast_moments
from .model import SECONDS_PER_YEAR

#: how far the forecast band is drawn past the last campaign, as a share of the history's length (at least 90 days)
FORECAST_SHARE = 0.5


def trend_figure(result) -> Figure:
    """One panel per quantity: posterior mean and 95 % band at each campaign date (solid; at 20 °C when the
    temperatures are modelled, the values as measured then as grey crosses), the forecast band (dashed; a kept
    drift rate extrapolated), tolerance limits (red) and flagged changes (orange marks)."""
    hf, dates = result.fit, result.dates
    names = hf.quantities
    ncols = 4
    nrows = -(-len(names) // ncols)
    fig = figure(figsize=(13, 3.0 * nrows + 0.6))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True)
    span = max((dates[-1] - dates[0]).days * FORECAST_SHARE, 90.0)
    ahead = min(span, HORIZON_YEARS * 365.25)
    future = [dates[-1] + datetime.timedelta(days=float(x)) for x in np.linspace(0, ahead, 30)]
    years = np.linspace(0, ahead, 30) * 86400.0 / SECONDS_PER_YEAR
    flagged = {(c["quantity"], c["date"]) for c in result.flagged}
    for k, (ax, q) in enumerate(zip(axes.ravel(), names)):
        s = result.summary_at_20C.xs(q, level="quantity")
        ax.fill_between(dates, s["hdi_low"], s["hdi_high"], color=COLOURS["posterior"], alpha=0.25, lw=0)
        ax.plot(dates, s["mean"], "o-", color=COLOURS["posterior"], ms=4)
        if result.temperatures is not None:  # as measured, at the campaign's temperature
            measured = result.summary.xs(q, level="quantity")
            ax.plot(dates, measured["mean"], "x", color="0.35", ms=5)
        m, sd = forecast_moments(hf, k, years)
        lo = np.quantile(m - 1.96 * sd, 0.5, axis=0)
        hi = np.quantile(m + 1.96 * sd, 0.5, axis=0)
        ax.plot(future, lo, "--", color=COLOURS["posterior"], lw=1)
        ax.plot(future, hi, "--", color=COLOURS["posterior"], lw=1)
        tol = result.tolerances.get(q)
        if tol is not None:
            for v in tol:
                if np.isfinite(v):
                    ax.axhline(v, color="#C00000", lw=1)
        for when in dates:
            if (q, when) in flagged:
                ax.axvline(when, color="#E69F00", lw=2, alpha=0.8)
        ax.set_title(label(q), fontsize=10)
        ax.grid(alpha=0.25)
        ax.tick_params(axis="x", labelrotation=30, labelsize=8)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    at = "at 20 °C, " if result.temperatures is not None else ""
    handles = [Line2D([], [], color=COLOURS["posterior"], marker="o", ms=4, lw=6, alpha=0.5,
                      label=f"posterior mean and 95 % band ({at}all campaigns jointly)"),
               Line2D([], [], color=COLOURS["posterior"], ls="--", lw=1, label="forecast 95 % band"),
               Line2D([], [], color="#C00000", lw=1, label="tolerance"),
               Line2D([], [], color="#E69F00", lw=2, label="flagged change")]
    if result.temperatures is not None:
        handles.insert(1, Line2D([], [], color="0.35", marker="x", ls="", ms=5,
                                 label="as measured, at the campaign's temperature"))
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=9, frameon=False)
    tight_layout(fig, (0, 0, 1, 1 - 0.35 / fig.get_figheight()))
    return fig
