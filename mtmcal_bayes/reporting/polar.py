"""Polar ΔL trajectories of each ball-bar run, magnified as ball-bar software shows them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.lines import Line2D

from .. import units
from ..conventions import machine_repeats
from ..figure_style import COLOURS, figure
from ..io.machine_reader import description_of
from ..observations import Observations
from ..machines import patterns as described_patterns

CAPTION = (
    "Ball-bar trajectories as ball-bar software draws them: the change of bar length ΔL along the "
    "pattern, magnified radially (the dotted ring is ΔL = 0, radial ticks in µm) against the polar-plot "
    "angle: the B angle for B patterns over their 0–90° arc; for C patterns the direction of the bar over a "
    "full turn (the C angle, or C + 180° for CR with the T ball inside the W ball); on a machine described by its "
    "chain, the angle ψ of its eccentricity fit over the run's arc (docs/machines.md). Only the eccentricity part "
    "ΔL = e_a·u_a + e_b·u_b is drawn (the mean radius change is not modelled). Black: the eccentricity circle "
    "of the mean of the measured repeats; grey: each repeat; blue band: 95 % of the posterior's predicted "
    "trajectories (the model with the sampled deviations and mounting offsets, no measurement noise)."
)
N_BAND_DRAWS = 400
C_GRID_DEG = np.linspace(0.0, 360.0, 181)
#: the panels' layout, inches: margins at the sides, above (a panel's two-line title), below (the legend) and the
#: gaps between panels (a title and the angle labels beneath the panel above); fixed, not measured, since every
#: panel has the same decorations (measuring them was half the figure's time)
SIDE_IN, TOP_IN, BOTTOM_IN, ROW_GAP_IN, COLUMN_GAP_IN = 0.45, 0.85, 0.85, 1.15, 0.7


def _runs(campaign):
    """(run index, run, list of (observation index, component)) for every run with observations."""
    keys = Observations.from_campaign(campaign).keys
    out = {}
    for j, k in enumerate(keys):
        out.setdefault(k.run, []).append((j, k.component))
    return [(i, campaign.ballbar.runs[i], comps) for i, comps in sorted(out.items())]


@dataclass
class _Geometry:
    """How one run's ΔL is drawn: the polar angles ψ (k,) rad, ΔL's design matrix over them (k, 3) (columns 1 and
    the two components in the order ``components``), whether the arc is a part of a turn, and the mount in words."""

    psi: np.ndarray
    basis: np.ndarray
    components: tuple[str, str]
    partial: bool
    mount: str


def _geometry(run, campaign) -> _Geometry:
    """The polar geometry of ``run`` from its machine's description (SPEC §19): the angle ψ of the eccentricity fit
    over the run's arc (the B angle over a part turn; for a pattern over a turn, the direction of the bar, C or
    C + 180°), its components in the machine frame, the W ball and the tool length in words."""
    bb = campaign.ballbar
    s, m = bb.setups[run.setup], bb.mounts[run.mount]
    desc = description_of(campaign.machine)
    cmd = described_patterns.pattern_commands(desc, run.pattern, length=s.R_B, ball=m.centre(), bar=bb.length,
                                              arc_deg=bb.arc_of(run), hold_deg=run.hold_deg, reverse=bb.bar_reversed(run))
    psi = cmd.psi if np.ptp(cmd.psi) < np.deg2rad(300.0) else np.deg2rad(C_GRID_DEG)
    where = ", ".join(f"{v:g}" for v in m.centre())
    return _Geometry(psi, described_patterns.fit_basis(psi), described_patterns.components(desc, run.pattern),
                     np.ptp(psi) < np.deg2rad(300.0), f"R_B {s.R_B:g} mm, W ball at ({where}) mm")


def _dL(g: _Geometry, comps: list[str], values: np.ndarray) -> np.ndarray:
    """ΔL (..., k) from component values (..., len(comps)) over the run's polar angles."""
    cols = [1 + g.components.index(c) for c in comps]
    return values @ g.basis[:, cols].T


