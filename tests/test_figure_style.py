"""Saving figures: drawn once at the report resolution, drawn again with a tight box only where something is cut."""

import numpy as np
import pytest
from PIL import Image

from mtmcal_bayes.figure_style import MAX_WIDTH_PX, PALETTE, new_figure, png_dpi, save_png, tight_layout, touches_edge


def _ink_columns(path) -> np.ndarray:
    """The columns of a saved PNG that hold anything but white."""
    rgb = np.asarray(Image.open(path).convert("RGB"))
    return np.flatnonzero((rgb < 250).any(axis=(0, 2)))


def test_a_figure_inside_its_canvas_is_saved_as_drawn(tmp_path):
    fig, ax = new_figure(figsize=(6, 3))
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("x [µm]")
    fig.tight_layout()
    save_png(fig, tmp_path / "inside.png")
    with Image.open(tmp_path / "inside.png") as img:
        assert img.mode == "P" and len(img.getcolors(PALETTE)) <= PALETTE
        assert img.size == (round(6 * png_dpi(fig)), round(3 * png_dpi(fig)))  # the canvas, not a re-cropped box
    assert not touches_edge(np.asarray(Image.open(tmp_path / "inside.png").convert("RGB")))


def test_a_text_beyond_the_canvas_grows_the_saved_figure_to_hold_it(tmp_path):
    fig, ax = new_figure(figsize=(6, 3))
    ax.plot([0, 1], [0, 1])
    fig.tight_layout()
    ax.text(0.9, 0.5, "a long annotation that runs well past the right edge of the figure", transform=ax.transAxes)
    save_png(fig, tmp_path / "spill.png")
    width = Image.open(tmp_path / "spill.png").size[0]
    assert width > 6 * png_dpi(fig) + 100  # the canvas grew by the text that did not fit
    assert _ink_columns(tmp_path / "spill.png").max() < width - 1  # and the text ends inside it


def test_a_wide_figure_is_saved_at_most_the_report_column_wide(tmp_path):
    fig, ax = new_figure(figsize=(20, 4))
    ax.plot([0, 1], [0, 1])
    fig.tight_layout()
    save_png(fig, tmp_path / "wide.png")
    assert Image.open(tmp_path / "wide.png").size[0] == MAX_WIDTH_PX


def test_the_edge_test_sees_one_dark_pixel_on_each_edge():
    blank = np.full((20, 30, 3), 255, np.uint8)
    assert not touches_edge(blank)
    for where in [(0, 10), (19, 10), (10, 0), (10, 29)]:
        marked = blank.copy()
        marked[where] = 0
        assert touches_edge(marked)
    inner = blank.copy()
    inner[1:-1, 1:-1] = 0
    assert not touches_edge(inner)


def test_a_figure_shown_elsewhere_keeps_its_canvas_and_resolution(tmp_path):
    """A figure of another canvas (here SVG, as a notebook's or a window's would be) is saved without being moved
    onto an Agg canvas, and its resolution is left as it was."""
    from matplotlib.backends.backend_svg import FigureCanvasSVG
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 3), dpi=72)
    canvas = FigureCanvasSVG(fig)
    ax = fig.add_subplot()
    ax.plot([0, 1], [1, 0])
    fig.tight_layout()
    save_png(fig, tmp_path / "elsewhere.png")
    assert fig.canvas is canvas and fig.dpi == 72
    assert Image.open(tmp_path / "elsewhere.png").size == (round(4 * png_dpi(fig)), round(3 * png_dpi(fig)))


@pytest.mark.parametrize("rows, cols", [(1, 1), (3, 1), (2, 3)])
@pytest.mark.parametrize("rect, kw", [((0, 0.08, 1, 1), {}), ((0, 0.05, 1, 1), {"h_pad": 2.5}),
                                      ((0, 0, 1, 0.93), {}), ((0.04, 0.1, 0.9, 0.95), {"h_pad": 0.6, "w_pad": 2.0})])
def test_tight_layout_in_one_pass_places_the_axes_where_matplotlibs_two_passes_do(rows, cols, rect, kw):
    """The subplot parameters of :func:`tight_layout` equal those of ``Figure.tight_layout(rect=…)`` (which
    measures the decorations twice) to round-off, for grids of axes with long labels and two-line titles."""
    def make():
        fig, axes = new_figure(rows, cols, figsize=(8, 6))
        for i, ax in enumerate(np.ravel(axes)):
            ax.plot([0, 10_000 * i + 1], [0, i])
            ax.set_title(f"panel {i}\nsecond line")
            ax.set_ylabel("a long label, µm")
            ax.set_xlabel("x")
        return fig

    theirs, ours = make(), make()
    theirs.tight_layout(rect=rect, **kw)
    tight_layout(ours, rect, **kw)
    keys = ("left", "right", "bottom", "top", "wspace", "hspace")
    np.testing.assert_allclose([getattr(ours.subplotpars, k) for k in keys],
                               [getattr(theirs.subplotpars, k) for k in keys], rtol=0, atol=1e-12)
