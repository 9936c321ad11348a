"""Figures of a described machine (SPEC §19, docs/machines.md): its chain at the home pose, and what each of its
location errors means.

:func:`chain_figure` draws the machine at the home pose (every axis at 0) in its own frame: the frame axes, each
rotary axis' nominal line through its ``point_mm`` with the sense of a positive turn, the spindle from its
``point_mm`` along its direction with a nominal tool, the directions in which a positive command of each linear
axis moves the tool (tool side) or the workpiece (a primed axis: the opposite way), and the chain from workpiece
to tool beneath.  :func:`deviations_figure` sketches, per rotary axis and for the spindle, the nominal line and the
line that a positive value of each of its location errors puts in its place, as the chain
(:class:`~mtmcal_bayes.machines.chain.Chain`) displaces it, exaggerated; and the squareness of the linear axes.
Errors left out of the default set (:func:`~mtmcal_bayes.machines.selection.redundant`) are drawn in grey.
"""

from __future__ import annotations

import textwrap

from pathlib import Path

import numpy as np
from matplotlib import rc_context
from matplotlib.figure import Figure
from matplotlib.patches import FancyBboxPatch

from ..figure_style import figure, save_png, tight_layout
from ..io.machine_reader import description_of
from ..machines.chain import Chain
from ..machines.description import FRAME, SPINDLE, MachineDescription, along_frame, inclined_basis
from ..machines.deviations import (
    SQUARENESS_ERRORS,
    Deviation,
    generated,
    spindle_basis,
    spindle_own_basis,
)
from ..machines.plugins import provided
from ..machines.rotations import rotation
from ..machines.selection import redundant, selected

WORK = "#0072B2"  # what moves the workpiece
TOOL = "#D55E00"  # what moves the tool
SPINDLE_COLOUR = "#000000"
FRAME_COLOUR = "0.45"
LEFT_OUT = "0.55"  # errors not in the default set
#: length of the nominal tool drawn from the spindle's point_mm, mm
TOOL_MM = 150.0
#: exaggeration of the location errors in the sketches: a position error as this fraction of the line drawn, an
#: orientation error as this angle
SHIFT = 0.25
TILT_DEG = 12.0
ZERO_DEG = 25.0
#: 8 pt characters a line of the figure's notes holds per inch of the figure's width (with a margin)
NOTE_CHARS_PER_IN = 15



def _unit(i: int) -> np.ndarray:
    e = np.zeros(3)
    e[i] = 1.0
    return e


def _direction_text(v: np.ndarray) -> str:
    """``+Y`` for a frame axis, the vector ``[0, 0.7071, 0.7071]`` for an inclined direction."""
    if not along_frame(v):
        return "[" + ", ".join(f"{float(c):.4g}" for c in np.asarray(v) + 0.0) + "]"
    i = int(np.argmax(np.abs(v)))
    return f"{'+' if v[i] > 0 else '−'}{FRAME[i]}"


def _point_text(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:g}" for x in p) + ")"


def _prime(letter: str, work_side: bool) -> str:
    return letter + ("′" if work_side else "")


def mathtext(symbol: str) -> str:
    """``E_X(0C1)B`` → ``$E_{X(0C1)B}$``."""
    return f"$E_{{{symbol[2:]}}}$" if symbol.startswith("E_") else symbol


def _label(d: Deviation) -> str:
    """A deviation's ISO symbol, with its thesis name beside it where it has one."""
    return mathtext(d.symbol) + (f" = {d.name}" if d.name != d.symbol else "")


# --------------------------------------------------------------------------------------------------------------
# the chain at the home pose


def _extent(desc: MachineDescription, tool_mm: float) -> float:
    pts = [a.point for a in desc.rotary_axes] + [desc.spindle.point,
                                                  desc.spindle.point + tool_mm * desc.spindle.direction]
    return max(float(np.abs(np.array(pts)).max()), tool_mm)


