"""Shared look of the report figures: labels with units, colours, PNG output.

Every figure module draws on a non-interactive backend and returns a
:class:`matplotlib.figure.Figure`; :func:`save_png` writes it.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from .. import units  # noqa: E402
from ..parameters import QUANTITIES  # noqa: E402

#: colours of what the figures compare (colour-blind-safe Okabe–Ito palette)
COLOURS = {
    "posterior": "#0072B2",
    "ballbar": "#D55E00",
    "probe_reported": "#009E73",
    "probe_recomputed": "#CC79A7",
    "observed": "#000000",
    "prior": "#999999",
}
#: one colour per forward model in model comparisons
MODEL_COLOURS = {"linear": "#0072B2", "htm-literal": "#E69F00", "htm-thesis": "#009E73"}

REFERENCE_LABELS = {
    "ballbar": "ball bar, deterministic (Eqs 4.10–4.18)",
    "probe_reported": "touch probe, as printed (Table 5.3)",
    "probe_recomputed": "touch probe, recomputed (Eqs 5.1–5.19)",
}

_GREEK = {"alpha": r"\alpha", "beta": r"\beta", "gamma": r"\gamma"}
DPI = 130


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


def unit_symbol(name: str) -> str:
    """Display unit symbol of a quantity (″ or µm)."""
    unit = "um" if name == "sigma_model" else QUANTITIES[name].unit
    return units.SYMBOL[unit]


def label(name: str) -> str:
    """Axis label: symbol and unit, e.g. ``$\\beta_{XB}$ [″]``."""
    return f"{symbol(name)} [{unit_symbol(name)}]"


def save_png(fig, path) -> None:
    """Write ``fig`` as PNG at the report resolution and release it."""
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
