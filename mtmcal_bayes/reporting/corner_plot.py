"""Corner plot of the quantities a report draws together, with deterministic values marked: the thesis' where the
machine's plug-in gives them (ball bar as lines, touch probe as lines and markers), else the least squares."""

from __future__ import annotations

import corner
import numpy as np
import pandas as pd
from matplotlib.contour import ContourSet
from matplotlib.lines import Line2D

from ..figure_style import COLOURS, REFERENCE_LABELS, figure, label, symbol, unit_symbol
from ..posterior.comparison import REFERENCES

#: probability mass inside the 2-D contours (corner's own default is 0.5σ…2σ of a 2-D Gaussian)
LEVELS = (0.68, 0.95)
#: a reference value further than this many posterior sd from the mean is not drawn, but listed
OFF_SCALE_SD = 8.0
MAX_POINTS = 40_000
#: how the individual draws are drawn (corner's ``data_kwargs``, with corner's own marker, zorder and rasterising)
DRAW_STYLE = {"alpha": 0.02, "ms": 1.5, "mec": "none", "zorder": -1, "rasterized": True}
#: a draw at least this far inside the fill that hides the densest draws is left out, pixels (its marker is
#: about 1.4 px wide at the report's resolution; the rest is room for antialiasing)
HIDDEN_MARGIN_PX = 3.0

#: the caption where the thesis' values are drawn
CAPTION = (
    "Corner plot of the posterior of the eight quantities the thesis identifies. Diagonal: marginal "
    "histograms with the posterior mean ± sd as title. Off-diagonal: 2-D histograms of the draws "
    "with contours enclosing 68 % and 95 % of the posterior mass (set explicitly; corner's default "
    "levels would be 11.8/39.3/67.5/86.5 %, the 0.5σ–2σ levels of a 2-D Gaussian), individual draws "
    "outside them. Orange lines: the ball-bar deterministic values (thesis Eqs 4.10–4.18 recomputed); "
    "green: the touch-probe values as printed (Table 5.3); pink dashed: the touch-probe values "
    "recomputed from Table 5.2 (Eqs 5.1–5.19). Strong diagonal ridges are quantities the data tie "
    "together (e.g. β_XB with δx_CZ − δx_BT through dx_BT)."
)
#: the caption where the least squares are drawn (a machine whose plug-ins give no values of their own)
LEAST_SQUARES_CAPTION = (
    "Corner plot of the posterior of the deviations this campaign determines (one by one or in combination). "
    "Diagonal: marginal histograms with the posterior mean ± sd as title. Off-diagonal: 2-D histograms with contours "
    "enclosing 68 % and 95 % of the posterior mass; a narrow diagonal ridge is a combination the data determine "
    "better than its terms. Orange lines: the least-squares identification of each deviation determined one by one."
)


def _draws(idata, names: list[str], seed: int = 0) -> np.ndarray:
    """(N, len(names)) posterior draws, at most :data:`MAX_POINTS`, evenly chosen."""
    cols = [np.asarray(idata.posterior[n]).ravel() for n in names]
    x = np.column_stack(cols)
    if len(x) > MAX_POINTS:
        x = x[np.random.default_rng(seed).choice(len(x), MAX_POINTS, replace=False)]
    return x


def _ranges(x: np.ndarray, refs: dict[str, list], names) -> tuple[list, list[str]]:
    """Axis range per quantity covering the draws and the reference values within reach (``refs``: those drawn)."""
    ranges, off = [], []
    mean, sd = x.mean(axis=0), x.std(axis=0)
    for i, n in enumerate(names):
        lo, hi = np.quantile(x[:, i], [0.001, 0.999])
        for key, values in refs.items():
            v = values[i]
            if v is None:
                continue
            if abs(v - mean[i]) > OFF_SCALE_SD * sd[i]:
                off.append(f"{n}: {REFERENCE_LABELS[key]} {v:.2f} {unit_symbol(n)} "
                           f"({(v - mean[i]) / sd[i]:+.0f} sd, off scale)")
            else:
                lo, hi = min(lo, v), max(hi, v)
        pad = 0.05 * (hi - lo)
        ranges.append((lo - pad, hi + pad))
    return ranges, off


def reference_values(comparison: pd.DataFrame, names) -> dict[str, list]:
    """Per reference kind (:data:`~mtmcal_bayes.posterior.comparison.REFERENCES`), a list aligned with ``names`` of
    values (display units) or None."""
    out = {}
    for key in REFERENCES:
        vals = []
        for n in names:
            v = comparison.loc[n, key] if n in comparison.index and key in comparison else None
            vals.append(None if v is None or not np.isfinite(v) else float(v))
        out[key] = vals
    return out


def _corner_size(K: int) -> float:
    """Side of corner's own figure for K quantities, inches (corner sizes only the figures it creates)."""
    factor, whspace = 2.0, 0.05
    return 0.5 * factor + factor * K + factor * (K - 1.0) * whspace + 0.2 * factor