def campaign_tool(campaign) -> tuple[float, str]:
    """The tool a campaign's figure draws: ``(length mm, whose)`` — its first ball-bar set-up's tool length, else
    its first stylus, else a nominal :data:`TOOL_MM`."""
    setups = campaign.ballbar.setups
    if setups:
        sid, setup = next(iter(setups.items()))
        return float(setup.R_B), f"set-up {sid}'s tool length"
    styli = getattr(campaign.probe, "styli", None) or {}
    if styli:
        sid, length = next(iter(styli.items()))
        return float(length), f"stylus {sid}'s length"
    return TOOL_MM, "a nominal length"


def figure_jobs(campaign) -> list:
    """The drawing jobs of the figures of the campaign's machine (``machine.png`` with the campaign's tool,
    ``deviations.png``): they need the campaign alone (a report begins them before anything else,
    :mod:`~.start`)."""
    description, tool = description_of(campaign.machine), campaign_tool(campaign)
    return [("machine.png", lambda: chain_figure(description, tool)),
            ("deviations.png", lambda: deviations_figure(description))]


def _arc3d(ax, centre: np.ndarray, d: np.ndarray, *, radius: float, colour: str) -> None:
    """A circular arrow about ``d`` at ``centre``: the sense of a positive (right-handed) turn."""
    k = int(np.argmax(np.abs(d)))
    u, w = _unit((k + 1) % 3), _unit((k + 2) % 3)
    if d[k] < 0:
        u, w = w, u  # (u, w, d) right-handed
    if not along_frame(d):
        u, w = inclined_basis(d)  # (u, v, d) right-handed
    t = np.deg2rad(np.linspace(20.0, 300.0, 40))
    pts = centre + radius * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * w)
    ax.plot(*pts.T, color=colour, lw=1.2)
    tangent = -np.sin(t[-1]) * u + np.cos(t[-1]) * w
    ax.quiver(*pts[-1], *(0.5 * radius * tangent), color=colour, lw=1.2, arrow_length_ratio=0.9)


