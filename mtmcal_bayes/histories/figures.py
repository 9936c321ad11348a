"""The trend figure of a machine's history: each quantity at each date with its 95 % band, the forecast, the
tolerances and the flagged changes."""

from __future__ import annotations

import datetime

import numpy as np
from matplotlib.figure import Figure

from ..figure_style import COLOURS, label
from .fit import HORIZON_YEARS
from .model import SECONDS_PER_YEAR

#: how far the forecast band is drawn past the last campaign, as a share of the history's length (at least 90 days)
FORECAST_SHARE = 0.5


def trend_figure(result) -> Figure:
    """One panel per quantity: posterior mean and 95 % band at each campaign date (solid), the forecast band
    (dashed), tolerance limits (red) and flagged changes (orange marks)."""
    hf, dates = result.fit, result.dates
    names = hf.quantities
    ncols = 4
    nrows = -(-len(names) // ncols)
    fig = Figure(figsize=(13, 3.0 * nrows + 0.6))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True)
    span = max((dates[-1] - dates[0]).days * FORECAST_SHARE, 90.0)
    ahead = min(span, HORIZON_YEARS * 365.25)
    future = [dates[-1] + datetime.timedelta(days=float(x)) for x in np.linspace(0, ahead, 30)]
    years = np.linspace(0, ahead, 30) * 86400.0 / SECONDS_PER_YEAR
    flagged = {(c["quantity"], c["date"]) for c in result.flagged}
    for k, (ax, q) in enumerate(zip(axes.ravel(), names)):
        s = result.summary.xs(q, level="quantity")
        ax.fill_between(dates, s["hdi_low"], s["hdi_high"], color=COLOURS["posterior"], alpha=0.25, lw=0)
        ax.plot(dates, s["mean"], "o-", color=COLOURS["posterior"], ms=4)
        m = hf.mean[:, -1, k]
        sd = np.sqrt(hf.last_var[:, k][:, None] + hf.walk_var[:, k][:, None] * years[None, :])
        lo = np.quantile(m[:, None] - 1.96 * sd, 0.5, axis=0)
        hi = np.quantile(m[:, None] + 1.96 * sd, 0.5, axis=0)
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
    fig.tight_layout()
    return fig