def polar_figure(result, campaign, seed: int = 0):
    """One polar panel per run: measured circle, repeats and the posterior band (µm)."""
    post = result.posterior
    flat = result.chains.reshape(-1, result.chains.shape[-1])
    rng = np.random.default_rng(seed)
    sub = flat[rng.choice(len(flat), min(N_BAND_DRAWS, len(flat)), replace=False)]
    pred = units.from_internal(post.forward.predict(sub[:, : post.p]), "um")  # (n, m)
    runs = _runs(campaign)
    ncols = min(3, len(runs))
    nrows = int(np.ceil(len(runs) / ncols))
    fig = figure(figsize=(5.0 * ncols, 5.2 * nrows + 0.6))
    for panel, (i, run, comps) in enumerate(runs, start=1):
        ax = fig.add_subplot(nrows, ncols, panel, projection="polar")
        idx = [j for j, _ in comps]
        names = [c for _, c in comps]
        g = _geometry(run, campaign)
        psi = g.psi
        machine = machine_repeats(run, campaign.ballbar)
        reps = np.column_stack([units.from_internal(machine[c], "um") for c in names])  # (r, len(comps))
        measured = _dL(g, names, reps.mean(axis=0))
        band = np.quantile(_dL(g, names, pred[:, idx]), [0.025, 0.975], axis=0)
        repeat_lines = _dL(g, names, reps)
        M = 1.15 * max(np.abs(measured).max(), np.abs(band).max(), np.abs(repeat_lines).max(), 1.0)
        ax.fill_between(psi, band[0], band[1], color=COLOURS["posterior"], alpha=0.35, lw=0)
        for r in repeat_lines:
            ax.plot(psi, r, color="0.55", lw=0.7)
        ax.plot(psi, measured, color=COLOURS["observed"], lw=1.6)
        ax.plot(psi, np.zeros_like(psi), color="0.3", lw=1.0, ls=":")
        ax.set_rorigin(-1.6 * M)
        ax.set_rlim(-M, M)
        ticks = np.array([-1, 0, 1]) * float(f"{M * 0.7:.1g}")
        ax.set_rticks(ticks, [f"{t:+g} µm" if t else "0" for t in ticks], fontsize=8)
        ax.set_rlabel_position(np.rad2deg(psi.min()) + 45 if g.partial else 112.5)
        if g.partial:
            ax.set_thetamin(np.rad2deg(psi.min()))
            ax.set_thetamax(np.rad2deg(psi.max()))
        ax.tick_params(axis="x", labelsize=8)
        e = ", ".join(f"{c} {v:+.1f}" for c, v in zip(names, reps.mean(axis=0)))
        held = "".join(f", {a} {v:g}° held" for a, v in (run.hold_deg or {}).items())
        ax.set_title(f"{run.pattern}{held} @ {run.setup}/{run.mount}  ({g.mount})\n"
                     f"measured: {e} µm", fontsize=9.5, pad=12)
    handles = [Line2D([], [], color=COLOURS["observed"], lw=1.6, label="measured (mean of repeats)"),
               Line2D([], [], color="0.55", lw=0.7, label="each repeat"),
               Line2D([], [], color=COLOURS["posterior"], lw=8, alpha=0.35, label="posterior 95 % band"),
               Line2D([], [], color="0.3", lw=1.0, ls=":", label="ΔL = 0")]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=9, frameon=False)
    _lay_out(fig, nrows, ncols)
    return fig


def _lay_out(fig, nrows: int, ncols: int) -> None:
    """Place the panels by the fixed margins and gaps (inches) of :data:`SIDE_IN` and the others."""
    W, H = fig.get_figwidth(), fig.get_figheight()
    panel_w = (W - 2 * SIDE_IN - (ncols - 1) * COLUMN_GAP_IN) / ncols
    panel_h = (H - TOP_IN - BOTTOM_IN - (nrows - 1) * ROW_GAP_IN) / nrows
    fig.subplots_adjust(left=SIDE_IN / W, right=1 - SIDE_IN / W, top=1 - TOP_IN / H, bottom=BOTTOM_IN / H,
                        wspace=COLUMN_GAP_IN / panel_w, hspace=ROW_GAP_IN / panel_h)