def chain_figure(desc: MachineDescription, tool: tuple[float, str] | None = None) -> Figure:
    """The machine at the home pose, in 3-D, with a key of its axes beside it and its chain from workpiece to tool
    beneath; ``tool`` = (length mm, whose) the tool drawn from the spindle's point (default a nominal
    :data:`TOOL_MM`; a campaign's: :func:`campaign_tool`)."""
    tool_mm, whose = tool or (TOOL_MM, "a nominal length")
    fig = figure(figsize=(8.6, 8.8))
    with rc_context({"grid.color": "0.87", "grid.linewidth": 0.5}):  # a light grid: read when the axes is made
        ax = fig.add_axes((0.12, 0.17, 0.88, 0.70), projection="3d")
    L = _extent(desc, tool_mm)
    half = 1.2 * L
    # the frame axes through the origin, named at their + end
    for i in range(3):
        e = _unit(i)
        ax.plot(*np.c_[-half * e, half * e], color=FRAME_COLOUR, lw=0.8, ls=":")
        ax.text(*(1.05 * half * e), f"+{FRAME[i]}", color=FRAME_COLOUR, fontsize=9, ha="center", va="center")
    ax.scatter([0], [0], [0], color=FRAME_COLOUR, s=12)
    # rotary axes: nominal lines through point_mm, the letter at the + end (the − end where the tool is)
    ell = max(0.55 * L, 110.0)  # half the length of a line drawn
    s = desc.spindle
    tip = s.point + tool_mm * s.direction
    for a in desc.rotary_axes:
        colour = WORK if a.work_side else TOOL
        ax.plot(*np.c_[a.point - ell * a.direction, a.point + ell * a.direction], color=colour, lw=2.2, ls="-.")
        ax.scatter(*a.point, color=colour, s=30, depthshade=False)
        _arc3d(ax, a.point + 0.75 * ell * a.direction, a.direction, radius=0.16 * ell, colour=colour)
        at = a.point + 1.12 * ell * a.direction
        if min(np.linalg.norm(at - tip), np.linalg.norm(at - s.point)) < 0.3 * L:
            at = a.point - 1.12 * ell * a.direction
        ax.text(*at, _prime(a.letter, a.work_side), color=colour, fontsize=13, fontweight="bold", ha="center",
                va="center")
    # the spindle and a nominal tool
    ax.plot(*np.c_[s.point, tip], color=SPINDLE_COLOUR, lw=3.2)
    ax.scatter(*s.point, color=SPINDLE_COLOUR, marker="s", s=34, depthshade=False)
    ax.scatter(*tip, color=SPINDLE_COLOUR, s=55, depthshade=False)
    beside = _unit(2 if s.frame_axis == 0 else 0)  # a frame axis across the tool
    ax.text(*(tip + 0.08 * L * beside), "tool tip", color=SPINDLE_COLOUR, fontsize=9, ha="left", va="center")
    # the linear axes: which way a positive command moves the tool, or (primed) the workpiece
    anchor = np.array([-0.8 * half, -0.8 * half, -0.8 * half])
    n_arrow = 0.42 * half
    for a in desc.work_chain + desc.tool_chain:
        if a.rotary:
            continue
        colour = WORK if a.work_side else TOOL
        d = -a.direction if a.work_side else a.direction
        ax.quiver(*anchor, *(n_arrow * d), color=colour, lw=2.0, arrow_length_ratio=0.2)
        ax.text(*(anchor + 1.25 * n_arrow * d), _prime(a.letter, a.work_side), color=colour, fontsize=11,
                fontweight="bold", ha="center", va="center")
    for set_lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        set_lim(-half, half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [mm]", labelpad=-2)
    ax.set_ylabel("y [mm]", labelpad=-2)
    ax.set_zlabel("z [mm]", labelpad=-2)
    ax.tick_params(labelsize=7, pad=0)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_pane_color((1.0, 1.0, 1.0, 0.0))
    ax.view_init(elev=22, azim=-58)
    fig.text(0.5, 0.985, f"{desc.name or desc.builtin or 'machine'}:  {desc.configuration}", ha="center", va="top",
             fontsize=13, fontweight="bold")
    fig.text(0.5, 0.95, "the home pose (every axis at 0) in the machine frame (dotted: its axes through the "
             "origin); blue moves the workpiece, orange the tool", ha="center", va="top", fontsize=8.5,
             color="0.25")
    _key(fig, desc, tool_mm, whose)
    _chain_strip(fig.add_axes((0.03, 0.01, 0.94, 0.15)), desc)
    return fig


def _key(fig: Figure, desc: MachineDescription, tool_mm: float, whose: str) -> None:
    """What the 3-D view shows, one coloured line per axis, at the figure's upper left."""
    lines: list[tuple[str, str]] = []
    for a in desc.rotary_axes:
        travel = f", travel {np.rad2deg(a.travel[0]):g}…{np.rad2deg(a.travel[1]):g}°" if a.travel else ""
        lines.append((f"{_prime(a.letter, a.work_side)}: rotary, {_direction_text(a.direction)} through "
                      f"{_point_text(a.point)} mm{travel}", WORK if a.work_side else TOOL))
    s = desc.spindle
    carrier = "the bed" if s.carrier == "b" else f"the {s.carrier} axis"
    lines.append((f"spindle (C1) on {carrier}: {_direction_text(s.direction)} from {_point_text(s.point)} mm "
                  f"(■), tool {tool_mm:g} mm drawn ({whose})", SPINDLE_COLOUR))
    tool = [a.letter for a in desc.tool_chain if not a.rotary]
    work = [a.letter for a in desc.work_chain if not a.rotary]
    if tool:
        lines.append((f"arrows {', '.join(tool)}: a + command moves the tool along +{', +'.join(tool)}", TOOL))
    if work:
        lines.append((f"arrows {', '.join(a + '′' for a in work)}: a + command moves the workpiece along "
                      f"−{', −'.join(work)} (the tool + relative to it)", WORK))
    lines.append(("dash-dot: a rotary axis' nominal line; circular arrow: its positive (right-handed) turn",
                  "0.25"))
    y = 0.915
    for text, colour in lines:
        fig.text(0.03, y, text, fontsize=8.5, color=colour, va="top")
        y -= 0.021


def _chain_strip(ax, desc: MachineDescription) -> None:
    """The chain from workpiece to tool as a row of boxes, each axis with its direction or travel."""
    items: list[tuple[str, str, str]] = [("w", "workpiece", WORK)]
    for a in reversed(desc.work_chain):  # from the workpiece to the bed
        items.append((_prime(a.letter, True), _axis_note(a), WORK))
    items.append(("b", "bed", FRAME_COLOUR))
    for a in desc.tool_chain:
        items.append((a.letter, _axis_note(a), TOOL))
    items.append(("(C1)", "spindle " + _direction_text(desc.spindle.direction), SPINDLE_COLOUR))
    items.append(("t", "tool", SPINDLE_COLOUR))
    n = len(items)
    xs = np.arange(n)
    for x, (token, note, colour) in zip(xs, items):
        ax.add_patch(FancyBboxPatch((x - 0.3, -0.25), 0.6, 0.5, boxstyle="round,pad=0.02", fc="white", ec=colour,
                                    lw=1.6))
        ax.text(x, 0.0, token, ha="center", va="center", fontsize=12, fontweight="bold", color=colour)
        ax.text(x, -0.42, note, ha="center", va="top", fontsize=7.5, color="0.2")
        if x:
            ax.plot([x - 0.7, x - 0.3], [0, 0], color="0.4", lw=1.0)
    ax.text(-0.45, 0.45, "chain from workpiece to tool (each axis carries those farther from the bed b):",
            fontsize=8.5, color="0.25", va="bottom")
    ax.set_xlim(-0.55, n - 0.45)
    ax.set_ylim(-1.0, 0.75)
    ax.axis("off")


def _axis_note(a) -> str:
    if a.rotary:
        note = _direction_text(a.direction)
        if a.travel is not None:
            note += f"\n{np.rad2deg(a.travel[0]):g}…{np.rad2deg(a.travel[1]):g}°"
        return note
    note = "linear"
    if a.travel is not None:
        note += f"\n{a.travel[0]:g}…{a.travel[1]:g} mm"
    return note


# --------------------------------------------------------------------------------------------------------------
# what the location errors mean


def _basis(h: int, v: int) -> tuple[np.ndarray, str]:
    """The panel's out-of-plane frame axis as the viewer sees it: ``⊙`` toward the viewer, ``⊗`` away."""
    n = np.cross(_unit(h), _unit(v))
    k = int(np.argmax(np.abs(n)))
    return n, ("⊙ +" if n[k] > 0 else "⊗ +") + FRAME[k]


def _panel_frame(ax, h: int, v: int, *, extent: float, centre: np.ndarray) -> None:
    ax.set_xlim(centre[h] - extent, centre[h] + extent)
    ax.set_ylim(centre[v] - extent, centre[v] + extent)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    _axis_labels(ax, h, v)


def _axis_labels(ax, h: int, v: int) -> None:
    """The panel's frame axes: across, up, and out of the page."""
    _, out = _basis(h, v)
    ax.set_xlabel(f"+{FRAME[h]} →        ({out} out of the page)", fontsize=8, labelpad=2)
    ax.set_ylabel(f"+{FRAME[v]} →", fontsize=8, labelpad=2)
    for spine in ax.spines.values():
        spine.set_color("0.7")


def _line_panel(ax, chain: Chain, body: str, *, point: np.ndarray, direction: np.ndarray, length: float,
                h: int, v: int, shift: Deviation | None, tilt: Deviation | None, colour: str, grey: set[str],
                spindle: bool = False) -> None:
    """Nominal line (grey) through ``point`` along ``direction``; the line a positive ``shift`` puts in its place
    (dashed) and the one a positive ``shift`` and ``tilt`` put there (solid), as the chain displaces ``body``;
    projected on the frame axes ``h`` (across) and ``v`` (up).  A spindle is drawn from ``point`` to the tool tip."""
    t = np.array([0.0, length]) if spindle else np.array([-length, length])
    nominal = point + t[:, None] * direction
    body_ = chain.bodies[body]

    def moved(dev: dict[str, float]) -> np.ndarray:
        return body_.displace(nominal[None], {k: np.array([x]) for k, x in dev.items()})[0]

    dev_shift = {shift.name: SHIFT * length} if shift is not None else {}
    dev_tilt = {tilt.name: np.deg2rad(TILT_DEG)} if tilt is not None else {}
    shifted, both = moved(dev_shift), moved(dev_shift | dev_tilt)
    style = "-" if spindle else "-."
    ax.plot(nominal[:, h], nominal[:, v], color="0.6", lw=2.2, ls=style)
    ax.plot(point[h], point[v], "o", color="0.6", ms=5)
    if spindle:
        ax.plot(nominal[-1, h], nominal[-1, v], "o", color="0.6", ms=8)
    if tilt is not None and shift is not None:
        ax.plot(shifted[:, h], shifted[:, v], color=colour, lw=1.0, ls="--")
    ax.plot(both[:, h], both[:, v], color=colour, lw=2.2, ls=style)
    if spindle:
        ax.plot(both[-1, h], both[-1, v], "o", color=colour, ms=8)
    if shift is not None:
        c = LEFT_OUT if shift.name in grey else colour
        # the arrow where the tilt has not moved the line (at point_mm), a little below it along the line
        a0 = nominal[0] if spindle else point
        a1 = shifted[0] if spindle else point + (shifted[0] - nominal[0])
        if shift.component == v:  # along the line (the spindle's offset along its own axis): beside it
            side = 0.18 * length * _unit(h)
            a0, a1 = a0 + side, a1 + side
            ax.plot(*np.c_[nominal[0] + side * 0.3, a0 + side * 0.3][[h, v]], color="0.6", lw=0.8)
            ax.plot(*np.c_[shifted[0] + side * 0.3, a1 + side * 0.3][[h, v]], color=c, lw=0.8)
        ax.annotate("", xy=(a1[h], a1[v]), xytext=(a0[h], a0[v]),
                    arrowprops=dict(arrowstyle="-|>", color=c, lw=1.5, shrinkA=0, shrinkB=0,
                                    mutation_scale=12))
        if shift.component == v:
            ax.text(a1[h] + 0.05 * length, 0.5 * (a0[v] + a1[v]), _label(shift), fontsize=9, color=c, ha="left",
                    va="center")
        else:  # beside the arrow's tail, away from the lines
            right = a1[h] < a0[h]
            ax.text(a0[h] + (0.07 if right else -0.07) * length, a0[v], _label(shift), fontsize=9, color=c,
                    ha="left" if right else "right", va="center")
    if tilt is not None:
        c = LEFT_OUT if tilt.name in grey else colour
        end_s, end_b = shifted[-1], both[-1]
        ccw = _turns_ccw(tilt, h, v) == (direction[v] > 0)
        ax.annotate("", xy=(end_b[h], end_b[v]), xytext=(end_s[h], end_s[v]),
                    arrowprops=dict(arrowstyle="-|>", color=c, lw=1.3, mutation_scale=12, shrinkA=0, shrinkB=2,
                                    connectionstyle=f"arc3,rad={0.3 if ccw else -0.3}"))
        right = end_b[h] >= end_s[h]
        ax.text(end_b[h] + (0.06 if right else -0.06) * length, end_b[v], _label(tilt), fontsize=9, color=c,
                ha="left" if right else "right", va="center")


def _turns_ccw(d: Deviation, h: int, v: int) -> bool:
    """Whether a positive rotation ``d`` (about a frame axis) turns counter-clockwise in the panel (h across, v up)."""
    n, _ = _basis(h, v)
    return bool(n[d.component] > 0)


def _zero_panel(ax, point: np.ndarray, direction: np.ndarray, zero: Deviation, *, colour: str, radius: float,
                grey: set[str]) -> tuple[int, int]:
    """The view along the axis (its frame axis toward the viewer): a reference mark at 0 and where a positive zero
    error turns it."""
    k = int(np.argmax(np.abs(direction)))
    h, v = (k + 1) % 3, (k + 2) % 3  # h × v = +e_k
    c = LEFT_OUT if zero.name in grey else colour
    t = np.linspace(0, 2 * np.pi, 100)
    ax.plot(point[h] + radius * np.cos(t), point[v] + radius * np.sin(t), color="0.6", lw=1.2)
    ax.plot(point[h], point[v], "o", color="0.6", ms=5)
    ang = np.deg2rad(ZERO_DEG)  # a positive turn about +e_k: counter-clockwise here
    ax.plot([point[h], point[h] + radius], [point[v], point[v]], color="0.6", lw=2.2)
    ax.plot([point[h], point[h] + radius * np.cos(ang)], [point[v], point[v] + radius * np.sin(ang)], color=c,
            lw=2.2)
    r = 0.7 * radius
    ax.annotate("", xy=(point[h] + r * np.cos(ang), point[v] + r * np.sin(ang)), xytext=(point[h] + r, point[v]),
                arrowprops=dict(arrowstyle="-|>", color=c, lw=1.3, mutation_scale=12,
                                connectionstyle="arc3,rad=0.2"))
    ax.text(point[h] + 1.06 * radius * np.cos(ang), point[v] + 1.06 * radius * np.sin(ang), _label(zero),
            fontsize=9, color=c, ha="left", va="bottom")
    return h, v


def _not_estimated(desc: MachineDescription) -> dict[str, str]:
    """The generated errors a campaign does not estimate by default (drawn grey), with why."""
    why = redundant(desc)
    chosen = {d.name for d in selected(desc)}
    out = {}
    for d in generated(desc):
        if d.name in why and d.name not in chosen:
            out[d.name] = why[d.name]
        elif d.name not in chosen:
            out[d.name] = f"not among {provided(desc, 'selection_source', 'the [machine] deviations')}"
    return out


def deviations_figure(desc: MachineDescription) -> Figure:
    """One row per rotary axis, one for the spindle on a rotary axis, one for the squareness of the linear axes;
    the errors drawn with positive values, exaggerated, as the chain displaces the body."""
    gen = generated(desc)
    left_out = _not_estimated(desc)
    grey = set(left_out)
    chain = Chain(desc, gen)
    by_body: dict[str, list[Deviation]] = {}
    for d in gen:
        by_body.setdefault(d.body, []).append(d)
    rows: list[tuple[str, object]] = [("axis", a) for a in desc.rotary_axes]
    if SPINDLE in by_body:
        rows.append(("spindle", desc.spindle))
    rows.append(("squareness", None))
    length = 100.0
    fig = figure(figsize=(10.0, 3.1 * len(rows) + 1.2))
    axes = fig.subplots(len(rows), 3, squeeze=False)

    def pick(errs, role, component):
        return next(d for d in errs if d.role == role and d.component == component)

    for r, (kind, item) in enumerate(rows):
        row = axes[r]
        if kind == "axis" and item.inclined:
            _basis_row(row, f"{_prime(item.letter, item.work_side)} axis (inclined)", direction=item.direction,
                       point=item.point, basis=item.basis, errs=by_body[item.letter], grey=grey)
        elif kind == "spindle" and spindle_own_basis(desc):
            _basis_row(row, f"spindle, relative to the {desc.spindle.carrier} axis", direction=desc.spindle.direction,
                       point=desc.spindle.point, basis=spindle_basis(desc), errs=by_body[SPINDLE], grey=grey)
        elif kind == "axis":
            a = item
            colour = WORK if a.work_side else TOOL
            errs, k = by_body[a.letter], a.frame_axis
            for col, i in enumerate(((k + 1) % 3, (k + 2) % 3)):
                _line_panel(row[col], chain, a.letter, point=a.point, direction=a.direction, length=length, h=i,
                            v=k, shift=pick(errs, "position", i), tilt=pick(errs, "orientation", 3 - k - i),
                            colour=colour, grey=grey)
                _panel_frame(row[col], i, k, extent=1.5 * length, centre=a.point)
            h, v = _zero_panel(row[2], a.point, a.direction, pick(errs, "orientation", k), colour=colour,
                               radius=length, grey=grey)
            _panel_frame(row[2], h, v, extent=1.5 * length, centre=a.point)
            name = _prime(a.letter, a.work_side)
            row[0].set_title(f"{name} axis, {_direction_text(a.direction)} through {_point_text(a.point)}: "
                             "position and orientation", fontsize=10, loc="left", color=colour)
            row[2].set_title(f"{name}: zero position (view along +{FRAME[k]})", fontsize=10, loc="left",
                             color=colour)
        elif kind == "spindle":
            s = item
            errs, k = by_body[SPINDLE], s.frame_axis
            centre = s.point + 0.5 * length * s.direction
            for col, i in enumerate(((k + 1) % 3, (k + 2) % 3)):
                _line_panel(row[col], chain, SPINDLE, point=s.point, direction=s.direction, length=length, h=i,
                            v=k, shift=pick(errs, "position", i), tilt=pick(errs, "orientation", 3 - k - i),
                            colour=SPINDLE_COLOUR, grey=grey, spindle=True)
                _panel_frame(row[col], i, k, extent=1.5 * length, centre=centre)
            i = (k + 1) % 3
            _line_panel(row[2], chain, SPINDLE, point=s.point, direction=s.direction, length=length, h=i, v=k,
                        shift=pick(errs, "position", k), tilt=None, colour=SPINDLE_COLOUR, grey=grey, spindle=True)
            _panel_frame(row[2], i, k, extent=1.5 * length, centre=centre)
            row[0].set_title(f"spindle, {_direction_text(s.direction)} from {_point_text(s.point)}, relative to "
                             f"the {desc.spindle.carrier} axis: position and orientation", fontsize=10, loc="left")
            row[2].set_title(f"spindle: offset along +{FRAME[k]} (its own axis)", fontsize=10, loc="left")
        else:
            _squareness_row(row, gen, grey, form=desc.squareness, length=length)
    fig.suptitle(f"{desc.name or desc.builtin or 'machine'}:  {desc.configuration}\nwhat each location error "
                 "means (positive values, exaggerated)", fontsize=12, fontweight="bold")
    notes = ["grey: nominal; colour: with the error, as the chain displaces the body the axis carries (dashed: the "
             "position error alone); orientation errors turn about point_mm.",
             "⊙ / ⊗: the frame axis out of the page points toward / away from you; a positive angle turns "
             "right-handed about the frame axis in its symbol (E_A..: X, E_B..: Y, E_C..: Z).",
             "Squareness: " + ("rigid form (the thesis' M_XY, M_YZ): the body the linear axis carries turns, its "
                               "direction of motion with it." if desc.squareness == "rigid" else
                               "motion form (ISO 230-1): the axis' direction of motion tilts; what it carries keeps "
                               "its orientation.")]
    greyed = [d for d in gen if d.name in grey]
    if greyed:
        notes.append("Grey symbols: not estimated by default —")
        by_reason: dict[str, list[str]] = {}
        for d in greyed:
            by_reason.setdefault(left_out[d.name], []).append(d.symbol)
        notes += [f"    {', '.join(syms)}: {reason}" for reason, syms in by_reason.items()]
    width = int(fig.get_figwidth() * NOTE_CHARS_PER_IN)
    notes = [part for line in notes
             for part in textwrap.wrap(line, width, subsequent_indent=" " * (len(line) - len(line.lstrip()) + 4))]
    fig.text(0.012, 0.006, "\n".join(notes), fontsize=8, color="0.25", va="bottom", linespacing=1.35)
    bottom = (0.155 * len(notes) + 0.2) / fig.get_figheight()  # 8 pt lines, 1.35 apart, in inches
    tight_layout(fig, (0.0, bottom, 1.0, 1.0 - 0.55 / fig.get_figheight()), h_pad=2.0)
    return fig


def _basis_row(row, title: str, *, direction: np.ndarray, point: np.ndarray, basis, errs: list[Deviation],
               grey: set[str]) -> None:
    """An element named in its own basis (SPEC §21): its line, its basis u, v and its errors in words; the drawing in
    its basis is not made yet, so the row says so rather than draw it in frame axes it does not lie along."""
    u, v = basis
    shown = (lambda x: "[" + ", ".join(f"{float(c):.4g}" for c in np.asarray(x) + 0.0) + "]")  # noqa: E731
    lines = [f"{title}: line along {shown(direction)} through {shown(point)} mm", f"its basis: u = {shown(u)}, "
             f"v = {shown(v)}", ""] + [f"{d.symbol}: {d.meaning}" + ("  (not estimated by default)" if d.name in grey
                                                                       else "") for d in errs]
    lines += ["", "(drawn in words: the drawing of an inclined axis' errors in its basis is not made yet)"]
    for ax in row:
        ax.set_axis_off()
    words = row[0].text(0.0, 1.0, "\n".join(lines), transform=row[0].transAxes, fontsize=9, va="top", ha="left")
    words.set_in_layout(False)  # it runs across the row's empty panels: the layout must not shrink them to fit it


def _squareness_row(row, gen: list[Deviation], grey: set[str], *, form: str, length: float) -> None:
    by_symbol = {d.symbol: d for d in gen}
    for col, (sym, (about, tilted, ref)) in enumerate(SQUARENESS_ERRORS.items()):
        ax = row[col]
        d = by_symbol[sym]
        h, v = FRAME.index(tilted), FRAME.index(ref)
        e_t, e_r = _unit(h), _unit(v)
        turned = rotation(np.deg2rad(TILT_DEG) * _unit(about))[0] @ e_t
        c = LEFT_OUT if d.name in grey else TOOL
        for vec, colour, text in ((e_r, "0.35", ref), (e_t, "0.6", tilted), (turned, c, "")):
            ax.annotate("", xy=(length * vec[h], length * vec[v]), xytext=(0, 0),
                        arrowprops=dict(arrowstyle="-|>", color=colour, lw=2.0, shrinkA=0, shrinkB=0,
                                        mutation_scale=14))
            if text:
                ax.text(length * vec[h] + (0.06 * length if vec[h] > 0.5 else 0.0),
                        length * vec[v] + (0.06 * length if vec[v] > 0.5 else 0.0), text, color=colour,
                        fontsize=10, ha="left" if vec[h] > 0.5 else "center", va="bottom" if vec[v] > 0.5 else
                        "center")
        r = 0.8 * length
        ax.annotate("", xy=(r * turned[h], r * turned[v]), xytext=(r, 0.0),
                    arrowprops=dict(arrowstyle="-|>", color=c, lw=1.2, mutation_scale=11,
                                    connectionstyle=f"arc3,rad={0.3 if turned[v] > 0 else -0.3}"))
        ax.text(1.06 * length * turned[h], 1.06 * length * turned[v] + (0.1 if turned[v] > 0 else -0.1) * length,
                _label(d), fontsize=9, color=c, ha="left", va="bottom" if turned[v] > 0 else "top")
        ax.set_xlim(-0.3 * length, 1.9 * length)
        ax.set_ylim(-0.55 * length, 1.35 * length)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        _axis_labels(ax, h, v)
        ax.set_title(f"squareness of {tilted} to {ref} ({form} form)", fontsize=10, loc="left")


def draw_chain(desc: MachineDescription, path) -> Path:
    """Write :func:`chain_figure` of ``desc`` as a PNG at ``path``."""
    save_png(chain_figure(desc), path)
    return Path(path)


def draw_deviations(desc: MachineDescription, path) -> Path:
    """Write :func:`deviations_figure` of ``desc`` as a PNG at ``path``."""
    save_png(deviations_figure(desc), path)
    return Path(path)
