"""The shared look of every figure the package draws: labels with units, colours, new figures, PNG output.

Figures are built with matplotlib's object API (:class:`matplotlib.figure.Figure`),
never through ``pyplot``: drawing a report selects no backend and opens no
window, so importing or running the package in a notebook leaves the user's
own plotting alone.  A figure module returns a ``Figure``; :func:`save_png`
writes it, and in a notebook it displays as any figure does.
"""

from __future__ import annotations

import io

import numpy as np
from matplotlib.figure import Figure

from . import units
from .iso import iso_symbol
from .models import MODELS
from .parameters import quantity_unit

#: colours of what the figures compare (colour-blind-safe Okabe–Ito palette)
COLOURS = {
    "posterior": "#0072B2",
    "ballbar": "#D55E00",
    "probe_reported": "#009E73",
    "probe_recomputed": "#CC79A7",
    "observed": "#000000",
    "prior": "#999999",
}
#: one colour per forward model in model comparisons, in the order of :data:`~mtmcal_bayes.models.MODELS`
MODEL_COLOURS = dict(zip(MODELS, ("#0072B2", "#E69F00", "#009E73")))
#: the ball-bar-only, probe-only, R-test-only and fused posteriors
DATA_COLOURS = {"ball bar only": "#0072B2", "probe only": "#CC79A7", "R-test only": "#009E73", "fused": "#000000"}

#: the label of each kind of deterministic value (:data:`~mtmcal_bayes.posterior.comparison.REFERENCES`): the thesis
#: plug-in's three, and the least squares of every machine
REFERENCE_LABELS = {
    "ballbar": "ball bar, deterministic (Eqs 4.10–4.18)",
    "probe_reported": "touch probe, as printed (Table 5.3)",
    "probe_recomputed": "touch probe, recomputed (Eqs 5.1–5.19)",
    "least_squares": "least squares (the kinematic model's first order)",
}

_GREEK = {"alpha": r"\alpha", "beta": r"\beta", "gamma": r"\gamma"}
DPI = 130
#: widest a saved figure is drawn, pixels: the report's column (``html_page``: 1180 px) shows it at its own size, so
#: a wider figure costs drawing time and bytes and shows nothing more
MAX_WIDTH_PX = 1180
#: colours of a saved figure
PALETTE = 256


def figure(**figure_kw) -> Figure:
    """A new figure on its own Agg canvas at the resolution it is saved at (:func:`png_dpi`): its layout
    (``tight_layout``) and its drawing then measure every text with one renderer, once."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(**figure_kw)
    if "dpi" not in figure_kw:
        fig.set_dpi(png_dpi(fig))
    FigureCanvasAgg(fig)
    return fig


def new_figure(nrows: int = 1, ncols: int = 1, **subplots_kw) -> tuple[Figure, object]:
    """A figure (:func:`figure`) and its axes (``Figure.subplots``): ``figsize`` and the other figure options go to
    the figure."""
    fig_kw = {k: subplots_kw.pop(k) for k in ("figsize", "dpi") if k in subplots_kw}
    fig = figure(**fig_kw)
    return fig, fig.subplots(nrows, ncols, **subplots_kw)


def tight_layout(fig: Figure, rect: tuple[float, float, float, float], **kw) -> None:
    """``fig.tight_layout(rect=rect, **kw)`` with one measuring pass instead of matplotlib's two.

    Given a ``rect``, matplotlib measures every axes' decorations (tick labels, titles: most of a layout's time)
    twice at the same axes positions, the second pass only to place the same margins inside ``rect``.  Here the
    figure is laid out once over its whole area and the subplot parameters are then moved into ``rect`` the way
    that second pass moves them: the margins shifted by the rect's edges, the same gaps in figure units
    between the axes (their ``wspace``/``hspace`` rescaled to the narrower axes).  ``kw``: ``pad``, ``h_pad``,
    ``w_pad`` as for ``Figure.tight_layout``.
    """
    fig.tight_layout(**kw)
    rl, rb, rr, rt = rect
    p = fig.subplotpars
    specs = [ax.get_subplotspec() for ax in fig.axes if ax.get_subplotspec() is not None]
    rows = max((ss.get_gridspec().nrows for ss in specs), default=1)
    cols = max((ss.get_gridspec().ncols for ss in specs), default=1)

    def spaced(space, span, new_span, n):  # the same gap between n axes over a span of the figure shrunk to new_span
        if n < 2:
            return space
        gap = space * span / (n + space * (n - 1))
        return gap / ((new_span - gap * (n - 1)) / n)

    left, right, bottom, top = rl + p.left, p.right - (1 - rr), rb + p.bottom, p.top - (1 - rt)
    fig.subplots_adjust(left=left, right=right, bottom=bottom, top=top,
                        wspace=spaced(p.wspace, p.right - p.left, right - left, cols),
                        hspace=spaced(p.hspace, p.top - p.bottom, top - bottom, rows))


def symbol(name: str) -> str:
    """Mathtext symbol of a quantity: ``beta_XB`` → ``$\\beta_{XB}$``; ``dx_CZ`` → ``$\\delta x_{CZ}$``."""
    if name == "dx_CZ_minus_dx_BT":
        return r"$\delta x_{CZ} - \delta x_{BT}$"
    if name == "sigma_model":
        return r"$\sigma_{model}$"
    head, _, sub = name.partition("_")
    if head in _GREEK:
        return f"${_GREEK[head]}_{{{sub}}}$"
    if head in ("dx", "dy", "dz"):
        return rf"$\delta {head[1]}_{{{sub}}}$"
    return name


def iso_mathtext(name: str) -> str:
    """Mathtext of a quantity's ISO 230-7 symbol (``E_A0B`` → ``$E_{A0B}$``), or "" where it has none."""
    s = iso_symbol(name)
    return f"$E_{{{s[2:]}}}$" if s else ""


