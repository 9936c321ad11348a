"""SBC figures: rank histograms (Talts et al. 2018) and ECDF-difference plots (Säilynoja et al. 2022)."""

from __future__ import annotations

import re
import warnings

import numpy as np
from scipy import stats

from ..arviz_import import az
from ..figure_style import COLOURS, new_figure, symbol

NCOLS = 4
#: an ISO 230-7 symbol in a described machine's quantity (``E_X(0C1)B``, also inside a combination's name)
ISO_SYMBOL = re.compile(r"\bE_([A-Z0-9()]+)")
#: a panel title longer than this (characters of the quantity's name) puts its p-value on a second line
TITLE_CHARS = 20


def _title(q: str, p: float) -> str:
    """A panel's title: the quantity's symbol (a described machine's ISO symbols as ``$E_{X0C}$``, a combination
    with its weights) and the p-value of its ranks."""
    if ISO_SYMBOL.search(q):
        return ISO_SYMBOL.sub(r"$E_{\1}$", q) + ("\n" if len(q) > TITLE_CHARS else "   ") + f"p = {p:.3f}"
    return f"{symbol(q)}   p = {p:.3f}"


def _grid(n: int, title: str):
    rows = -(-n // NCOLS)
    fig, axes = new_figure(rows, NCOLS, figsize=(3.3 * NCOLS, 2.6 * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize=11)
    return fig, axes.flat


def _flag(ax, p: float, threshold: float) -> None:
    """Title colour: red where the uniformity test fails (``p`` at or below ``threshold``)."""
    if p <= threshold:
        ax.title.set_color("#C00000")


def rank_histograms(result):
    """One rank histogram per quantity; grey band = 99 % range of a bin's count under uniform ranks."""
    counts, B, N = result.bin_counts(), result.n_bins, len(result.ranks)
    lo, hi = stats.binom.interval(0.99, N, 1.0 / B)
    s = result.summary()
    fig, axes = _grid(len(result.quantities),
                      f"SBC rank histograms — {result.settings.model}, {result.settings.sampler}, N = {N}, "
                      f"L = {result.settings.n_ranked}, {B} bins (grey: 99 % band of a uniform histogram)")
    for ax, q, c in zip(axes, result.quantities, counts):
        ax.axhspan(lo, hi, color=COLOURS["prior"], alpha=0.3, lw=0)
        ax.axhline(N / B, color=COLOURS["prior"], lw=1)
        ax.bar(np.arange(B), c, width=0.9, color=COLOURS["posterior"])
        ax.set_title(_title(q, s.loc[q, "p_uniform"]), fontsize=10)
        _flag(ax, s.loc[q, "p_uniform"], result.p_threshold)
        ax.set_xticks([0, B - 1], ["low", "high"])
        ax.set_ylim(0, max(hi, c.max()) * 1.15)
        ax.tick_params(labelsize=8)
    fig.supxlabel("rank of the truth among the posterior draws (binned)", fontsize=9)
    fig.supylabel("replicates", fontsize=9)
    fig.tight_layout()
    return fig


def ecdf_differences(result):
    """ECDF of the ranks minus the uniform CDF, with ArviZ's simultaneous 95 % band."""
    L1, N = result.settings.n_ranked + 1, len(result.ranks)
    uniform = stats.randint(0, L1)
    s = result.summary()
    fig, axes = _grid(len(result.quantities),
                      f"SBC ECDF difference — {result.settings.model}, {result.settings.sampler}, N = {N} "
                      "(band: simultaneous 95 % for uniform ranks)")
    points = np.arange(L1)
    for j, (ax, q) in enumerate(zip(axes, result.quantities)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # ArviZ's notice that its default algorithm may change
            az.plot_ecdf(result.ranks[:, j], cdf=uniform.cdf, difference=True, confidence_bands="simulated",
                         eval_points=points, rvs=lambda n, random_state=None: uniform.rvs(n, random_state=random_state),
                         random_state=np.random.default_rng(result.settings.seed), ci_prob=0.95, ax=ax,
                         plot_kwargs={"color": COLOURS["posterior"]}, fill_kwargs={"color": COLOURS["prior"],
                                                                                   "alpha": 0.3})
        ax.axhline(0, color="k", lw=0.6)
        ax.set_title(_title(q, s.loc[q, "p_uniform"]), fontsize=10)
        _flag(ax, s.loc[q, "p_uniform"], result.p_threshold)
        ax.set_xlim(0, L1 - 1)
        ax.tick_params(labelsize=8)
    fig.supxlabel(f"rank of the truth (0…{L1 - 1})", fontsize=9)
    fig.supylabel("ECDF − uniform CDF", fontsize=9)
    fig.tight_layout()
    return fig
