"""Draw docs/figures/pattern_frames.png and docs/figures/bx_by_readings.png: what a ball-bar centre offset means
in machine axes, pattern by pattern (docs/conventions.md).  Run from the repository root:

    python docs/figures/pattern_frames.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mtmcal_bayes import conventions as cv
from mtmcal_bayes.figure_style import new_figure, save_png
from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.campaign import Mount, Run, Setup
from mtmcal_bayes.patterns import B_PATTERNS, COMPONENTS, PATTERNS
from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands

OUT = Path(__file__).parent
#: the thesis' geometry (Tables 4.3 and Sec 4.3.2), a smaller R_B so the panels stay readable
GEO = {"R_B": 200.0, "Z_C": 65.5, "L_B": 100.0}
BAR_AXIS = {"BX": "X", "BY": "Y", "BZ": "Z", "BA": "Y", "CA": "Z", "CZ": "Z", "CX": "X", "CY": "Y"}


def _plane(pattern: str, cmd):
    """Commanded points in the pattern's plane (k, 2) and the out-of-plane coordinate."""
    if pattern in B_PATTERNS:
        return np.c_[cmd.X, cmd.Z], cmd.Y
    return np.c_[cmd.X, cmd.Y], cmd.Z


def _directions(convention: str, pattern: str, R_C: float) -> np.ndarray:
    """``D`` (2, 2) of ``convention`` for a run of thesis ``pattern`` at GEO, from the frame the package reads it
    against (the chain's), its columns along the pattern's plane axes (X, Z) or (X, Y)."""
    bb = load_campaign(None).ballbar
    bb.setups, bb.mounts, bb.length = {"S": Setup("S", GEO["R_B"], 0.0, 0.0)}, {"M": Mount("M", GEO["Z_C"], R_C)}, GEO["L_B"]
    frame = cv.run_frame(Run(pattern, "S", "M", {}, convention=convention), bb)
    return cv.frame_directions(convention, frame)[:, [frame.axes.index(a) for a in _axes(pattern)]]


def _axes(pattern: str) -> tuple[str, str]:
    """The pattern's plane axes in the thesis' order of its components: (X, Z) or (X, Y)."""
    return tuple(c[1].upper() for c in COMPONENTS[pattern])


def draw_pattern(ax, pattern: str, convention: str = "thesis", title: str | None = None) -> None:
    """One panel: the programmed path, the balls and the bar at 0°, where the samples at 0° and 90° are drawn,
    and the directions of positive offsets of the two components."""
    R_C = 0.0 if pattern in B_PATTERNS else 50.0
    full = np.linspace(0.0, 90.0 if pattern in B_PATTERNS else 360.0, 91)
    cmd = pattern_commands(pattern, R_B=GEO["R_B"], Z_C=GEO["Z_C"], R_C=R_C, L_B=GEO["L_B"], angles_deg=full)
    pts, _ = _plane(pattern, cmd)
    a0 = pattern_commands(pattern, R_B=GEO["R_B"], Z_C=GEO["Z_C"], R_C=R_C, L_B=GEO["L_B"],
                          angles_deg=np.array([0.0, 90.0, 180.0]))
    p0, _ = _plane(pattern, a0)
    centre = 0.5 * (p0[0] + p0[2])
    ax.plot(*pts.T, color="0.55", lw=1.2, label="programmed path")
    ax.plot(*centre, "+", color="0.4", ms=8)
    if pattern in B_PATTERNS:  # W on the C axis at the table height Z_C; T where the tool points at B = 0
        W = np.array([0.0, GEO["Z_C"]])
        T = p0[0] - GEO["R_B"] * np.array([0.0, 1.0])
    else:  # W on the table at radius R_C, C = 0; T below the commanded point (B = 0: the tool points to -Z)
        W = np.array([R_C, 0.0])
        T = p0[0]
    ax.plot(*W, "o", color="#0072B2", ms=7, label="W ball")
    ax.plot(*T, "o", color="#D55E00", ms=7, label="T ball at 0°")
    if np.linalg.norm(T - W) > 1e-6:
        ax.plot([W[0], T[0]], [W[1], T[1]], color="k", lw=2.2, label="bar at 0°")
    D = _directions(convention, pattern, R_C)
    r = 0.5 * float(np.linalg.norm(p0[0] - centre))
    angle = "B" if pattern in B_PATTERNS else "C"
    for d, lab, col in ((D[0], f"{angle} = 0°", "#009E73"), (D[1], f"{angle} = 90°", "#CC79A7")):
        ax.annotate("", xy=centre + r * d, xytext=centre, arrowprops=dict(arrowstyle="-|>", color=col, lw=1.8))
        ax.plot(*(centre + 1.5 * r * d), alpha=0.0)  # keeps the arrow and its label inside the axes
        ax.text(*(centre + 1.3 * r * d + np.array([0.0, 0.15 * r * abs(d[0])])), lab, color=col, ha="center",
                va="center", fontsize=8, fontweight="bold")
    axes = _axes(pattern)
    comps = COMPONENTS[pattern]
    ax.set_xlabel(f"{axes[0]} [mm]")
    ax.set_ylabel(f"{axes[1]} [mm]")
    bar = BAR_AXIS.get(pattern)
    note = f"bar along +{bar}" if bar and bar not in axes else ""
    ax.set_title(title or f"{pattern}: +{comps[0]} → +{axes[0]}, +{comps[1]} → +{axes[1]}" + (f"\n{note}" if note else ""),
                 fontsize=9)
    ax.set_aspect("equal")
    ax.margins(0.25)
    ax.tick_params(labelsize=7)


def main() -> None:
    fig, axs = new_figure(3, 4, figsize=(15, 11.5))
    for ax, p in zip(axs.ravel(), PATTERNS):
        draw_pattern(ax, p)
    handles, labels = axs[0, 3].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=9, frameon=False)
    fig.suptitle("The machine frame of every pattern (convention \"thesis\"): the programmed path, the bar at 0°, "
                 "where the samples at 0° and 90° stand (their ΔL is the offset's component along that direction)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    save_png(fig, OUT / "pattern_frames.png")

    built_in = {run.pattern: run.convention for run in load_campaign(None).ballbar.runs if run.pattern in ("BX", "BY")}
    fig, axs = new_figure(2, 2, figsize=(10, 9.5))
    for col, p in enumerate(("BX", "BY")):
        draw_pattern(axs[0, col], p, "thesis", f"{p}, the thesis' reading (\"thesis\")")
        extra = ": B = 0° at −Z, 90° at +X,\nthe bar at −Y of the W ball drawn as the thesis draws it at +Y" if p == "BY" else ""
        draw_pattern(axs[1, col], p, built_in[p], f"{p}, the built-in campaign's reading \"{built_in[p]}\"{extra}")
    fig.suptitle("Table 4.4's B runs: where the thesis reads the samples, and where the touch probe's evidence "
                 "puts them (docs/thesis-notes.md)", fontsize=10)
    fig.tight_layout()
    save_png(fig, OUT / "bx_by_readings.png")


if __name__ == "__main__":
    main()