def _shown_draws(ax, xy: np.ndarray) -> np.ndarray:
    """The draws ``xy`` ``(N, 2)`` of one 2-D panel that can be seen: those not under corner's opaque fill of the
    region inside the outer contour (drawn over the draws, it hides them; 95 % of them here).  Leaving the hidden
    ones out draws the same image with a twentieth of the markers.  Should the panel not hold exactly one filled
    contour set (another corner), every draw is kept."""
    fills = [c for c in ax.collections if isinstance(c, ContourSet) and c.filled]
    if len(fills) != 1:
        return xy
    pixels = ax.transData.transform(xy)
    hidden = np.zeros(len(xy), dtype=bool)
    for path in fills[0].get_paths():
        if len(path.vertices) < 3:
            continue
        path = path.transformed(ax.transData)
        # contains_points widens a path by radius/2 on the side its orientation gives: the sign that shrinks this
        # one's filled area (its signed area says which way round it goes)
        x, y = path.vertices[:, 0], path.vertices[:, 1]
        area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
        hidden |= path.contains_points(pixels, radius=-2.0 * HIDDEN_MARGIN_PX * np.sign(area))
    return xy[~hidden]


class _LowerTriangle:
    """A figure as ``corner.corner`` is given it: the figure's attributes, and its ``axes`` as the K×K cells corner
    reshapes them into, each cell on or below the diagonal an axes of its own and every cell above it one shared
    placeholder (:meth:`remove_placeholder` takes it off afterwards).

    Corner only blanks the cells above the diagonal (frame and ticks off); made as axes of their own they were 28
    of the 64 axes of an eight-quantity plot, a fifth of its drawing time, for nothing drawn."""

    def __init__(self, fig, K: int):
        grid = fig.add_gridspec(K, K)
        cells = {(i, j): fig.add_subplot(grid[i, j]) for i in range(K) for j in range(i + 1)}  # corner's order
        self.placeholder = fig.add_subplot(grid[0, K - 1]) if K > 1 else None
        self.axes = [cells.get((i, j), self.placeholder) for i in range(K) for j in range(K)]
        self.figure = fig

    def __getattr__(self, name):
        return getattr(self.figure, name)

    def remove_placeholder(self):
        if self.placeholder is not None:
            self.placeholder.remove()


def _line_key(refs: dict[str, list]) -> str:
    """The kind of reference drawn as corner's truth lines: the thesis' ball-bar values where there are any, else
    the least squares (the touch-probe values are drawn beside them in a style of their own)."""
    return "ballbar" if any(v is not None for v in refs["ballbar"]) else "least_squares"


def caption(comparison: pd.DataFrame, names) -> str:
    """The corner figure's caption for the reference values it draws of ``names``."""
    return CAPTION if _line_key(reference_values(comparison, names)) == "ballbar" else LEAST_SQUARES_CAPTION


def corner_figure(idata, comparison: pd.DataFrame, names):
    """The corner figure and a list of reference values left off the axes (too far away)."""
    names = [n for n in names if n in idata.posterior]
    x = _draws(idata, names)
    refs = reference_values(comparison, names)
    line_key = _line_key(refs)  # drawn as corner's truths
    drawn = (line_key, "probe_reported", "probe_recomputed")
    ranges, off = _ranges(x, {k: refs[k] for k in drawn}, names)
    K = len(names)
    cells = _LowerTriangle(figure(figsize=(_corner_size(K),) * 2), K)
    corner.corner(
        x, fig=cells, labels=[label(n) for n in names], range=ranges, bins=30, smooth=1.0, levels=LEVELS,
        color=COLOURS["posterior"], truths=refs[line_key], truth_color=COLOURS["ballbar"],
        plot_datapoints=False, label_kwargs={"fontsize": 13}, max_n_ticks=4, labelpad=0.08,
    )
    cells.remove_placeholder()
    fig = cells.figure
    axes = np.array(cells.axes).reshape(K, K)
    for i in range(K):  # the draws, under corner's fill as corner draws them, those the fill hides left out
        for j in range(i):
            shown = _shown_draws(axes[i, j], x[:, [j, i]])
            axes[i, j].plot(shown[:, 0], shown[:, 1], "o", color=COLOURS["posterior"], **DRAW_STYLE)
    mean, sd = x.mean(axis=0), x.std(axis=0)
    for i, n in enumerate(names):
        axes[i, i].set_title(f"{symbol(n)} = {mean[i]:.1f} ± {sd[i]:.1f} {unit_symbol(n)}", fontsize=11)
    styles = {"probe_reported": dict(color=COLOURS["probe_reported"], ls="-", marker="s"),
              "probe_recomputed": dict(color=COLOURS["probe_recomputed"], ls="--", marker="D")}
    for key, st in styles.items():
        v = refs[key]
        for i in range(K):
            if v[i] is None or not ranges[i][0] <= v[i] <= ranges[i][1]:
                continue
            for r in range(i, K):
                axes[r, i].axvline(v[i], color=st["color"], ls=st["ls"], lw=1.3)
            for c in range(i):
                axes[i, c].axhline(v[i], color=st["color"], ls=st["ls"], lw=1.3)
                if v[c] is not None and ranges[c][0] <= v[c] <= ranges[c][1]:
                    axes[i, c].plot(v[c], v[i], marker=st["marker"], color=st["color"], ms=6, mec="white")
    handles = [Line2D([], [], color=COLOURS["posterior"], lw=6, alpha=0.5, label="posterior (68 % / 95 % contours)")]
    if any(v is not None for v in refs[line_key]):
        handles.append(Line2D([], [], color=COLOURS["ballbar"], lw=1.5,
                              label=REFERENCE_LABELS[line_key]))
    for key, st in styles.items():
        if any(v is not None for v in refs[key]):
            handles.append(Line2D([], [], color=st["color"], ls=st["ls"], marker=st["marker"], lw=1.3,
                                  label=REFERENCE_LABELS[key]))
    fig.legend(handles=handles, loc="upper right", bbox_to_anchor=(0.95, 0.95), fontsize=14, frameon=False)
    return fig, off