def unit_symbol(name: str) -> str:
    """Display unit symbol of a quantity (″ or µm)."""
    return units.SYMBOL[quantity_unit(name)]


def label(name: str) -> str:
    """Axis label: symbol, ISO 230-7 symbol where there is one, and unit, e.g. ``$\\beta_{XB}$ ($E_{B0B}$) [″]``."""
    iso = iso_mathtext(name)
    return f"{symbol(name)}{f' ({iso})' if iso else ''} [{unit_symbol(name)}]"


def png_dpi(fig: Figure) -> float:
    """The resolution a figure is saved at: :data:`DPI`, lowered so that it is at most :data:`MAX_WIDTH_PX` wide."""
    return min(DPI, MAX_WIDTH_PX / fig.get_figwidth())


def warm_up() -> None:
    """Load what every figure needs once (fonts, the mathtext parser, the PNG writer) by saving a small figure: a
    process forked afterwards to draw figures inherits it instead of loading it again."""
    fig, ax = new_figure(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel(label("alpha_CZ"))
    ax.set_title("µm ″")
    fig.tight_layout()  # as every figure lays itself out: drawn once, not again through savefig's tight bbox
    save_png(fig, io.BytesIO())


def _savefig_rgb(fig: Figure, dpi: float, **savefig_kw) -> np.ndarray:
    """``fig`` through matplotlib's ``savefig`` at ``dpi`` (``savefig_kw`` passed on): ``(height, width, 3)`` uint8,
    by way of an intermediate PNG, compressed least, the fastest to write."""
    from PIL import Image

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": 1}, **savefig_kw)
    buf.seek(0)
    with Image.open(buf) as img:
        return np.asarray(img.convert("RGB"))


def _canvas_rgb(fig: Figure, dpi: float) -> np.ndarray:
    """``fig`` drawn once at ``dpi``: ``(height, width, 3)`` uint8.  On its Agg canvas (:func:`figure`; a bare
    ``Figure`` is given one); a figure shown elsewhere (pyplot, a notebook) keeps its own canvas and resolution and
    is drawn through ``savefig``."""
    from matplotlib.backend_bases import FigureCanvasBase
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg) and type(fig.canvas) is not FigureCanvasBase:
        return _savefig_rgb(fig, dpi)
    before = fig.dpi
    if before != dpi:
        fig.set_dpi(dpi)
    try:
        canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()
    finally:
        if fig.dpi != before:
            fig.set_dpi(before)


def touches_edge(rgb: np.ndarray) -> bool:
    """Whether anything is drawn on the outermost pixels of ``rgb`` ``(h, w, 3)`` (white elsewhere): a text or
    legend that reaches the edge was cut there."""
    edges = np.concatenate([rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]])
    return bool((edges < 250).any())


def save_png(fig: Figure, path) -> None:
    """Write ``fig`` as PNG at the report resolution (:func:`png_dpi`), in 256 colours (a palette PNG, a quarter of
    the bytes of the full-colour one: line plots and the corner plot's shades need no more; the report embeds
    every figure), compressed at zlib level 3 (half the time of the default 6 for 15 % more bytes: a report's
    eighteen figures 4 % sooner, its page 1.6 MB instead of 1.4).

    The figure is drawn once, as laid out (every figure lays itself out inside its canvas).  Only where that
    drawing reaches the canvas's edge (a label longer than its figure allows) is it drawn again with matplotlib's
    ``bbox_inches="tight"``, which grows the canvas to hold it — that costs a layout pass and a second drawing,
    40 % of a figure's time, so it is the exception, not the rule."""
    from PIL import Image

    rgb = _canvas_rgb(fig, png_dpi(fig))
    if touches_edge(rgb):
        rgb = _savefig_rgb(fig, png_dpi(fig), bbox_inches="tight")
    Image.fromarray(rgb).quantize(colors=PALETTE, method=Image.Quantize.FASTOCTREE,
                                  dither=Image.Dither.NONE).save(path, format="png", compress_level=3)
